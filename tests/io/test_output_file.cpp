// io::OutputFile and io::OutputDirectory: regular files replaced atomically, symlinks written
// through, FIFOs and devices written in place, every failure an error with nothing left behind.

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>

#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

namespace fs = std::filesystem;
using cairn::io::OutputDirectory;
using cairn::io::OutputFile;
using cairn::io::ParseError;
using cairn::io::write_output;

class OutputFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("cairn_output_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path path(const std::string& name) const { return dir_ / name; }
  /// Every entry of the scratch directory (temporaries included: they are hidden files).
  std::vector<std::string> entries() const { return entries(dir_); }
  static std::vector<std::string> entries(const fs::path& d) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(d)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  fs::path dir_;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

auto text(const std::string& s) {
  return [s](std::ostream& out) { out << s; };
}

TEST_F(OutputFileTest, NewAndExistingRegularFilesAreReplacedWholeKeepingTheirMode) {
  write_output(path("a.txt").string(), text("first\n"));
  EXPECT_EQ(slurp(path("a.txt")), "first\n");
  ::chmod(path("a.txt").c_str(), 0640);
  write_output(path("a.txt").string(), text("second\n"));
  EXPECT_EQ(slurp(path("a.txt")), "second\n");
  struct stat st {};
  ASSERT_EQ(::stat(path("a.txt").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(entries(), std::vector<std::string>{"a.txt"});  // no temporary left
}

TEST_F(OutputFileTest, LargeContentArrivesComplete) {
  std::string big(3'000'000, 'x');
  for (std::size_t i = 0; i < big.size(); i += 1000) big[i] = '\n';
  write_output(path("big.txt").string(), [&](std::ostream& out) {
    for (std::size_t i = 0; i < big.size(); i += 777) out << big.substr(i, 777);
  });
  EXPECT_EQ(slurp(path("big.txt")), big);
}

TEST_F(OutputFileTest, SymlinksAreWrittenThroughAndStayLinks) {
  put(path("real.txt"), "old\n");
  fs::create_symlink("real.txt", path("link.txt"));     // relative
  fs::create_symlink(path("link.txt"), path("link2.txt"));  // absolute, to a link
  write_output(path("link2.txt").string(), text("new\n"));
  EXPECT_TRUE(fs::is_symlink(path("link.txt")));
  EXPECT_TRUE(fs::is_symlink(path("link2.txt")));
  EXPECT_EQ(slurp(path("real.txt")), "new\n");
  // A dangling link creates its target.
  fs::create_symlink("target.txt", path("dangling.txt"));
  write_output(path("dangling.txt").string(), text("made\n"));
  EXPECT_TRUE(fs::is_symlink(path("dangling.txt")));
  EXPECT_EQ(slurp(path("target.txt")), "made\n");
  EXPECT_EQ(entries(), (std::vector<std::string>{"dangling.txt", "link.txt", "link2.txt", "real.txt", "target.txt"}));
}

TEST_F(OutputFileTest, SymlinkLoopsAndDirectoriesAreErrors) {
  fs::create_symlink("b", path("a"));
  fs::create_symlink("a", path("b"));
  try {
    write_output(path("a").string(), text("x"));
    FAIL() << "a symlink loop was written";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("symbolic links"), std::string::npos) << e.what();
  }
  fs::create_directory(path("d"));
  EXPECT_THROW(write_output(path("d").string(), text("x")), ParseError);
  EXPECT_THROW(write_output(path("missing_dir/x.txt").string(), text("x")), ParseError);
}

TEST_F(OutputFileTest, FifoIsWrittenInPlaceForItsReader) {
  ASSERT_EQ(::mkfifo(path("pipe").c_str(), 0600), 0);
  std::string received;
  std::thread reader([&] { received = slurp(path("pipe")); });
  write_output(path("pipe").string(), text("through the pipe\n"));
  reader.join();
  EXPECT_EQ(received, "through the pipe\n");
  struct stat st {};
  ASSERT_EQ(::lstat(path("pipe").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_EQ(entries(), std::vector<std::string>{"pipe"});
}

TEST_F(OutputFileTest, CharacterDevicesAreWrittenInPlace) {
  write_output("/dev/null", text("discarded\n"));
  struct stat st {};
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  // A private device node (needs root): a link to it is followed and the node stays a node.
  if (::mknod(path("null").c_str(), S_IFCHR | 0666, ::makedev(1, 3)) != 0) {
    GTEST_SKIP() << "mknod needs root (" << std::strerror(errno) << "): private device node not tested";
  }
  fs::create_symlink("null", path("null_link"));
  write_output(path("null_link").string(), text("discarded\n"));
  ASSERT_EQ(::lstat(path("null").c_str(), &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_TRUE(fs::is_symlink(path("null_link")));
  EXPECT_EQ(entries(), (std::vector<std::string>{"null", "null_link"}));
}

TEST_F(OutputFileTest, FullDeviceIsAnErrorNamingThePath) {
  struct stat st {};
  if (::stat("/dev/full", &st) != 0) GTEST_SKIP() << "/dev/full not present";
  try {
    write_output("/dev/full", text("does not fit\n"));
    FAIL() << "writing /dev/full succeeded";
  } catch (const ParseError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/dev/full"), std::string::npos) << what;
    EXPECT_NE(what.find(std::strerror(ENOSPC)), std::string::npos) << what;
  }
  ASSERT_EQ(::lstat("/dev/full", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
}

// A write that fails half-way into a regular file (a file-size limit: EFBIG, the same path as
// ENOSPC or EIO) leaves the old file and no temporary. In a child process, so the limit stays there.
TEST_F(OutputFileTest, FailedWriteLeavesTheOldFileAndNoTemporary) {
  put(path("kept.txt"), "precious\n");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{16384, 16384};
    ::setrlimit(RLIMIT_FSIZE, &limit);
    try {
      write_output(path("kept.txt").string(), [](std::ostream& out) {
        for (int i = 0; i < 100000; ++i) out << "line " << i << '\n';
      });
      ::_exit(2);  // succeeded: wrong
    } catch (const ParseError& e) {
      const std::string what = e.what();
      ::_exit(what.find("kept.txt") != std::string::npos && what.find(std::strerror(EFBIG)) != std::string::npos ? 0 : 3);
    } catch (...) {
      ::_exit(4);
    }
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "2: the write succeeded; 3: the error did not name the path and EFBIG";
  EXPECT_EQ(slurp(path("kept.txt")), "precious\n");
  EXPECT_EQ(entries(), std::vector<std::string>{"kept.txt"});
}

TEST_F(OutputFileTest, AnExceptionWhileProducingWritesNothing) {
  put(path("kept.txt"), "precious\n");
  EXPECT_THROW(write_output(path("kept.txt").string(),
                            [](std::ostream& out) {
                              out << "half";
                              throw std::runtime_error("producer failed");
                            }),
               std::runtime_error);
  EXPECT_EQ(slurp(path("kept.txt")), "precious\n");
  // A pair fails together: the first is written but not committed when the second throws.
  {
    OutputFile first(path("poses.txt").string());
    first.write(text("poses\n"));
    OutputFile second(path("times.txt").string());
    EXPECT_THROW(second.write([](std::ostream&) { throw std::runtime_error("no"); }), std::runtime_error);
  }
  EXPECT_EQ(entries(), std::vector<std::string>{"kept.txt"});
}

TEST_F(OutputFileTest, UnfinishedTemporariesCanBeRemovedFromASignalHandler) {
  OutputFile file(path("x.txt").string());
  file.write(text("pending\n"));
  ASSERT_EQ(entries().size(), 1u);  // the hidden temporary
  EXPECT_EQ(entries()[0].rfind(".x.txt.cairn-tmp-", 0), 0u) << entries()[0];
  cairn::io::remove_unfinished_outputs();
  EXPECT_TRUE(entries().empty());
}

TEST_F(OutputFileTest, StandardOutputIsRecognised) {
  EXPECT_TRUE(cairn::io::is_standard_output("-"));
  EXPECT_TRUE(cairn::io::is_standard_output("/dev/stdout"));
  EXPECT_TRUE(cairn::io::is_standard_output("/dev/fd/1"));
  EXPECT_TRUE(cairn::io::is_standard_output("/proc/self/fd/1"));
  EXPECT_FALSE(cairn::io::is_standard_output("/dev/fd/12"));
  EXPECT_FALSE(cairn::io::is_standard_output("out.g2o"));
  EXPECT_EQ(cairn::io::resolve_output("/dev/stdout").kind, cairn::io::OutputKind::kDirect);
  EXPECT_EQ(cairn::io::resolve_output("/dev/stderr").inherited_fd, 2);
}

TEST_F(OutputFileTest, DashWritesToTheStandardOutputDescriptor) {
  int fds[2];
  ASSERT_EQ(::pipe(fds), 0);
  const int saved = ::dup(1);
  ::dup2(fds[1], 1);
  write_output("-", text("to stdout\n"));
  ::dup2(saved, 1);
  ::close(saved);
  ::close(fds[1]);
  char buffer[64] = {};
  const ssize_t n = ::read(fds[0], buffer, sizeof buffer);
  ::close(fds[0]);
  EXPECT_EQ(std::string(buffer, static_cast<std::size_t>(std::max<ssize_t>(n, 0))), "to stdout\n");
}

// --- OutputDirectory -------------------------------------------------------------------------

TEST_F(OutputFileTest, DirectoryAppearsWholeOnCommitOnly) {
  const fs::path out = path("run");
  {
    OutputDirectory d(out.string(), false);
    write_output(d.staging_path("a.txt"), text("a"));
    fs::create_directory(d.staging_path("sub"));
    write_output(d.staging_path("sub/b.txt"), text("b"));
    EXPECT_FALSE(fs::exists(out));  // nothing at DIR before commit
    d.commit();
  }
  EXPECT_EQ(slurp(out / "a.txt"), "a");
  EXPECT_EQ(slurp(out / "sub" / "b.txt"), "b");
  struct stat st {};
  ASSERT_EQ(::stat(out.c_str(), &st), 0);
  EXPECT_NE(st.st_mode & 0055, 0u) << "the staging directory's 0700 must not stay";
  EXPECT_EQ(entries(), std::vector<std::string>{"run"});
}

TEST_F(OutputFileTest, DirectoryOfARunThatFailsLeavesNothing) {
  {
    OutputDirectory d(path("run").string(), false);
    write_output(d.staging_path("a.txt"), text("a"));
  }  // no commit: the run failed
  EXPECT_TRUE(entries().empty());
}

TEST_F(OutputFileTest, DirectoryHoldingFilesIsRefusedUnlessOverwrite) {
  const fs::path out = path("run");
  fs::create_directory(out);
  put(out / "old.txt", "old");
  put(out / "a.txt", "previous a");
  try {
    OutputDirectory d(out.string(), false);
    FAIL() << "a directory holding files was accepted";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  }
  EXPECT_EQ(entries(), std::vector<std::string>{"run"});  // no staging directory left
  {
    OutputDirectory d(out.string(), true);
    write_output(d.staging_path("a.txt"), text("new a"));
    d.commit();
  }
  EXPECT_EQ(slurp(out / "a.txt"), "new a");
  EXPECT_EQ(slurp(out / "old.txt"), "old");  // other files are left alone
  EXPECT_EQ(entries(), std::vector<std::string>{"run"});
  // An empty existing directory needs no --overwrite.
  fs::create_directory(path("empty"));
  OutputDirectory e(path("empty").string(), false);
  write_output(e.staging_path("c.txt"), text("c"));
  e.commit();
  EXPECT_EQ(slurp(path("empty") / "c.txt"), "c");
}

TEST_F(OutputFileTest, DirectoryBehindASymlinkKeepsTheLink) {
  fs::create_directory(path("run_0420"));
  fs::create_directory_symlink("run_0420", path("latest"));
  {
    OutputDirectory d(path("latest").string(), false);
    write_output(d.staging_path("a.txt"), text("a"));
    d.commit();
  }
  EXPECT_TRUE(fs::is_symlink(path("latest")));
  EXPECT_EQ(slurp(path("run_0420") / "a.txt"), "a");
  EXPECT_EQ(entries(), (std::vector<std::string>{"latest", "run_0420"}));
}

// Files that appear in an (empty) DIR during the run are not overwritten without --overwrite:
// the commit refuses before moving anything. With --overwrite, a symlink in DIR to a device is
// written through (the node stays a node), a replaced file keeps its mode, and the staging
// directory (inside an existing DIR) is gone.
TEST_F(OutputFileTest, DirectoryCommitChecksEveryMoveFirst) {
  fs::create_directory(path("run"));
  {
    OutputDirectory d(path("run").string(), false);
    write_output(d.staging_path("a.txt"), text("ours"));
    write_output(d.staging_path("b.txt"), text("ours"));
    put(path("run") / "b.txt", "another run's");  // appears meanwhile
    EXPECT_THROW(d.commit(), ParseError);
  }
  EXPECT_EQ(entries(path("run")), std::vector<std::string>{"b.txt"});
  EXPECT_EQ(slurp(path("run") / "b.txt"), "another run's");

  fs::create_symlink("/dev/null", path("run") / "null.txt");
  ::chmod((path("run") / "b.txt").c_str(), 0640);
  {
    OutputDirectory d(path("run").string(), true);
    write_output(d.staging_path("null.txt"), text("discarded"));
    write_output(d.staging_path("b.txt"), text("ours"));
    d.commit();
  }
  struct stat st {};
  ASSERT_EQ(::lstat("/dev/null", &st), 0);
  EXPECT_TRUE(S_ISCHR(st.st_mode));
  EXPECT_TRUE(fs::is_symlink(path("run") / "null.txt"));
  EXPECT_EQ(slurp(path("run") / "b.txt"), "ours");
  ASSERT_EQ(::stat((path("run") / "b.txt").c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(entries(path("run")), (std::vector<std::string>{"b.txt", "null.txt"}));
}

TEST_F(OutputFileTest, DirectoryCannotBeStandardOutputOrAFile) {
  EXPECT_THROW(OutputDirectory("-", true), ParseError);
  put(path("file"), "x");
  EXPECT_THROW(OutputDirectory(path("file").string(), true), ParseError);
}

TEST_F(OutputFileTest, UnfinishedDirectoriesCanBeRemovedFromASignalHandler) {
  OutputDirectory d(path("run").string(), false);
  fs::create_directories(fs::path(d.staging()) / "sub" / "deeper");
  put(fs::path(d.staging()) / "sub" / "deeper" / "f.txt", "f");
  put(fs::path(d.staging()) / "g.txt", "g");
  ASSERT_EQ(entries().size(), 1u);
  cairn::io::remove_unfinished_outputs();
  EXPECT_TRUE(entries().empty());
}

}  // namespace
