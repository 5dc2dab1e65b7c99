#include "cairn/io/atomic_write.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cairn/io/parse_error.hpp"

namespace cairn::io {

AtomicFile::AtomicFile(std::string path)
    : path_(std::move(path)), temp_path_(path_ + ".tmp." + std::to_string(::getpid())) {}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ignored;
    std::filesystem::remove(temp_path_, ignored);
  }
}

void AtomicFile::write(const std::function<void(std::ostream&)>& emit) {
  std::ofstream out(temp_path_, std::ios::binary | std::ios::trunc);
  if (!out) fail("cannot create " + temp_path_ + ": " + std::strerror(errno));
  emit(out);
  out.close();
  if (!out) fail("error writing " + temp_path_ + " (disk full?)");
}

void AtomicFile::commit() {
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) fail("cannot rename " + temp_path_ + ": " + ec.message());
  committed_ = true;
}

void AtomicFile::fail(const std::string& why) const { throw ParseError(path_, 0, "cannot write: " + why); }

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  AtomicFile file(path);
  file.write(write);
  file.commit();
}

}  // namespace cairn::io
