#include "cairn/io/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "cairn/io/parse_error.hpp"

namespace cairn::io {

void check_input_file(const std::string& path, const std::string& what) {
  if (path == "-") return;
  if (path.empty()) throw ParseError("(input)", 0, "an empty path: expected " + what);
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) throw ParseError(path, 0, "is a directory, expected " + what);
  if (!S_ISREG(st.st_mode)) return;  // a FIFO or device: opened by the reader, which reports its own errors
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw ParseError(path, 0, std::string("cannot open file: ") + std::strerror(errno));
  ::close(fd);
}

}  // namespace cairn::io
