#include "cairn/io/atomic_write.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "cairn/io/parse_error.hpp"

namespace cairn::io {

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write) {
  const std::string temp = path + ".tmp." + std::to_string(::getpid());
  std::error_code ignored;
  try {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) throw ParseError(path, 0, std::string("cannot write: ") + std::strerror(errno));
    write(out);
    out.flush();
    if (!out) throw ParseError(path, 0, "cannot write: output error (disk full?)");
    out.close();
    std::error_code ec;
    std::filesystem::rename(temp, path, ec);
    if (ec) throw ParseError(path, 0, "cannot write: rename failed: " + ec.message());
  } catch (...) {
    std::filesystem::remove(temp, ignored);
    throw;
  }
}

}  // namespace cairn::io
