#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {
std::string format_message(const std::string& file, std::size_t line, const std::string& detail) {
  if (line == 0) return file + ": " + detail;
  return file + ":" + std::to_string(line) + ": " + detail;
}
}  // namespace

ParseError::ParseError(std::string file, std::size_t line, std::string detail)
    : std::runtime_error(format_message(file, line, detail)),
      file_(std::move(file)),
      line_(line),
      detail_(std::move(detail)) {}

}  // namespace cairn::io
