// Hostile input over every command (docs/conventions.md, "Hostile input"), on the real binary:
//
//  * every numeric flag of every command, found in the command's own --help (so a flag added
//    later is swept too), given NaN, infinities, a negative number, zero, huge numbers and a
//    word;
//  * every command's main input as a missing path, a directory (or a file where a folder is
//    expected), an empty file, binary bytes, and a copy under a name that is not UTF-8;
//  * every command's output on /dev/full, and over an existing output while the run fails.
//
// Each run must end by itself (no signal, within a time limit) with status 0 (a value the flag
// accepts), 1 or 2; a refused run names what it refused (the flag, or the path); a run that
// fails leaves a pre-existing output byte for byte as it was. NaN, infinities and words are
// always refused (status 2, at parsing, before any work).

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cli_runner.hpp"
#include "test_data.hpp"

namespace {

namespace fs = std::filesystem;

using cairn::test::CliResult;
using cairn::test::slurp;

fs::path scratch() { return cairn::test::scratch_folder("hostile_cli"); }

// Each test process makes its own fixtures (ctest runs the tests as separate processes): they go
// when it ends.
class RemoveScratch : public ::testing::Environment {
 public:
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(scratch(), ignored);
  }
};
[[maybe_unused]] ::testing::Environment* const remove_scratch = ::testing::AddGlobalTestEnvironment(new RemoveScratch);

std::string q(const fs::path& p) { return "'" + p.string() + "'"; }

// Runs `cairn ARGS` with a time limit: `timeout` turns a hang into status 124 (or 137 after
// KILL) and passes a signal death on as 128 + signal, both of which the checks below refuse.
CliResult run(const std::string& args) {
  return cairn::test::run_command("timeout -k 10 120 " + std::string(CAIRN_BINARY), args, scratch() / "stderr.txt");
}

// What every run must satisfy, whatever it was given.
void expect_clean_end(const CliResult& r, const std::string& what) {
  EXPECT_TRUE(r.status == 0 || r.status == 1 || r.status == 2)
      << what << ": status " << r.status << " (124/137: hang; >128: killed by a signal)\n" << r.err;
  if (r.status == 1 || r.status == 2) {
    EXPECT_FALSE(r.err.empty()) << what << ": refused without a message";
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << what << ": an assertion reached by input\n" << r.err;
    EXPECT_EQ(r.err.find("terminate called"), std::string::npos) << what << "\n" << r.err;
    EXPECT_EQ(r.err.find("basic_filebuf"), std::string::npos) << what << ": libstdc++'s text\n" << r.err;
  }
}

// The numeric flags of a command, read from its --help: "  --name INT...", "  -o,--name FLOAT...".
std::vector<std::string> numeric_flags(const std::string& command) {
  const CliResult help = run(command + " --help");
  EXPECT_EQ(help.status, 0) << help.err;
  std::vector<std::string> flags;
  const std::regex option(R"(^\s+(?:-\w,)?(--[\w-]+) (INT|UINT|FLOAT)\b)");
  std::istringstream lines(help.out);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_search(line, m, option)) flags.push_back(m[1]);
  }
  return flags;
}

// One command as a user runs it, on small real or simulated data made once for the suite.
struct Command {
  enum class Output { kFile, kDirectory };
  Command(std::string name_, std::string prefix_, std::string args_, std::string input_, bool input_is_folder_ = false,
          Output output_ = Output::kFile, std::string data_ = "")
      : name(std::move(name_)), prefix(std::move(prefix_)), args(std::move(args_)), input(std::move(input_)),
        input_is_folder(input_is_folder_), output(output_), data(std::move(data_)) {}
  std::string name;    // test name
  std::string prefix;  // the command words ("eval ape")
  std::string args;    // with {in} (the main input) and {out} (the output) to fill in
  std::string input;   // a good main input
  bool input_is_folder = false;
  Output output = Output::kFile;
  std::string data;    // needs this under the data root ("" = none)
};

// gtest prints a parameter by this, not as a dump of its bytes.
void PrintTo(const Command& c, std::ostream* os) { *os << "cairn " << c.prefix; }

// The shared fixtures: small files made once per test process, and the fixtures that cost a run
// of cairn each (a CARMEN log with its map, a simulated landmark run) made only by the tests
// that name them (ensure_fixtures), since ctest runs every test in a process of its own.
struct Fixtures {
  fs::path dir;
  bool ready = false;
  bool carmen_ready = false;
  bool landmarks_ready = false;
  bool map3d_ready = false;
  bool visual_map_ready = false;
};

Fixtures& fixtures() {
  static Fixtures f;
  if (f.ready) return f;
  f.dir = scratch() / "fixtures";
  fs::remove_all(f.dir);
  fs::create_directories(f.dir);
  const fs::path& d = f.dir;
  // A 2D pose graph with a loop (6 poses), and two trajectories of one path.
  std::ofstream(d / "graph.g2o") << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 1.5708\nVERTEX_SE2 3 2 1 3.1416\n"
                                    "VERTEX_SE2 4 1 1 3.1416\nVERTEX_SE2 5 0 1 -1.5708\n"
                                    "EDGE_SE2 0 1 1 0 0 100 0 0 100 0 1000\nEDGE_SE2 1 2 1 0 1.5708 100 0 0 100 0 1000\n"
                                    "EDGE_SE2 2 3 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 3 4 1 0 0 100 0 0 100 0 1000\n"
                                    "EDGE_SE2 4 5 1 0 1.5708 100 0 0 100 0 1000\nEDGE_SE2 5 0 1 0 1.5708 100 0 0 100 0 1000\n";
  {
    std::ofstream gt(d / "gt.tum"), est(d / "est.tum");
    // 156 m in 4 s: long enough for the KITTI metric's 100 m segments.
    for (int k = 0; k < 40; ++k) {
      const double t = 0.1 * k;
      gt << 100 + t << ' ' << 40 * t << ' ' << 0.5 * t * t << " 0 0 0 0 1\n";
      est << 100 + t << ' ' << 40 * t + 0.01 * (k % 3) << ' ' << 0.5 * t * t << " 0.02 0 0 0 1\n";
    }
  }
  // Relations between the ground truth's stamps (t_i t_j x y z roll pitch yaw).
  std::ofstream(d / "gt.relations") << "100 100.5 20 0.2 0 0 0 0\n100.5 101 20 0.7 0 0 0 0\n";
  std::ofstream(d / "binary.bin", std::ios::binary) << std::string("\x7f\x45\x4c\x46\x00\x01\xff\xfe\x00\x00\x13\x37", 12);
  std::ofstream(d / "empty.txt");
  fs::create_directories(d / "empty_folder");
  f.ready = true;
  return f;
}

// Makes the costly fixtures `text` (command-line arguments or a path) names.
void ensure_fixtures(const std::string& text) {
  Fixtures& f = fixtures();
  const fs::path& d = f.dir;
  const bool carmen = text.find("log.clf") != std::string::npos || text.find("map.cmap") != std::string::npos;
  if (carmen && !f.carmen_ready && fs::exists(cairn::test::data_path("laser2d/intel/intel.clf.bz2"))) {
    // The first 400 lines (133 scans) of the real Intel log, and a map of them.
    // python3 is one of the packages scripts/install_deps.sh installs; bzip2's tools need not be.
    const std::string cut = "python3 -c 'import bz2, itertools, sys; sys.stdout.buffer.writelines(itertools.islice(bz2.open(sys.argv[1]), 400))' " +
                            q(cairn::test::data_path("laser2d/intel/intel.clf.bz2")) + " > " + q(d / "log.clf");
    EXPECT_EQ(std::system(cut.c_str()), 0);
    const CliResult map = run("slam2d " + q(d / "log.clf") + " --out " + q(d / "map_run") + " --save-map " + q(d / "map.cmap") + " -q");
    EXPECT_EQ(map.status, 0) << map.err;
    f.carmen_ready = true;
  }
  if (text.find("map.c3dm") != std::string::npos && !f.map3d_ready && fs::exists(cairn::test::data_path("lidar3d/kitti00_keyframes/key_frames"))) {
    // A map of the first 3 real KITTI key frames.
    const CliResult map = run("slam3d " + q(cairn::test::data_path("lidar3d/kitti00_keyframes/key_frames")) + " --max-scans 3 --out " +
                              q(d / "map3d_run") + " --save-map " + q(d / "map.c3dm") + " -q");
    EXPECT_EQ(map.status, 0) << map.err;
    f.map3d_ready = true;
  }
  if (text.find("map.cvsm") != std::string::npos && !f.visual_map_ready && fs::exists(cairn::test::data_path("visual/kitti_extract_seq2/calib.txt"))) {
    // A visual map of the first 3 real KITTI stereo frames.
    const CliResult map = run("vslam " + q(cairn::test::data_path("visual/kitti_extract_seq2")) + " --max-frames 3 --out " + q(d / "vslam_map_run") +
                              " --save-map " + q(d / "map.cvsm") + " -q");
    EXPECT_EQ(map.status, 0) << map.err;
    f.visual_map_ready = true;
  }
  if (text.find("landmarks_run") != std::string::npos && !f.landmarks_ready) {
    const CliResult sim = run("simulate landmarks --out " + q(d / "landmarks_run") + " -q");
    EXPECT_EQ(sim.status, 0) << sim.err;
    f.landmarks_ready = true;
  }
}

std::vector<Command> commands() {
  const std::string D = cairn::test::data_root().string();
  const std::string F = (scratch() / "fixtures").string();
  using O = Command::Output;
  return {
      {"info", "info", "{in} --json {out}", F + "/graph.g2o"},
      {"convert", "convert", "{in} {out} --to g2o", F + "/graph.g2o", false, O::kFile},
      {"corrupt", "corrupt", "{in} -o {out} --outliers 3", F + "/graph.g2o"},
      {"optimize", "optimize", "{in} -o {out} -q", F + "/graph.g2o"},
      {"ba", "ba", "{in} -o {out} -q", D + "/bal/dubrovnik-3-7-pre.txt", false, O::kFile,
       "bal/dubrovnik-3-7-pre.txt"},
      {"eval_ape", "eval ape", "{in} " + F + "/est.tum --json {out}", F + "/gt.tum"},
      {"eval_rpe", "eval rpe", "{in} " + F + "/est.tum --json {out}", F + "/gt.tum"},
      {"eval_kitti", "eval kitti", "{in} " + F + "/est.tum --json {out}", F + "/gt.tum"},
      {"eval_relations", "eval relations", "{in} " + F + "/gt.tum --json {out}", F + "/gt.relations"},
      {"slam2d", "slam2d", "{in} --out {out} -q", F + "/log.clf", false, O::kDirectory, "laser2d/intel/intel.clf.bz2"},
      {"localize2d", "localize2d", "{in} --map " + F + "/map.cmap --out {out} -q", F + "/log.clf", false, O::kDirectory,
       "laser2d/intel/intel.clf.bz2"},
      {"slam3d", "slam3d", "{in} --max-scans 2 --out {out} -q", D + "/lidar3d/kitti00_keyframes/key_frames", true, O::kDirectory,
       "lidar3d/kitti00_keyframes/key_frames"},
      {"localize3d", "localize3d", "{in} --map " + F + "/map.c3dm --max-scans 2 --out {out} -q", D + "/lidar3d/kitti00_keyframes/key_frames",
       true, O::kDirectory, "lidar3d/kitti00_keyframes/key_frames"},
      {"vslam", "vslam", "{in} --max-frames 2 --out {out} -q", D + "/visual/kitti_extract_seq2", true, O::kDirectory,
       "visual/kitti_extract_seq2/calib.txt"},
      {"vslam_localize", "vslam", "{in} --localize-in " + F + "/map.cvsm --max-frames 2 --out {out} -q", D + "/visual/kitti_extract_seq2", true,
       O::kDirectory, "visual/kitti_extract_seq2/calib.txt"},
      {"landmarks", "landmarks", "{in} --out {out} -q", F + "/landmarks_run", true, O::kDirectory},
      {"simulate", "simulate", "landmarks --out {out} -q", "", false, O::kDirectory},
      {"register", "register", "{in} " + D + "/lidar3d/kitti00_keyframes/key_frames/key_frame_0.pcd.xz --json {out}",
       D + "/lidar3d/kitti00_keyframes/key_frames/key_frame_0.pcd.xz", false, O::kFile,
       "lidar3d/kitti00_keyframes/key_frames/key_frame_0.pcd.xz"},
      {"navigate", "navigate", "{in} --until 30 --out {out} -q", D + "/bags/robot_localization_test1.bag", false, O::kDirectory,
       "bags/robot_localization_test1.bag"},
      {"imu", "imu", "{in} --no-allan --out {out} -q", D + "/inertial/euroc_v1_01/mav0", true, O::kDirectory,
       "inertial/euroc_v1_01/mav0"},
      {"vocabulary_train", "vocabulary train", "{in} --every 25 --out {out}", D + "/visual/kitti_extract_seq2/image_l", true,
       O::kFile, "visual/kitti_extract_seq2/image_l"},
  };
}

std::string fill(const Command& c, const std::string& in, const std::string& out) {
  std::string args = c.prefix + " " + c.args;
  for (const auto& [key, value] : {std::pair<std::string, std::string>{"{in}", q(in)}, {"{out}", q(out)}}) {
    for (std::size_t at = args.find(key); at != std::string::npos; at = args.find(key)) args.replace(at, key.size(), value);
  }
  return args;
}

class HostileCli : public ::testing::TestWithParam<Command> {
 protected:
  void SetUp() override {
    if (!GetParam().data.empty()) CAIRN_REQUIRE_DATA(GetParam().data);
    ensure_fixtures(GetParam().args + " " + GetParam().input);
    dir_ = scratch() / GetParam().name;
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  // A fresh output path for one run.
  std::string fresh_output() { return (dir_ / ("out_" + std::to_string(++runs_))).string(); }
  CliResult run_with(const std::string& in, const std::string& out, const std::string& extra = "") {
    return run(fill(GetParam(), in, out) + extra);
  }
  fs::path dir_;
  int runs_ = 0;
};

TEST_P(HostileCli, TheFixtureRunSucceeds) {
  const CliResult r = run_with(GetParam().input, fresh_output());
  EXPECT_EQ(r.status, 0) << r.err;
}

TEST_P(HostileCli, EveryNumericFlagRefusesWhatIsNotAFiniteNumberAndSurvivesTheRest) {
  const Command& c = GetParam();
  const std::vector<std::string> flags = numeric_flags(c.prefix);  // info has none
  for (const std::string& flag : flags) {
    // A flag the fixture run sets already (--max-scans 2) would be refused as given twice.
    if (c.args.find(flag + " ") != std::string::npos) continue;
    for (const std::string value : {"nan", "inf", "-inf", "abc", "1e999"}) {
      const CliResult r = run_with(c.input, fresh_output(), " " + flag + " " + value);
      expect_clean_end(r, c.prefix + " " + flag + " " + value);
      EXPECT_EQ(r.status, 2) << c.prefix << " " << flag << " " << value << " must be refused at parsing\n" << r.err;
      EXPECT_NE(r.err.find(flag), std::string::npos) << "the message must name " << flag << "\n" << r.err;
    }
    for (const std::string value : {"-1", "0", "1e308", "99999999999999999999", "-99999999999999999999", "0.5"}) {
      const CliResult r = run_with(c.input, fresh_output(), " " + flag + " " + value);
      expect_clean_end(r, c.prefix + " " + flag + " " + value);
      if (r.status == 2) {
        EXPECT_NE(r.err.find(flag), std::string::npos) << "the message must name " << flag << "\n" << r.err;
      }
      // No bound is printed as a 309-digit number.
      EXPECT_EQ(r.err.find("000000000000000000000000000000"), std::string::npos) << r.err;
    }
  }
}

TEST_P(HostileCli, BadMainInputsGetALocatedErrorAndWriteNothing) {
  const Command& c = GetParam();
  if (c.input.empty()) GTEST_SKIP() << c.prefix << " has no input";
  const Fixtures& f = fixtures();
  std::vector<std::pair<std::string, fs::path>> bad{{"missing", dir_ / "no_such_input"}};
  if (c.input_is_folder) {
    bad.push_back({"a file for a folder", f.dir / "graph.g2o"});
    bad.push_back({"an empty folder", f.dir / "empty_folder"});
  } else {
    bad.push_back({"a directory", f.dir / "empty_folder"});
    bad.push_back({"an empty file", f.dir / "empty.txt"});
    bad.push_back({"binary bytes", f.dir / "binary.bin"});
  }
  for (const auto& [what, path] : bad) {
    const std::string out = fresh_output();
    const CliResult r = run_with(path.string(), out);
    expect_clean_end(r, c.prefix + " on " + what);
    EXPECT_NE(r.status, 0) << c.prefix << " on " << what << " must fail\n" << r.out;
    EXPECT_NE(r.err.find(path.filename().string()), std::string::npos) << c.prefix << " on " << what << ": the message must name the path\n"
                                                                       << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.prefix << " on " << what << " wrote " << out;
  }
}

TEST_P(HostileCli, AnInputNameThatIsNotUtf8IsReadAndItsReportIsValidJson) {
  const Command& c = GetParam();
  if (c.input.empty()) GTEST_SKIP() << c.prefix << " has no input";
  const fs::path latin1 = dir_ / "caf\xe9";  // "cafe" with a Latin-1 e-acute: not UTF-8
  fs::create_symlink(fs::absolute(c.input), latin1);
  const std::string out = fresh_output();
  const CliResult r = run_with(latin1.string(), out);
  expect_clean_end(r, c.prefix + " on a Latin-1 name");
  ASSERT_EQ(r.status, 0) << r.err;
  std::vector<fs::path> reports;
  if (fs::is_directory(out)) {
    for (const auto& e : fs::directory_iterator(out)) {
      if (e.path().extension() == ".json") reports.push_back(e.path());
    }
  } else if (fs::path(out).extension() == ".json" || c.args.find("--json {out}") != std::string::npos) {
    reports.push_back(out);
  }
  for (const fs::path& report : reports) {
    EXPECT_TRUE(nlohmann::json::accept(slurp(report))) << report;
  }
}

TEST_P(HostileCli, AFullDiskIsAnErrorNamingTheOutputAndAFailedRunLeavesTheOldOutputAlone) {
  const Command& c = GetParam();
  if (c.output == Command::Output::kFile) {
    const CliResult full = run_with(c.input, "/dev/full");
    expect_clean_end(full, c.prefix + " to /dev/full");
    EXPECT_EQ(full.status, 1) << full.err;
    EXPECT_NE(full.err.find("/dev/full"), std::string::npos) << full.err;
  }
  if (c.input.empty()) return;
  // An output of an earlier run, then a run that fails: the old output stays byte for byte.
  const fs::path old = dir_ / "earlier";
  if (c.output == Command::Output::kFile) {
    std::ofstream(old) << "an earlier result\n";
  } else {
    fs::create_directories(old);
    std::ofstream(old / "report.json") << "{\"earlier\": true}\n";
  }
  const fs::path bad = c.input_is_folder ? fixtures().dir / "empty_folder" : fixtures().dir / "binary.bin";
  const CliResult r = run_with(bad.string(), old.string(), c.output == Command::Output::kDirectory ? " --overwrite" : "");
  expect_clean_end(r, c.prefix + " failing over an earlier output");
  EXPECT_NE(r.status, 0);
  if (c.output == Command::Output::kFile) {
    EXPECT_EQ(slurp(old), "an earlier result\n");
  } else {
    EXPECT_EQ(slurp(old / "report.json"), "{\"earlier\": true}\n");
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(old)) ++entries;
    EXPECT_EQ(entries, 1u) << "a failed run added files to " << old;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryCommand, HostileCli, ::testing::ValuesIn(commands()),
                         [](const ::testing::TestParamInfo<Command>& param_info) { return param_info.param.name; });

// The cases of the issue that found these holes (#43), each as it was reported.
class HostileCases : public ::testing::Test {
 protected:
  void SetUp() override { fixtures(); }
  fs::path f(const std::string& name) const {
    ensure_fixtures(name);
    return fixtures().dir / name;
  }
};

TEST_F(HostileCases, TwoOutputsThatAreOneFileAreRefusedBeforeAnyWrite) {
  const fs::path out = scratch() / "same.kitti";
  std::ofstream(out) << "earlier\n";
  const CliResult r = run("convert " + q(f("gt.tum")) + " " + q(out) + " --out-times " + q(out));
  EXPECT_EQ(r.status, 1) << r.out;
  EXPECT_NE(r.err.find("name the same file"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), "earlier\n");
  // The same file through a symlink.
  const fs::path link = scratch() / "link.json";
  fs::remove(link);
  fs::create_symlink(out, link);
  const CliResult l = run("optimize " + q(f("graph.g2o")) + " -o " + q(out) + " --report " + q(link));
  EXPECT_EQ(l.status, 1);
  EXPECT_NE(l.err.find("name the same file"), std::string::npos) << l.err;
  EXPECT_EQ(slurp(out), "earlier\n");
}

TEST_F(HostileCases, AFailedSolveNamesTheEdgeAndKeepsTheOldOutput) {
  const fs::path graph = scratch() / "overflow.g2o";
  std::ofstream(graph) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1e308 0 0\nVERTEX_SE2 2 -1e308 0 0\n"
                          "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 1e308 0 0 1 0 0 1 0 1\n";
  const fs::path out = scratch() / "kept.g2o";
  std::ofstream(out) << "earlier\n";
  const CliResult r = run("optimize " + q(graph) + " -o " + q(out) + " -q");
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("overflow.g2o:4: the cost of the edge from pose 0 to pose 1 is not finite"), std::string::npos) << r.err;
  EXPECT_EQ(slurp(out), "earlier\n");
}

TEST_F(HostileCases, CorruptRefusesWhatTheGraphCannotHoldBeforeAllocating) {
  const fs::path two = scratch() / "two.g2o";
  std::ofstream(two) << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nEDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\n";
  const fs::path out = scratch() / "corrupt_out.g2o";
  const CliResult small = run("corrupt " + q(two) + " -o " + q(out) + " --outliers 3");
  EXPECT_EQ(small.status, 1);
  EXPECT_NE(small.err.find("at least 3 poses"), std::string::npos) << small.err;
  // 6 poses: 6 x 5 ordered pairs, 5 consecutive id pairs in both directions: 20.
  const CliResult many = run("corrupt " + q(f("graph.g2o")) + " -o " + q(out) + " --outliers 2000000000");
  EXPECT_EQ(many.status, 1);
  EXPECT_NE(many.err.find("only 20 distinct ordered pairs"), std::string::npos) << many.err;
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(HostileCases, FlagsThatWouldDoNothingAreRefused) {
  const fs::path out = scratch() / "combo.g2o";
  for (const std::string flags : {"--covariance 1", "--robust huber --gnc-threshold 3", "--solver dogleg --exact-steps",
                                  "--robust none --robust-scale 2", "--certify-tolerance 1e-3", "--gauss-newton-hessian"}) {
    const CliResult r = run("optimize " + q(f("graph.g2o")) + " -o " + q(out) + " " + flags);
    EXPECT_EQ(r.status, 2) << flags << "\n" << r.err;
    EXPECT_NE(r.err.find(flags.substr(flags.rfind("--"), flags.find(' ', flags.rfind("--")) - flags.rfind("--"))), std::string::npos)
        << flags << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(HostileCases, ThreadCountsAboveTheMachineAreClamped) {
  CAIRN_REQUIRE_DATA("bal/dubrovnik-3-7-pre.txt");
  const CliResult r = run("ba " + q(cairn::test::data_path("bal/dubrovnik-3-7-pre.txt")) + " --threads 100000 -q --max-iterations 3");
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.err.find("--threads 100000: this machine runs"), std::string::npos) << r.err;
  EXPECT_EQ(r.err.find("TBB Warning"), std::string::npos) << r.err;
}

TEST_F(HostileCases, ALandmarkRunWithoutObservationsIsRefused) {
  const fs::path run_dir = scratch() / "no_observations";
  fs::remove_all(run_dir);
  fs::copy(f("landmarks_run"), run_dir, fs::copy_options::recursive);
  std::ofstream(run_dir / "landmark_observations.csv") << "time_s,landmark_id,range_m,bearing_rad\n";
  const CliResult r = run("landmarks " + q(run_dir) + " --out " + q(scratch() / "no_observations_out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("landmark_observations.csv: holds no observation"), std::string::npos) << r.err;
}

TEST_F(HostileCases, ACalibrationNoCameraHasIsRefused) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const fs::path calib = scratch() / "telephoto.yaml";
  std::ofstream(calib) << "fx: 1e7\nfy: 1e7\ncx: 600\ncy: 180\nbaseline_m: 0.54\n";
  const CliResult r = run("vslam " + q(cairn::test::data_path("visual/kitti_extract_seq2")) + " --calib " + q(calib) +
                          " --max-frames 2 --out " + q(scratch() / "telephoto_out"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("telephoto.yaml: implausible calibration: horizontal field of view 0.00711"), std::string::npos) << r.err;
  std::ofstream(calib) << "fx: 1e300\nfy: 1e300\ncx: 600\ncy: 180\nbaseline_m: 0.54\n";
  const CliResult huge = run("vslam " + q(cairn::test::data_path("visual/kitti_extract_seq2")) + " --calib " + q(calib) +
                             " --max-frames 2 --out " + q(scratch() / "telephoto_out"));
  EXPECT_EQ(huge.status, 1) << huge.err;
  EXPECT_NE(huge.err.find("implausible calibration"), std::string::npos) << huge.err;
  EXPECT_FALSE(fs::exists(scratch() / "telephoto_out"));
}

TEST_F(HostileCases, Slam2dSettingsThatContradictEachOtherAreRefused) {
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  for (const std::string set : {"scan.min_range_m=100", "scan.voxel_size_m=-1", "grid.hit_probability=0.2"}) {
    const CliResult r = run("slam2d " + q(f("log.clf")) + " --out " + q(scratch() / "bad_set") + " --set " + set);
    EXPECT_EQ(r.status, 1) << set;
    EXPECT_NE(r.err.find(set.substr(0, set.find('='))), std::string::npos) << set << "\n" << r.err;
  }
  const CliResult r = run("slam2d " + q(f("log.clf")) + " --out " + q(scratch() / "map_in_out") + " --save-map " +
                          q(scratch() / "map_in_out" / "report.json"));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("which this run writes into --out"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch() / "bad_set"));
}

TEST_F(HostileCases, EveryInputFlagGivenADirectorySaysSo) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/key_frames");
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  CAIRN_REQUIRE_DATA("laser2d/intel/intel.clf.bz2");
  const std::string dir = q(f("empty_folder"));
  const std::string kitti = q(cairn::test::data_path("lidar3d/kitti00_keyframes/key_frames"));
  const std::string stereo = q(cairn::test::data_path("visual/kitti_extract_seq2"));
  const std::string out = q(scratch() / "dir_flag_out");
  for (const std::string& args :
       {"slam2d " + q(f("log.clf")) + " --out " + out + " --config " + dir,
        "slam2d " + q(f("log.clf")) + " --out " + out + " --relations " + dir,
        "localize2d " + q(f("log.clf")) + " --out " + out + " --map " + dir,
        "localize2d " + q(f("log.clf")) + " --out " + out + " --map " + q(f("map.cmap")) + " --config " + dir,
        "localize2d " + q(f("log.clf")) + " --out " + out + " --map " + q(f("map.cmap")) + " --ground-truth " + dir,
        "slam3d " + kitti + " --max-scans 2 --out " + out + " --times " + dir,
        "slam3d " + kitti + " --max-scans 2 --out " + out + " --ground-truth " + dir,
        "vslam " + stereo + " --max-frames 2 --out " + out + " --ground-truth " + dir,
        "vslam " + stereo + " --max-frames 2 --out " + out + " --vocabulary " + dir,
        "vslam " + stereo + " --max-frames 2 --out " + out + " --calib " + dir,
        "eval ape " + dir + " " + q(f("est.tum")), "eval ape " + q(f("gt.tum")) + " " + dir,
        "eval relations " + dir + " " + q(f("gt.tum")), "info " + dir, "optimize " + dir + " -o " + out,
        "ba " + dir, "vocabulary info " + dir}) {
    const CliResult r = run(args);
    expect_clean_end(r, args);
    EXPECT_EQ(r.status, 1) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("empty_folder: is a directory, expected "), std::string::npos) << args << "\n" << r.err;
    EXPECT_FALSE(fs::exists(scratch() / "dir_flag_out")) << args;
  }
}

TEST_F(HostileCases, ATimesFileWhereNoneIsReadIsRefused) {
  const fs::path out = scratch() / "times_out.tum";
  for (const std::string& args :
       {"info " + q(f("graph.g2o")) + " --times " + q(f("gt.tum")), "convert " + q(f("gt.tum")) + " " + q(out) + " --times " + q(f("gt.tum")),
        "convert " + q(f("gt.tum")) + " " + q(out) + " --out-times " + q(scratch() / "times.txt")}) {
    const CliResult r = run(args);
    EXPECT_EQ(r.status, 2) << args << "\n" << r.err;
    EXPECT_NE(r.err.find("times goes with"), std::string::npos) << args << "\n" << r.err;
  }
  EXPECT_FALSE(fs::exists(out));
  EXPECT_FALSE(fs::exists(scratch() / "times.txt"));
}

// Inputs that reached a CAIRN_ASSERT (an abort) before: each is now a located error, status 1.
TEST_F(HostileCases, InputsThatReachedAssertionsAreErrors) {
  const fs::path d = scratch() / "asserts";
  fs::remove_all(d);
  fs::create_directories(d);
  // Poses in UTM-sized coordinates: 6e6 m is 1.2e8 cells of 5 cm.
  {
    std::ofstream log(d / "utm.clf");
    for (int k = 0; k < 3; ++k) {
      log << "FLASER 3 1 1 1 " << 6000000 + 0.1 * k << " 0 0 " << 6000000 + 0.1 * k << " 0 0 " << k << " h " << k << "\n";
    }
  }
  // A chordal system singular in double precision: information 1e20 beside 1e-20.
  std::ofstream(d / "singular.g2o") << "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nVERTEX_SE2 2 2 0 0\n"
                                       "EDGE_SE2 1 2 1 0 0 1e20 0 0 1e20 0 1e20\nEDGE_SE2 0 2 2 0 0 1e-20 0 0 1e-20 0 1e-20\n";
  // A quaternion whose every number is finite and whose norm is not.
  std::ofstream(d / "big_quaternion.g2o") << "VERTEX_SE3:QUAT 0 0 0 0 1e200 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\n"
                                             "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n";
  // Odometry whose motion between two records is infinite.
  fs::create_directories(d / "infinite_odometry");
  std::ofstream(d / "infinite_odometry" / "log.clf") << "ODOM -1e308 0 0 0 0 0 1.0 h 1.0\nODOM 1e308 0 0 0 0 0 2.0 h 2.0\n";
  std::ofstream(d / "infinite_odometry" / "landmark_observations.csv") << "time_s,landmark_id,range_m,bearing_rad\n2.0,0,1.0,0.0\n";
  const std::string out = q(d / "out");  // no run that fails writes it; the one that succeeds writes a file last
  for (const auto& [args, expected] : std::vector<std::pair<std::string, std::string>>{
           {"slam2d " + q(d / "utm.clf") + " --out " + out, "lies more than 1e8 cells"},
           {"slam2d " + q(f("log.clf")) + " --out " + out + " --set grid.resolution_m=1e-9", "grid.resolution_m must be in"},
           {"slam2d " + q(f("log.clf")) + " --out " + out + " --set output.map_resolution_m=1e-9", "output.map_resolution_m must be in"},
           {"optimize " + q(d / "singular.g2o") + " -o " + out + " --init chordal", "not positive definite in double precision"},
           {"info " + q(d / "big_quaternion.g2o"), ""},
           {"landmarks " + q(d / "infinite_odometry") + " --out " + out + " --method graph", "log.clf:2: the motion from the previous ODOM"},
           {"landmarks " + q(d / "infinite_odometry") + " --out " + out, "log.clf:2: the motion from the previous ODOM"},
           {"simulate corridor-aliasing --set corridor.door_width_m=5 --set corridor.door_pitch_m=6 --out " + out,
            "corridor.door_width_m must be at most 3"},
           {"simulate outdoor-stretch --set office.width_m=1e308 --out " + out, ""},
           {"simulate building-yard --set office.room_depth_m=1e308 --out " + out, "office.room_depth_m must be in"},
           {"simulate landmarks --set landmark_field.landmarks=0 --out " + out, "landmark_field.landmarks must be in [1"},
           {"simulate open-hall --set open_hall.route_width_m=1e-10 --set open_hall.route_depth_m=1e-10 --out " + out,
            "open_hall.route_width_m must be in"},
           {"optimize " + q(d / "big_quaternion.g2o") + " -o " + out, ""}}) {
    const CliResult r = run(args);
    expect_clean_end(r, args);
    if (r.status == 0) {
      // Only the quaternion may be read: (1e200, 0, 0, 1) is a rotation, normalised and counted.
      EXPECT_NE(args.find("big_quaternion"), std::string::npos) << args << " succeeded\n" << r.out;
      EXPECT_NE(r.err.find("1 quaternions had a norm differing from 1"), std::string::npos) << args << "\n" << r.err;
    } else {
      EXPECT_NE(r.err.find(expected), std::string::npos) << args << "\n" << r.err;
    }
  }
}

TEST_F(HostileCases, ATruncatedLastLineIsSaidOutLoud) {
  const fs::path cut = scratch() / "cut.tum";
  // Cut inside the last number ("1.5" of a longer file): it still parses, so it must be said.
  std::ofstream(cut) << "1 0 0 0 0 0 0 1\n2 1 0 0 0 0 0 1\n3 2 0 0 0 0 0 1.5";
  const CliResult r = run("info " + q(cut));
  EXPECT_NE(r.err.find("cut.tum:3: the last line does not end with a newline"), std::string::npos) << r.err;
}

}  // namespace
