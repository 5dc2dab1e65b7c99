#include "cairn/io/output_file.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <pthread.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <sstream>
#include <streambuf>
#include <vector>

#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// Registry of unfinished temporaries, readable from a signal handler: fixed slots of fixed-size
// paths; a slot is published (state 2) only after its path is complete.

constexpr int kSlots = 64;
struct Slot {
  std::atomic<int> state{0};  // 0 free, 1 being filled or emptied, 2 published
  bool is_directory = false;
  char path[PATH_MAX] = {};
};
std::array<Slot, kSlots> g_slots;

int g_standard_output = 1;

int register_unfinished(const std::string& path, bool is_directory) {
  if (path.size() + 1 > PATH_MAX) return -1;
  for (int i = 0; i < kSlots; ++i) {
    int expected = 0;
    if (g_slots[static_cast<std::size_t>(i)].state.compare_exchange_strong(expected, 1)) {
      Slot& s = g_slots[static_cast<std::size_t>(i)];
      std::memcpy(s.path, path.c_str(), path.size() + 1);
      s.is_directory = is_directory;
      s.state.store(2, std::memory_order_release);
      return i;
    }
  }
  return -1;  // more than kSlots at once: cleaned up on the normal paths only
}

void unregister_unfinished(int slot) {
  if (slot < 0) return;
  g_slots[static_cast<std::size_t>(slot)].state.store(0, std::memory_order_release);
}

// Removes a directory tree with async-signal-safe calls only (open, getdents64, unlinkat,
// close); true when `name` is gone. Depth-limited: cairn's output directories are at most two
// levels deep. A listing is read again only after a pass that removed something, so an entry
// that cannot be removed ends the loop instead of spinning in the signal handler.
bool remove_tree_signal_safe(int parent_fd, const char* name, int depth) noexcept {
  if (::unlinkat(parent_fd, name, 0) == 0) return true;
  if (depth > 4) return false;
  const int fd = ::openat(parent_fd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0) return false;
  alignas(8) char buffer[4096];
  while (true) {
    const long n = ::syscall(SYS_getdents64, fd, buffer, sizeof buffer);
    if (n <= 0) break;
    bool removed_any = false;
    for (long offset = 0; offset < n;) {
      struct Entry {
        std::uint64_t ino;
        std::int64_t off;
        unsigned short reclen;
        unsigned char type;
        char name[1];
      };
      const auto* e = reinterpret_cast<const Entry*>(buffer + offset);
      offset += e->reclen;
      if (std::strcmp(e->name, ".") == 0 || std::strcmp(e->name, "..") == 0) continue;
      removed_any = remove_tree_signal_safe(fd, e->name, depth + 1) || removed_any;
    }
    if (!removed_any) break;
    ::lseek(fd, 0, SEEK_SET);  // the listing changed under us: read it again
  }
  ::close(fd);
  return ::unlinkat(parent_fd, name, AT_REMOVEDIR) == 0;
}

// ---------------------------------------------------------------------------------------------
// Checked writes.

std::string errno_text(int error) { return std::strerror(error); }

/// Writes all of [data, data + size) to fd; returns 0 or the errno of the failure (a write
/// that makes no progress counts as EIO).
int write_all(int fd, const char* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    if (n == 0) return EIO;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return 0;
}

/// A streambuf onto a file descriptor that remembers the first failed write.
class FdBuffer : public std::streambuf {
 public:
  explicit FdBuffer(int fd) : fd_(fd) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  int error() const { return error_; }
  /// Flushes; returns the first error (0 if none).
  int flush_all() {
    sync();
    return error_;
  }

 protected:
  int_type overflow(int_type ch) override {
    if (sync() != 0) return traits_type::eof();
    if (!traits_type::eq_int_type(ch, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(ch);
      pbump(1);
    }
    return traits_type::not_eof(ch);
  }
  int sync() override {
    if (error_ != 0) return -1;
    const std::size_t n = static_cast<std::size_t>(pptr() - pbase());
    if (n > 0) error_ = write_all(fd_, pbase(), n);
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return error_ == 0 ? 0 : -1;
  }
  std::streamsize xsputn(const char* s, std::streamsize count) override {
    if (error_ != 0) return 0;
    if (count >= static_cast<std::streamsize>(buffer_.size())) {
      if (sync() != 0) return 0;
      error_ = write_all(fd_, s, static_cast<std::size_t>(count));
      return error_ == 0 ? count : 0;
    }
    return std::streambuf::xsputn(s, count);
  }

 private:
  int fd_;
  int error_ = 0;
  std::array<char, 1 << 16> buffer_{};
};

mode_t process_umask() {
  static const mode_t mask = [] {
    const mode_t m = ::umask(0);
    ::umask(m);
    return m;
  }();
  return mask;
}

bool starts_with(const std::string& s, std::string_view prefix) { return s.compare(0, prefix.size(), prefix) == 0; }

/// N of /dev/fd/N or /proc/self/fd/N (or /proc/<our pid>/fd/N); -1 otherwise.
int descriptor_named(const std::string& p) {
  if (p == "/dev/stdout") return 1;
  if (p == "/dev/stderr") return 2;
  std::string_view digits;
  const std::string own = "/proc/" + std::to_string(::getpid()) + "/fd/";
  for (const std::string_view prefix : {std::string_view("/dev/fd/"), std::string_view("/proc/self/fd/"),
                                         std::string_view("/proc/thread-self/fd/"), std::string_view(own)}) {
    if (starts_with(p, prefix)) digits = std::string_view(p).substr(prefix.size());
  }
  if (digits.empty() || digits.size() > 9) return -1;
  int fd = -1;
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), fd);
  if (ec != std::errc() || end != digits.data() + digits.size()) return -1;
  return fd;
}

/// The descriptor to write for such a path: standard output may have moved (set_standard_output).
int inherited_descriptor(const std::string& p) {
  const int fd = descriptor_named(p);
  return fd == 1 ? g_standard_output : fd;
}

std::string parent_of(const std::string& p) {
  const auto slash = p.find_last_of('/');
  if (slash == std::string::npos) return ".";
  if (slash == 0) return "/";
  return p.substr(0, slash);
}

std::string base_of(const std::string& p) {
  const auto slash = p.find_last_of('/');
  return slash == std::string::npos ? p : p.substr(slash + 1);
}

}  // namespace

// -----------------------------------------------------------------------------------------------

void set_standard_output(int fd) { g_standard_output = fd; }

bool is_standard_output(const std::string& path) {
  if (path == "-") return true;
  return descriptor_named(path) == 1;
}

std::string output_display_name(const std::string& path) { return path == "-" ? "standard output" : path; }

OutputTarget resolve_output(const std::string& path) {
  OutputTarget t;
  t.path = path;
  if (path.empty()) throw ParseError("(output)", 0, "cannot write: empty output path");
  if (path == "-") {
    t.kind = OutputKind::kDirect;
    t.resolved = "standard output";
    t.inherited_fd = g_standard_output;
    return t;
  }
  std::string p = path;
  for (int hops = 0;; ++hops) {
    if (hops > 40) throw ParseError(path, 0, "cannot write: too many levels of symbolic links");
    if (const int fd = inherited_descriptor(p); fd >= 0) {
      t.kind = OutputKind::kDirect;
      t.resolved = p;
      t.inherited_fd = fd;
      return t;
    }
    if (starts_with(p, "/proc/")) {  // kernel objects: open, never replace
      t.kind = OutputKind::kDirect;
      t.resolved = p;
      return t;
    }
    struct stat st {};
    if (::lstat(p.c_str(), &st) != 0) {
      if (errno == ENOENT) {  // a new file (a missing directory is reported when it is created)
        t.kind = OutputKind::kReplaceFile;
        t.resolved = p;
        return t;
      }
      throw ParseError(path, 0, "cannot write: " + p + ": " + errno_text(errno));
    }
    if (S_ISLNK(st.st_mode)) {
      std::vector<char> target(static_cast<std::size_t>(st.st_size > 0 ? st.st_size : PATH_MAX) + 1);
      const ssize_t n = ::readlink(p.c_str(), target.data(), target.size());
      if (n < 0) throw ParseError(path, 0, "cannot write: cannot read the link " + p + ": " + errno_text(errno));
      std::string next(target.data(), static_cast<std::size_t>(n));
      if (next.empty()) throw ParseError(path, 0, "cannot write: the link " + p + " is empty");
      p = next.front() == '/' ? next : parent_of(p) + "/" + next;
      continue;
    }
    if (S_ISDIR(st.st_mode)) throw ParseError(path, 0, "cannot write: is a directory (expected a file)");
    t.resolved = p;
    t.kind = S_ISREG(st.st_mode) ? OutputKind::kReplaceFile : OutputKind::kDirect;
    return t;
  }
}

OutputFile::OutputFile(std::string path) : target_(resolve_output(path)) {}

OutputFile::~OutputFile() {
  if (!committed_) discard();
}

void OutputFile::discard() noexcept {
  if (temp_fd_ >= 0) {
    ::close(temp_fd_);
    temp_fd_ = -1;
  }
  if (!temp_path_.empty()) {
    ::unlink(temp_path_.c_str());
    temp_path_.clear();
  }
  unregister_unfinished(registry_slot_);
  registry_slot_ = -1;
  buffer_.clear();
}

void OutputFile::fail(const std::string& why) const {
  throw ParseError(output_display_name(target_.path), 0, "cannot write: " + why);
}

void OutputFile::write(const std::function<void(std::ostream&)>& emit) {
  if (written_) fail("internal error: OutputFile::write called twice");
  written_ = true;
  if (target_.kind == OutputKind::kDirect) {
    std::ostringstream memory;
    emit(memory);
    buffer_ = std::move(memory).str();
    return;
  }
  // Temporary file beside the target (hidden, unique, never an existing file: O_EXCL).
  std::string templ = parent_of(target_.resolved) + "/." + base_of(target_.resolved) + ".cairn-tmp-XXXXXX";
  if (templ.size() + 1 > PATH_MAX) fail("the path is too long");
  std::vector<char> name(templ.begin(), templ.end());
  name.push_back('\0');
  const int fd = ::mkostemp(name.data(), O_CLOEXEC);
  if (fd < 0) fail("cannot create a file in " + parent_of(target_.resolved) + ": " + errno_text(errno));
  temp_fd_ = fd;
  temp_path_ = name.data();
  registry_slot_ = register_unfinished(temp_path_, false);
  // The permissions a new file would get (0666 & ~umask), or those of the file replaced.
  struct stat st {};
  const mode_t mode = ::stat(target_.resolved.c_str(), &st) == 0 ? (st.st_mode & 07777) : (0666 & ~process_umask());
  ::fchmod(fd, mode);  // best effort: a failure leaves 0600, which is safe

  FdBuffer buffer(fd);
  std::ostream out(&buffer);
  try {
    emit(out);
  } catch (...) {
    discard();
    throw;
  }
  out.flush();
  if (const int error = buffer.flush_all(); error != 0) {
    discard();
    fail(errno_text(error));
  }
  if (::fsync(fd) != 0 && errno != EINVAL && errno != EROFS) {
    const int error = errno;
    discard();
    fail("flushing to disk: " + errno_text(error));
  }
  temp_fd_ = -1;
  if (::close(fd) != 0 && errno != EINTR) {
    const int error = errno;
    discard();
    fail("closing: " + errno_text(error));
  }
}

void OutputFile::commit() {
  if (!written_) fail("internal error: OutputFile::commit before write");
  if (committed_) return;
  if (target_.kind == OutputKind::kReplaceFile) {
    if (::rename(temp_path_.c_str(), target_.resolved.c_str()) != 0) {
      const int error = errno;
      discard();
      fail("cannot rename the temporary file over " + target_.resolved + ": " + errno_text(error));
    }
    temp_path_.clear();
    unregister_unfinished(registry_slot_);
    registry_slot_ = -1;
    committed_ = true;
    return;
  }
  int fd = target_.inherited_fd;
  if (fd < 0) {
    // No O_CREAT: the node exists (a device, FIFO or socket). A FIFO blocks here until a reader
    // opens it, as `cat > fifo` does.
    do {
      fd = ::open(target_.resolved.c_str(), O_WRONLY | O_NOCTTY | O_CLOEXEC);
    } while (fd < 0 && errno == EINTR);
    if (fd < 0) fail(errno_text(errno));
  }
  int error = write_all(fd, buffer_.data(), buffer_.size());
  if (target_.inherited_fd < 0) {
    if (::close(fd) != 0 && error == 0 && errno != EINTR) error = errno;
  }
  buffer_.clear();
  if (error != 0) fail(errno_text(error));
  committed_ = true;
}

void write_output(const std::string& path, const std::function<void(std::ostream&)>& emit) {
  OutputFile file(path);
  file.write(emit);
  file.commit();
}

void write_outputs(const std::vector<PlannedOutput>& outputs) {
  std::vector<std::unique_ptr<OutputFile>> files;
  for (const PlannedOutput& o : outputs) {
    if (o.path.empty()) continue;
    files.push_back(std::make_unique<OutputFile>(o.path));
    files.back()->write(o.emit);
  }
  for (auto& file : files) file->commit();
}

void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs) {
  struct Seen {
    const std::string* flag;
    const std::string* path;
    std::string key;
  };
  std::vector<Seen> seen;
  for (const auto& [flag, path] : outputs) {
    if (path.empty()) continue;
    std::string key;
    if (is_standard_output(path)) {
      key = "standard output";
    } else {
      const OutputTarget target = resolve_output(path);
      if (target.kind == OutputKind::kDirect) continue;
      struct stat st {};
      if (::stat(target.resolved.c_str(), &st) == 0) {
        key = "inode " + std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
      } else {  // a new file: its directory's identity and its name
        struct stat dir {};
        const std::string parent = parent_of(target.resolved);
        key = ::stat(parent.c_str(), &dir) == 0
                  ? "new " + std::to_string(dir.st_dev) + ":" + std::to_string(dir.st_ino) + "/" + base_of(target.resolved)
                  : "path " + target.resolved;
      }
    }
    for (const Seen& s : seen) {
      if (s.key == key) {
        const std::string which = *s.path == path ? output_display_name(path)
                                                  : output_display_name(*s.path) + " and " + output_display_name(path);
        throw ParseError(path, 0, *s.flag + " and " + flag + " name the same file (" + which + "): give each output its own path");
      }
    }
    seen.push_back({&flag, &path, key});
  }
}

void check_file_outside_directory(const std::string& file_flag, const std::string& file, const std::string& dir_flag,
                                  const std::string& dir, const std::vector<std::string>& names) {
  if (file.empty() || dir.empty() || is_standard_output(file)) return;
  std::error_code ec;
  const fs::path file_path = fs::weakly_canonical(fs::absolute(file, ec), ec);
  const fs::path dir_path = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  if (ec) return;  // the writes themselves report what is wrong with the paths
  if (file_path == dir_path) {
    throw ParseError(file, 0, file_flag + " names the " + dir_flag + " directory itself: give it a file name of its own");
  }
  if (file_path.parent_path() == dir_path &&
      std::find(names.begin(), names.end(), file_path.filename().string()) != names.end()) {
    throw ParseError(file, 0, file_flag + " names " + file_path.filename().string() + ", which this run writes into " +
                                  dir_flag + " " + dir + ": give it another name");
  }
}

// -----------------------------------------------------------------------------------------------

OutputDirectory::OutputDirectory(std::string dir, bool overwrite) : dir_(std::move(dir)) {
  if (dir_.empty()) throw ParseError("(output directory)", 0, "an output directory is required");
  if (is_standard_output(dir_) || dir_ == "-") {
    throw ParseError(dir_, 0, "this output is a directory of several files: standard output cannot hold it");
  }
  std::error_code ec;
  const fs::path given(dir_);
  const bool exists = fs::exists(given, ec);  // follows symlinks
  if (ec) throw ParseError(dir_, 0, "cannot examine the output directory: " + ec.message());
  if (exists) {
    if (!fs::is_directory(given, ec)) throw ParseError(dir_, 0, "exists and is not a directory");
    resolved_ = fs::canonical(given, ec).string();
    if (ec) throw ParseError(dir_, 0, "cannot resolve the output directory: " + ec.message());
    if (!overwrite) {
      fs::directory_iterator it(resolved_, ec);
      if (ec) throw ParseError(dir_, 0, "cannot list the output directory: " + ec.message());
      if (it != fs::directory_iterator()) {
        throw ParseError(dir_, 0,
                         "the output directory already holds files (" + it->path().filename().string() +
                             ", ...): pass --overwrite to replace the files of the same names, or choose a new "
                             "directory");
      }
    }
  } else {
    // A dangling symlink is followed to where it points; otherwise the path as given.
    std::string p = dir_;
    for (int hops = 0; fs::is_symlink(p, ec) && hops < 40; ++hops) {
      const fs::path link = fs::read_symlink(p, ec);
      if (ec) break;
      p = link.is_absolute() ? link.string() : (fs::path(p).parent_path() / link).string();
    }
    resolved_ = fs::absolute(p, ec).lexically_normal().string();
    if (!resolved_.empty() && resolved_.back() == '/') resolved_.pop_back();
    fs::create_directories(fs::path(resolved_).parent_path(), ec);
    if (ec) throw ParseError(dir_, 0, "cannot create the parent directory: " + ec.message());
  }
  // Staging on the file system of DIR: inside it when it exists (a mount point, a parent that is
  // not writable, the user's working directory: DIR itself is never replaced), beside it when not.
  existed_ = exists;
  overwrite_ = overwrite;
  const std::string where = existed_ ? resolved_ : parent_of(resolved_);
  std::string templ = where + "/." + (existed_ ? std::string("cairn") : base_of(resolved_)) + ".cairn-partial-XXXXXX";
  std::vector<char> name(templ.begin(), templ.end());
  name.push_back('\0');
  if (::mkdtemp(name.data()) == nullptr) {
    throw ParseError(dir_, 0, "cannot create a directory in " + where + ": " + errno_text(errno));
  }
  staging_ = name.data();
  registry_slot_ = register_unfinished(staging_, true);
}

OutputDirectory::~OutputDirectory() {
  if (committed_) return;
  std::error_code ignored;
  fs::remove_all(staging_, ignored);
  unregister_unfinished(registry_slot_);
}

std::string OutputDirectory::staging_path(const std::string& name) const { return (fs::path(staging_) / name).string(); }

std::string OutputDirectory::final_path(const std::string& name) const { return (fs::path(dir_) / name).string(); }

namespace {

/// The moves that put the entries of `from` into the existing directory `to` (files of the same
/// name replaced, subdirectories merged), all checked before anything moves: a file where a
/// directory is, or an existing file without `overwrite`, is an error.
struct Move {
  fs::path from;
  fs::path to;
  bool copy = false;  // the destination is a link to a device, FIFO or stream: written, not renamed over
};

void plan_merge(const fs::path& from, const fs::path& to, bool overwrite, const std::string& dir_name,
                std::vector<Move>& moves) {
  for (const auto& entry : fs::directory_iterator(from)) {
    const fs::path target = to / entry.path().filename();
    std::error_code ec;
    const auto target_status = fs::symlink_status(target, ec);
    const bool target_exists =
        target_status.type() != fs::file_type::not_found && target_status.type() != fs::file_type::none;
    if (entry.is_directory() && fs::is_directory(target, ec)) {
      plan_merge(entry.path(), fs::canonical(target), overwrite, dir_name, moves);
      continue;
    }
    if (target_exists && !overwrite) {
      throw ParseError(dir_name, 0, target.filename().string() +
                                        " appeared in the output directory during the run: nothing was moved in "
                                        "(pass --overwrite to replace files)");
    }
    if (target_status.type() == fs::file_type::directory) {
      throw ParseError(dir_name, 0, "cannot replace the directory " + target.string() + " with a file");
    }
    Move move{entry.path(), target, false};
    if (fs::is_symlink(target_status)) {
      // Written through, like any output: a regular target is renamed over, a node is written.
      const OutputTarget resolved = resolve_output(target.string());
      move.to = resolved.resolved;
      move.copy = resolved.kind == OutputKind::kDirect;
      if (move.copy && entry.is_directory()) {
        throw ParseError(dir_name, 0, "cannot write the directory " + entry.path().filename().string() + " to " +
                                          target.string());
      }
    }
    moves.push_back(move);
  }
}

}  // namespace

namespace {
/// Defers SIGINT and SIGTERM on this thread while it lives: a signal handler that removes
/// unfinished outputs must not run between the moves of a commit.
class DeferInterrupts {
 public:
  DeferInterrupts() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, &old_);
  }
  ~DeferInterrupts() { pthread_sigmask(SIG_SETMASK, &old_, nullptr); }
  DeferInterrupts(const DeferInterrupts&) = delete;
  DeferInterrupts& operator=(const DeferInterrupts&) = delete;

 private:
  sigset_t old_;
};
}  // namespace

void OutputDirectory::commit() {
  if (committed_) return;
  const DeferInterrupts defer;
  std::error_code ignored;
  if (!existed_) {
    // DIR did not exist: the whole set appears in one rename.
    ::chmod(staging_.c_str(), 0777 & ~process_umask());  // mkdtemp made it 0700
    if (::rename(staging_.c_str(), resolved_.c_str()) == 0) {
      unregister_unfinished(registry_slot_);
      registry_slot_ = -1;
      committed_ = true;
      return;
    }
    if (errno != ENOTEMPTY && errno != EEXIST) {
      throw ParseError(dir_, 0, "cannot move the outputs into place: " + errno_text(errno));
    }
    if (!overwrite_) {
      throw ParseError(dir_, 0,
                       "the output directory appeared during the run: nothing was moved in (pass --overwrite to "
                       "write into it)");
    }
    // Created meanwhile by someone else, and --overwrite: merged below like an existing DIR.
  }
  std::vector<Move> moves;
  plan_merge(staging_, resolved_, overwrite_, dir_, moves);
  for (const Move& move : moves) {
    if (move.copy) {
      std::ifstream in(move.from, std::ios::binary);
      write_output(move.to.string(), [&](std::ostream& out) { out << in.rdbuf(); });
      continue;
    }
    // A file replaced keeps its permission bits, as OutputFile does.
    struct stat st {};
    if (::stat(move.to.c_str(), &st) == 0 && S_ISREG(st.st_mode)) ::chmod(move.from.c_str(), st.st_mode & 07777);
    if (::rename(move.from.c_str(), move.to.c_str()) != 0) {
      throw ParseError(dir_, 0,
                       "cannot move " + move.from.string() + " to " + move.to.string() + ": " + errno_text(errno));
    }
  }
  fs::remove_all(staging_, ignored);
  unregister_unfinished(registry_slot_);
  registry_slot_ = -1;
  committed_ = true;
}

void remove_unfinished_outputs() noexcept {
  for (Slot& s : g_slots) {
    if (s.state.load(std::memory_order_acquire) != 2) continue;
    if (s.is_directory) {
      remove_tree_signal_safe(AT_FDCWD, s.path, 0);
    } else {
      ::unlink(s.path);
    }
  }
}

const std::string& standard_input(std::size_t max_bytes) {
  static std::mutex mutex;
  static bool read = false;
  static std::string contents;
  std::lock_guard<std::mutex> lock(mutex);
  if (read) return contents;
  std::array<char, 1 << 16> buffer{};
  while (true) {
    const ssize_t n = ::read(0, buffer.data(), buffer.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      const int error = errno;
      contents.clear();
      throw ParseError("standard input", 0, "read error: " + errno_text(error));
    }
    if (n == 0) break;
    contents.append(buffer.data(), static_cast<std::size_t>(n));
    if (contents.size() > max_bytes) {
      contents.clear();
      throw ParseError("standard input", 0, "more than " + std::to_string(max_bytes) + " bytes: refusing to read it");
    }
  }
  read = true;
  return contents;
}

}  // namespace cairn::io
