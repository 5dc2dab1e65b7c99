// Where the `cairn` binary writes (docs/conventions.md, "Outputs"): standard output, symlinks,
// FIFOs, devices, full devices, output directories, and interrupted runs (SIGINT, SIGTERM, and a
// second signal), each checked on the real binary in a child process.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "test_data.hpp"

namespace {

namespace fs = std::filesystem;

const std::string kSquare = std::string(CAIRN_SOURCE_DIR) + "/examples/square_loop.g2o";

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

class OutputsCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("cairn_outputs_cli_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path path(const std::string& name) const { return dir_ / name; }
  std::vector<std::string> entries(const fs::path& d) const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(d)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  std::vector<std::string> entries() const { return entries(dir_); }
  fs::path dir_;
};

/// A running `cairn` with its own pid (no shell in between), so signals reach it.
struct Child {
  pid_t pid = -1;
  int stdin_fd = -1;   // write end, when requested
  int stderr_fd = -1;  // read end, when requested
  fs::path stdout_file;
  fs::path stderr_file;  // when stderr is not piped
};

Child spawn(const std::vector<std::string>& args, const fs::path& stdout_file, bool pipe_stdin, bool pipe_stderr,
            const fs::path& stderr_file) {
  int in[2] = {-1, -1};
  int err[2] = {-1, -1};
  if (pipe_stdin && ::pipe(in) != 0) return {};
  if (pipe_stderr && ::pipe(err) != 0) return {};
  Child c;
  c.stdout_file = stdout_file;
  c.stderr_file = stderr_file;
  c.pid = ::fork();
  if (c.pid == 0) {
    if (pipe_stdin) {
      ::dup2(in[0], 0);
      ::close(in[0]);
      ::close(in[1]);
    }
    if (pipe_stderr) {
      ::dup2(err[1], 2);
      ::close(err[0]);
      ::close(err[1]);
    } else {
      const int e = ::open(stderr_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(e, 2);
    }
    const int o = ::open(stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    ::dup2(o, 1);
    std::vector<char*> argv;
    std::string binary = CAIRN_BINARY;
    argv.push_back(binary.data());
    std::vector<std::string> copy = args;
    for (auto& a : copy) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(binary.c_str(), argv.data());
    ::_exit(127);
  }
  if (pipe_stdin) {
    ::close(in[0]);
    c.stdin_fd = in[1];
  }
  if (pipe_stderr) {
    ::close(err[1]);
    c.stderr_fd = err[0];
  }
  return c;
}

/// Reads the child's stderr until `needle` appears (true), it closes, or `timeout` passes.
bool wait_for(const Child& c, const std::string& needle, std::string* seen, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  char buffer[4096];
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{c.stderr_fd, POLLIN, 0};
    if (::poll(&p, 1, 200) <= 0) continue;
    const ssize_t n = ::read(c.stderr_fd, buffer, sizeof buffer);
    if (n <= 0) return false;
    seen->append(buffer, static_cast<std::size_t>(n));
    if (seen->find(needle) != std::string::npos) return true;
  }
  return false;
}

/// Waits until the process has its SIGINT handler installed (bit 2 of SigCgt in
/// /proc/PID/status), so a signal sent next is caught rather than fatal.
bool wait_until_catching_sigint(pid_t pid) {
  for (int i = 0; i < 2000; ++i) {
    std::ifstream status("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(status, line)) {
      if (line.rfind("SigCgt:", 0) != 0) continue;
      const unsigned long long mask = std::stoull(line.substr(7), nullptr, 16);
      if (mask & (1ULL << (SIGINT - 1))) return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

struct Ended {
  int exit_code = -1;  // -1 when ended by a signal
  int signal = 0;
};

Ended wait_end(const Child& c, std::string* rest_of_stderr) {
  if (c.stderr_fd >= 0) {
    char buffer[4096];
    ssize_t n = 0;
    while ((n = ::read(c.stderr_fd, buffer, sizeof buffer)) > 0) rest_of_stderr->append(buffer, static_cast<std::size_t>(n));
    ::close(c.stderr_fd);
  }
  int status = 0;
  ::waitpid(c.pid, &status, 0);
  Ended e;
  if (WIFEXITED(status)) e.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) e.signal = WTERMSIG(status);
  return e;
}

/// Runs `args` with stderr piped, waits (up to 300 s) for `marker` on it, sends `signal` and waits
/// for the end. False, after killing the run, when the marker never came.
bool interrupt_when(const std::vector<std::string>& args, const fs::path& stdout_file, const std::string& marker,
                    int signal, Ended* ended, std::string* err) {
  const Child c = spawn(args, stdout_file, false, true, {});
  if (!wait_for(c, marker, err, std::chrono::seconds(300))) {
    ::kill(c.pid, SIGKILL);
    wait_end(c, err);
    return false;
  }
  ::kill(c.pid, signal);
  *ended = wait_end(c, err);
  return true;
}

struct Result {
  int status = -1;
  std::string out;
  std::string err;
};

/// Runs the binary to the end with `args`; stdout and stderr captured separately.
Result run(const fs::path& scratch, const std::vector<std::string>& args) {
  const Child c = spawn(args, scratch / "run.stdout", false, false, scratch / "run.stderr");
  std::string ignored;
  const Ended e = wait_end(c, &ignored);
  return {e.exit_code, slurp(scratch / "run.stdout"), slurp(scratch / "run.stderr")};
}

TEST_F(OutputsCli, DashAndDevStdoutCarryOnlyTheData) {
  struct stat before {};
  const bool have_dev_stdout = ::lstat("/dev/stdout", &before) == 0;
  for (const std::string target : {"-", "/dev/stdout"}) {
    if (target != "-" && !have_dev_stdout) continue;
    const Result r = run(dir_, {"optimize", kSquare, "-o", target});
    ASSERT_EQ(r.status, 0) << target << ": " << r.err;
    EXPECT_EQ(r.out.rfind("VERTEX_SE2 0 ", 0), 0u) << target << ": stdout must start with the graph:\n" << r.out;
    EXPECT_EQ(r.out.find("wrote"), std::string::npos) << target;
    EXPECT_EQ(r.out.find("iter"), std::string::npos) << target << ": progress must go to stderr";
    EXPECT_NE(r.err.find("wrote "), std::string::npos) << target << ": " << r.err;
    // What came out is a graph cairn reads back.
    std::ofstream(path("from_stdout.g2o")) << r.out;
    const Result info = run(dir_, {"info", path("from_stdout.g2o").string(), "--json", "-"});
    ASSERT_EQ(info.status, 0) << info.err;
    EXPECT_EQ(nlohmann::json::parse(info.out)["poses"], 11);  // examples/square_loop.g2o
  }
  if (have_dev_stdout) {
    struct stat after {};
    ASSERT_EQ(::lstat("/dev/stdout", &after), 0);
    EXPECT_TRUE(S_ISLNK(after.st_mode)) << "/dev/stdout was replaced";
  }
  // The report to standard output as well: the JSON alone.
  const Result report = run(dir_, {"optimize", kSquare, "-o", path("g.g2o").string(), "--report", "-", "-q"});
  ASSERT_EQ(report.status, 0) << report.err;
  EXPECT_EQ(nlohmann::json::parse(report.out)["interrupted"], false);
}

TEST_F(OutputsCli, DashReadsStandardInput) {
  const Child c = spawn({"optimize", "-", "-o", path("out.g2o").string(), "-q"}, path("stdout"), true, false,
                        path("stderr"));
  const std::string graph = slurp(kSquare);
  ASSERT_EQ(::write(c.stdin_fd, graph.data(), graph.size()), static_cast<ssize_t>(graph.size()));
  ::close(c.stdin_fd);
  std::string ignored;
  const Ended e = wait_end(c, &ignored);
  EXPECT_EQ(e.exit_code, 0) << slurp(path("stderr"));
  EXPECT_EQ(slurp(path("out.g2o")).rfind("VERTEX_SE2 0 ", 0), 0u);
  // convert to standard output needs the format named.
  const Result no_format = run(dir_, {"convert", kSquare, "-"});
  EXPECT_EQ(no_format.status, 1);
  EXPECT_NE(no_format.err.find("--to"), std::string::npos) << no_format.err;
  const Result toro = run(dir_, {"convert", kSquare, "-", "--to", "toro"});
  ASSERT_EQ(toro.status, 0) << toro.err;
  EXPECT_EQ(toro.out.rfind("VERTEX2 0 ", 0), 0u) << toro.out;
}

TEST_F(OutputsCli, SymlinkIsWrittenThroughFifoAndDeviceInPlace) {
  std::ofstream(path("real.g2o")) << "old\n";
  fs::create_symlink("real.g2o", path("link.g2o"));
  Result r = run(dir_, {"optimize", kSquare, "-o", path("link.g2o").string(), "-q"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::is_symlink(path("link.g2o")));
  EXPECT_EQ(slurp(path("real.g2o")).rfind("VERTEX_SE2 0 ", 0), 0u);

  ASSERT_EQ(::mkfifo(path("pipe.g2o").c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(path("pipe.g2o")); });
  r = run(dir_, {"optimize", kSquare, "-o", path("pipe.g2o").string(), "-q"});
  reader.join();
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(received.rfind("VERTEX_SE2 0 ", 0), 0u) << received;
  struct stat st {};
  ASSERT_EQ(::lstat(path("pipe.g2o").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));

  r = run(dir_, {"optimize", kSquare, "-o", "/dev/null", "-q"});
  EXPECT_EQ(r.status, 0) << r.err;
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_EQ(entries(), (std::vector<std::string>{"link.g2o", "pipe.g2o", "real.g2o", "run.stderr", "run.stdout"}));
}

TEST_F(OutputsCli, FullDeviceAndFileSizeLimitAreErrorsWithoutWrote) {
  struct stat st {};
  if (::stat("/dev/full", &st) == 0) {
    const Result r = run(dir_, {"optimize", kSquare, "-o", "/dev/full"});
    EXPECT_EQ(r.status, 1);
    EXPECT_NE(r.err.find("/dev/full"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(std::strerror(ENOSPC)), std::string::npos) << r.err;
    EXPECT_EQ(r.out.find("wrote"), std::string::npos) << r.out;
    ASSERT_EQ(::lstat("/dev/full", &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
  }
  // A regular file that cannot grow (ulimit -f: EFBIG on the write, as ENOSPC would be): exit 1,
  // the old file intact, no temporary beside it. The limit is set in a shell around the binary.
  CAIRN_REQUIRE_DATA("posegraph/se-sync/intel.g2o");
  std::ofstream(path("kept.g2o")) << "precious\n";
  const std::string command = "ulimit -f 64; exec '" + std::string(CAIRN_BINARY) + "' optimize '" +
                              cairn::test::data_path("posegraph/se-sync/intel.g2o").string() + "' -o '" +
                              path("kept.g2o").string() + "' > '" + path("o.txt").string() + "' 2> '" +
                              path("e.txt").string() + "'";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1) << slurp(path("e.txt"));
  EXPECT_NE(slurp(path("e.txt")).find("kept.g2o: cannot write: " + std::string(std::strerror(EFBIG))), std::string::npos)
      << slurp(path("e.txt"));
  EXPECT_EQ(slurp(path("o.txt")).find("wrote"), std::string::npos);
  EXPECT_EQ(slurp(path("kept.g2o")), "precious\n");
  EXPECT_EQ(entries(), (std::vector<std::string>{"e.txt", "kept.g2o", "o.txt", "run.stderr", "run.stdout"}));
}

TEST_F(OutputsCli, OutputDirectoryOfAnotherRunIsRefusedAndAFailedRunLeavesNone) {
  const fs::path out = path("sim");
  Result r = run(dir_, {"simulate", "office", "--seed", "1", "--out", out.string(), "-q", "--set", "trajectory.laps=1"});
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_TRUE(fs::exists(out / "manifest.json"));
  const std::string manifest = slurp(out / "manifest.json");
  r = run(dir_, {"simulate", "office", "--seed", "2", "--out", out.string(), "-q"});
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("--overwrite"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out / "manifest.json"), manifest);
  // A run that fails (a log that is not a log) leaves no output directory and no staging one.
  std::ofstream(path("bad.clf")) << "FLASER 3 1.0 nonsense\n";
  r = run(dir_, {"slam2d", path("bad.clf").string(), "--out", path("slam").string(), "-q"});
  EXPECT_EQ(r.status, 1);
  EXPECT_FALSE(fs::exists(path("slam")));
  for (const auto& name : entries()) EXPECT_EQ(name.find("cairn-partial"), std::string::npos) << name;
  // --overwrite: the files of this run replace those of the same names.
  r = run(dir_, {"slam2d", (out / "log.clf").string(), "--out", out.string(), "-q", "--overwrite", "--max-scans", "50"});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(fs::exists(out / "report.json"));
  EXPECT_EQ(slurp(out / "manifest.json"), manifest);
}

// --certify after a robust solve reports the certificate of least squares over all edges but
// never replaces the robust poses by that problem's optimum (outliers included).
TEST_F(OutputsCli, CertifyAfterGncDoesNotClimbTheStaircase) {
  Result r = run(dir_, {"corrupt", kSquare, "--outliers", "4", "--seed", "2", "-o", path("c.g2o").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir_, {"optimize", path("c.g2o").string(), "--robust", "gnc", "--objective", "chordal", "--certify", "-q",
                 "-o", path("o.g2o").string(), "--report", path("r.json").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("staircase is not climbed"), std::string::npos) << r.err;
  const auto report = nlohmann::json::parse(slurp(path("r.json")));
  EXPECT_EQ(report["staircase"]["levels"].size(), 1u);
}

// --polish-geodesic: g2o's chi2 minimised from the certified chordal optimum, reported apart
// from the certificate, which keeps the chordal point's f.
TEST_F(OutputsCli, GeodesicPolishStartsFromTheCertifiedChordalOptimum) {
  CAIRN_REQUIRE_DATA("posegraph/se-sync/MIT.g2o");
  const std::string graph = cairn::test::data_path("posegraph/se-sync/MIT.g2o").string();
  Result r = run(dir_, {"optimize", graph, "--init", "chordal", "--objective", "chordal", "--certify", "-q", "-o",
                        path("chordal.g2o").string(), "--report", path("chordal.json").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir_, {"optimize", graph, "--init", "chordal", "--objective", "chordal", "--certify", "--polish-geodesic", "-q",
                 "-o", path("polished.g2o").string(), "--report", path("polished.json").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("geodesic polish from the chordal certified optimum"), std::string::npos) << r.out;
  const auto chordal = nlohmann::json::parse(slurp(path("chordal.json")));
  const auto polished = nlohmann::json::parse(slurp(path("polished.json")));
  EXPECT_TRUE(polished["certificate"]["certified"].get<bool>());
  EXPECT_DOUBLE_EQ(polished["certificate"]["f"].get<double>(), chordal["certificate"]["f"].get<double>());
  const auto& polish = polished["geodesic_polish"];
  // It starts where the chordal solve ended, lowers g2o's chi2 and ends converged.
  EXPECT_NEAR(polish["initial_cost"].get<double>(), chordal["final_chi2_geodesic"].get<double>(),
              1e-9 * chordal["final_chi2_geodesic"].get<double>());
  EXPECT_LT(polish["final_cost"].get<double>(), polish["initial_cost"].get<double>());
  EXPECT_EQ(polish["termination"], "convergence");
  EXPECT_DOUBLE_EQ(polished["final_chi2_geodesic"].get<double>(), polish["final_cost"].get<double>());
  // The chordal f rises at the polished point: the certificate is not about it.
  EXPECT_GT(polished["final_f_chordal"].get<double>(), chordal["final_f_chordal"].get<double>());
  // A geodesic solve has nothing to polish.
  r = run(dir_, {"optimize", graph, "--polish-geodesic", "-q", "-o", path("g.g2o").string()});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("minimised the geodesic objective already"), std::string::npos) << r.err;
}

/// The Intel log: the SLAM run SIGINT stops after its 401st scan.
fs::path intel_log() { return cairn::test::data_path("laser2d/intel/intel.clf.bz2"); }

TEST_F(OutputsCli, SigintMidSlam2dLeavesACompleteResultMarkedInterrupted) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const fs::path out = path("intel");
  const Child c = spawn({"slam2d", intel_log().string(), "--out", out.string(), "--progress"}, path("stdout"), false,
                        true, {});
  std::string err;
  ASSERT_TRUE(wait_for(c, "scan 401 /", &err, std::chrono::seconds(300))) << err;
  ::kill(c.pid, SIGINT);
  const Ended e = wait_end(c, &err);
  EXPECT_EQ(e.exit_code, 130) << err;
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;

  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["interrupted"], true);
  EXPECT_EQ(report["interruption"]["signal"], "SIGINT");
  const std::size_t scans = report["input"]["scans"].get<std::size_t>();
  EXPECT_GE(scans, 401u);
  EXPECT_LT(scans, report["input"]["scans_in_log"].get<std::size_t>());
  // Loadable by cairn itself: the trajectory has one pose per scan, the graph is a graph.
  Result info = run(dir_, {"info", (out / "trajectory.tum").string(), "--json", "-"});
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["poses"].get<std::size_t>(), scans);
  info = run(dir_, {"info", (out / "graph.g2o").string(), "--json", "-"});
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["poses"], report["summary"]["keyframes"]);
  for (const char* name : {"map.png", "map.pgm", "map.yaml", "scans.csv", "corrected.clf"}) {
    EXPECT_GT(fs::file_size(out / name), 0u) << name;
  }
  for (const auto& name : entries()) EXPECT_EQ(name.find("cairn-partial"), std::string::npos) << name;
}

// slam3d and vslam stop at the next scan or frame too, and write what they have, marked.
TEST_F(OutputsCli, SigintMidSlam3dLeavesACompleteResultMarkedInterrupted) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/key_frames");
  const fs::path kitti = cairn::test::data_path("lidar3d/kitti00_keyframes");
  const fs::path out = path("kitti");
  std::string err;
  Ended e;
  ASSERT_TRUE(interrupt_when({"slam3d", (kitti / "key_frames").string(), "--preset", "kitti", "--times",
                              (kitti / "keyframes.txt").string(), "--times-column", "4", "--out", out.string(), "--progress"},
                             path("stdout"), "scan 21 /", SIGINT, &e, &err))
      << err;
  EXPECT_EQ(e.exit_code, 130) << err;
  EXPECT_NE(err.find("interrupted by SIGINT"), std::string::npos) << err;
  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["interrupted"], true);
  const std::size_t scans = report["input"]["scans_processed"].get<std::size_t>();
  EXPECT_GE(scans, 21u);
  EXPECT_LT(scans, report["input"]["scans_listed"].get<std::size_t>());
  const Result info = run(dir_, {"info", (out / "trajectory.tum").string(), "--json", "-"});
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["poses"].get<std::size_t>(), scans);
  for (const auto& name : entries()) EXPECT_EQ(name.find("cairn-partial"), std::string::npos) << name;
}

TEST_F(OutputsCli, SigtermMidVslamExitsWith143AndWritesTheFramesSoFar) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/image_l");
  const fs::path out = path("vslam");
  std::string err;
  Ended e;
  ASSERT_TRUE(interrupt_when({"vslam", cairn::test::data_path("visual/kitti_extract_seq2").string(), "--out", out.string(),
                              "--progress"},
                             path("stdout"), "frame 11 /", SIGTERM, &e, &err))
      << err;
  EXPECT_EQ(e.exit_code, 143) << err;
  const auto report = nlohmann::json::parse(slurp(out / "report.json"));
  EXPECT_EQ(report["summary"]["interrupted"], true);
  const std::size_t frames = report["summary"]["frames"].get<std::size_t>();
  EXPECT_GE(frames, 11u);
  EXPECT_LT(frames, 51u);  // the extract holds 51 frame pairs
}

TEST_F(OutputsCli, SigtermMidSlam2dExitsWith143) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const Child c = spawn({"slam2d", intel_log().string(), "--out", path("intel").string(), "--progress", "-q"},
                        path("stdout"), false, true, {});
  std::string err;
  // --progress prints its lines also with -q; wait for the first.
  ASSERT_TRUE(wait_for(c, "scan 1 /", &err, std::chrono::seconds(300))) << err;
  ::kill(c.pid, SIGTERM);
  const Ended e = wait_end(c, &err);
  EXPECT_EQ(e.exit_code, 143) << err;
  EXPECT_EQ(nlohmann::json::parse(slurp(path("intel") / "report.json"))["interruption"]["signal"], "SIGTERM");
}

// SIGINT while the graph is still being read from standard input: the optimiser stops before its
// first iteration and the start is written as the (interrupted) result.
TEST_F(OutputsCli, SigintDuringOptimizeWritesTheEstimateMarkedInterrupted) {
  const Child c = spawn({"optimize", "-", "-o", path("out.g2o").string(), "--report", path("r.json").string()},
                        path("stdout"), true, true, {});
  const std::string graph = slurp(kSquare);
  const std::size_t half = graph.size() / 2;
  ASSERT_EQ(::write(c.stdin_fd, graph.data(), half), static_cast<ssize_t>(half));
  ASSERT_TRUE(wait_until_catching_sigint(c.pid));
  ::kill(c.pid, SIGINT);
  ASSERT_EQ(::write(c.stdin_fd, graph.data() + half, graph.size() - half), static_cast<ssize_t>(graph.size() - half));
  ::close(c.stdin_fd);
  std::string err;
  const Ended e = wait_end(c, &err);
  EXPECT_EQ(e.exit_code, 130) << err;
  const auto report = nlohmann::json::parse(slurp(path("r.json")));
  EXPECT_EQ(report["interrupted"], true);
  EXPECT_EQ(report["summary"]["termination"], "interrupted");
  EXPECT_EQ(report["summary"]["iterations"], 0);
  const Result info = run(dir_, {"info", path("out.g2o").string(), "--json", "-"});
  ASSERT_EQ(info.status, 0) << info.err;
  EXPECT_EQ(nlohmann::json::parse(info.out)["poses"], 11);  // examples/square_loop.g2o
}

// A second signal ends the process at once, by the signal, and removes the temporaries of the
// outputs not yet in place. Here the graph goes to a FIFO nobody reads (the process waits in
// open()) after the report was written to its temporary file.
TEST_F(OutputsCli, SecondSignalEndsAtOnceLeavingNoTemporary) {
  ASSERT_EQ(::mkfifo(path("nobody.g2o").c_str(), 0600), 0);
  const Child c = spawn({"optimize", kSquare, "-o", path("nobody.g2o").string(), "--report",
                         path("r.json").string(), "-q"},
                        path("stdout"), false, true, {});
  // Wait until the report's temporary exists: the process is then blocked opening the FIFO.
  bool pending = false;
  for (int i = 0; i < 600 && !pending; ++i) {
    for (const auto& name : entries()) pending = pending || name.find(".r.json.cairn-tmp-") == 0;
    if (!pending) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(pending);
  ::kill(c.pid, SIGINT);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  ::kill(c.pid, SIGINT);
  std::string err;
  const Ended e = wait_end(c, &err);
  EXPECT_EQ(e.signal, SIGINT) << "exit " << e.exit_code << ": " << err;
  EXPECT_EQ(entries(), (std::vector<std::string>{"nobody.g2o", "stdout"}));
}

}  // namespace
