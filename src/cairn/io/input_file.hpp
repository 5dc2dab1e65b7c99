#pragma once
/// \file
/// The one check every reader makes before it opens an input path, so that each command says
/// the same thing for the same mistake (docs/conventions.md, "Inputs"):
///
///   cairn: error: runs/: is a directory, expected a file
///   cairn: error: grpah.g2o: cannot open file: No such file or directory
///
/// instead of what the C++ library makes of it ("read error", "empty file", "no poses found", or
/// libstdc++'s `basic_filebuf::underflow` for a directory opened as a file).

#include <string>

namespace cairn::io {

/// Throws ParseError(path, 0, ...) when `path` is a directory, does not exist or cannot be
/// opened for reading. "-" (standard input) and character devices, FIFOs and sockets pass.
/// `what` names the expected content in the directory message ("a map file", "a YAML file").
void check_input_file(const std::string& path, const std::string& what = "a file");

}  // namespace cairn::io
