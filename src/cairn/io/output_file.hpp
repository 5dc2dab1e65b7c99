#pragma once
/// \file
/// Every file cairn writes goes through this module. The rules (docs/conventions.md, "Outputs"):
///
/// * A regular file, or a path that does not exist yet, is written whole or not at all: the
///   content goes to a temporary file in the same directory, is flushed to disk (fsync) and
///   renamed over the target only when every write succeeded. A symlink is followed first (to
///   any depth): the link stays and its target is replaced, as `cp` and editors do.
/// * Anything else is written directly and never renamed over: `-` (standard output),
///   `/dev/stdout`, `/dev/stderr`, `/dev/fd/N` and `/proc/self/fd/N` (the descriptor the
///   process already has, sharing its offset, as a shell redirection expects), character and
///   block devices, FIFOs and everything under `/proc`. The content is assembled in memory
///   first, so a failure while producing it writes nothing at all.
/// * Every write, fsync and close is checked. A short write, ENOSPC, EIO, EPIPE or EFBIG
///   throws ParseError naming the path and the reason, and leaves no temporary file behind.
///   (The `cairn` binary ignores SIGPIPE and SIGXFSZ so that those arrive as errors.)
///
/// The temporaries of unfinished writes are registered so that a signal handler can remove them
/// (remove_unfinished_outputs()) before a forced exit.

#include <functional>
#include <memory>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

namespace cairn::io {

/// How an output path is written (see the file comment).
enum class OutputKind {
  kReplaceFile,  ///< a regular file or a new path: temporary file + rename in its directory
  kDirect,       ///< a stream, device, FIFO or inherited descriptor: written in place
};

struct OutputTarget {
  std::string path;         ///< as given (named in messages)
  OutputKind kind = OutputKind::kReplaceFile;
  std::string resolved;     ///< after following symlinks: the file replaced, or the node opened
  int inherited_fd = -1;    ///< >= 0: write to this descriptor of the process (stdout = 1)
};

/// Where `path` leads. Throws ParseError(path, 0, ...) for a directory, a symlink loop, or a
/// path whose components cannot be examined.
OutputTarget resolve_output(const std::string& path);

/// True for "-", /dev/stdout, /dev/fd/1 and /proc/self/fd/1: the command's messages must then
/// go to standard error so that standard output carries only the data.
bool is_standard_output(const std::string& path);

/// The descriptor "-" and /dev/stdout write to (default 1). The CLI moves the data's standard
/// output to another descriptor so that messages printed to descriptor 1 go to standard error
/// (cli::claim_standard_output).
void set_standard_output(int fd);

/// The name an output is called by in messages: "standard output" for "-", else the path.
std::string output_display_name(const std::string& path);

/// One output. write() produces the content (into the temporary file, or into memory for a
/// direct target); commit() makes it appear at the path. Destroyed without commit(), it leaves
/// the path as it was. Several OutputFiles written before any commits form a set that fails
/// together while producing the content (KITTI poses + times).
class OutputFile {
 public:
  explicit OutputFile(std::string path);
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  ~OutputFile();

  /// Calls `emit(stream)`. Throws ParseError(path, 0, "cannot write: ...") when the temporary
  /// file cannot be created or a write fails; exceptions from `emit` propagate (and nothing is
  /// written).
  void write(const std::function<void(std::ostream&)>& emit);
  /// Renames the temporary file over the target, or writes the content to the direct target.
  /// Throws ParseError on failure, leaving no temporary file.
  void commit();

  const OutputTarget& target() const { return target_; }

 private:
  [[noreturn]] void fail(const std::string& why) const;
  void discard() noexcept;

  OutputTarget target_;
  std::string temp_path_;  // kReplaceFile
  int temp_fd_ = -1;
  int registry_slot_ = -1;
  std::string buffer_;     // kDirect
  bool written_ = false;
  bool committed_ = false;
};

/// One OutputFile, written and committed.
void write_output(const std::string& path, const std::function<void(std::ostream&)>& emit);

/// One output of a set: its path (empty = not asked for) and what it holds.
struct PlannedOutput {
  std::string path;
  std::function<void(std::ostream&)> emit;
};

/// Several files that form one result (a graph and its `--report`, poses and `--out-times`):
/// every one is produced (into its temporary file, or into memory) before any replaces a path,
/// so a failure while producing any of them leaves every path as it was. Empty paths are skipped.
void write_outputs(const std::vector<PlannedOutput>& outputs);

/// Refuses, before any work, two outputs of one command that lead to the same file (the same
/// name, a symlink to it, another hard link of it, or standard output twice): ParseError naming
/// both flags. `outputs` holds (flag, path) pairs; empty paths are skipped. Devices other than
/// standard output (/dev/null) may be named twice.
void check_distinct_outputs(const std::vector<std::pair<std::string, std::string>>& outputs);

/// Refuses, before any work, a file output (`file_flag` `file`) that is the output directory
/// (`dir_flag` `dir`) itself or one of the files the run writes into it (`names`): ParseError
/// naming both flags.
void check_file_outside_directory(const std::string& file_flag, const std::string& file, const std::string& dir_flag,
                                  const std::string& dir, const std::vector<std::string>& names);

/// A directory of outputs (`--out DIR`) that appears whole or not at all. The constructor
/// checks the rule: DIR may be missing or empty; a DIR that already holds entries is refused
/// (ParseError naming DIR and an entry) unless `overwrite`, in which case the files this run
/// writes replace those of the same name (keeping their permission bits; a symlink in DIR is
/// written through) and other entries are left alone. Files are written into a hidden staging
/// directory on DIR's file system: beside a missing DIR (`.<name>.cairn-partial-XXXXXX`), then
/// renamed to DIR in one step; inside an existing DIR (`.cairn.cairn-partial-XXXXXX`), then
/// moved in file by file after every move was checked (DIR itself is never replaced). Files
/// that appear in DIR during the run are not overwritten without `overwrite`. Destroyed without
/// commit(), it removes the staging directory: a run that fails leaves DIR as it was. A symlink
/// DIR is followed: the link stays.
class OutputDirectory {
 public:
  OutputDirectory(std::string dir, bool overwrite);
  OutputDirectory(const OutputDirectory&) = delete;
  OutputDirectory& operator=(const OutputDirectory&) = delete;
  ~OutputDirectory();

  /// Where the run writes its files now (the staging directory).
  const std::string& staging() const { return staging_; }
  /// staging() / name.
  std::string staging_path(const std::string& name) const;
  /// The path a file will have after commit(): dir / name.
  std::string final_path(const std::string& name) const;
  const std::string& dir() const { return dir_; }

  void commit();

 private:
  std::string dir_;
  std::string resolved_;
  std::string staging_;
  int registry_slot_ = -1;
  bool existed_ = false;
  bool overwrite_ = false;
  bool committed_ = false;
};

/// Removes the temporary files and staging directories of every unfinished OutputFile and
/// OutputDirectory. Async-signal-safe (unlink, rmdir and getdents64 only): for a signal handler
/// that is about to end the process.
void remove_unfinished_outputs() noexcept;

/// The process's standard input, read whole on first use and kept (a later reader of "-" gets
/// the same bytes, so a format can be sniffed before it is parsed). Throws ParseError on a read
/// error or beyond `max_bytes`.
const std::string& standard_input(std::size_t max_bytes = std::size_t{4} << 30);

}  // namespace cairn::io
