#pragma once
/// \file
/// Whole-or-nothing file output: content goes to "<path>.tmp.<pid>", which is renamed over
/// `path` only after it was written and closed without error.

#include <functional>
#include <ostream>
#include <string>

namespace cairn::io {

/// A temporary file beside `path`, renamed over it by commit(); removed if never committed,
/// including when writing throws. Two AtomicFiles written before either commits make a pair of
/// outputs (KITTI poses + times) that fail together.
class AtomicFile {
 public:
  explicit AtomicFile(std::string path);
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  ~AtomicFile();

  /// Calls `emit(stream)` on the temporary file. Throws ParseError(path, 0, "cannot write: ...")
  /// when it cannot be created or written; exceptions from `emit` propagate.
  void write(const std::function<void(std::ostream&)>& emit);
  /// Renames the temporary file over `path`. Throws ParseError on failure.
  void commit();

 private:
  [[noreturn]] void fail(const std::string& why) const;

  std::string path_;
  std::string temp_path_;
  bool committed_ = false;
};

/// One AtomicFile, written and committed.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace cairn::io
