#pragma once
/// \file
/// The one exception cairn throws for bad input at a boundary (a file, a flag, a config).
/// what() reads "graph.g2o:1042: EDGE_SE2 expects 11 numbers after the tag, found 9".

#include <cstddef>
#include <stdexcept>
#include <string>

namespace cairn::io {

class ParseError : public std::runtime_error {
 public:
  /// `line` is 1-based; 0 means the error concerns the whole file (cannot open, empty, ...).
  ParseError(std::string file, std::size_t line, std::string detail);

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  /// The message without the "file:line: " prefix.
  const std::string& detail() const { return detail_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string detail_;
};

}  // namespace cairn::io
