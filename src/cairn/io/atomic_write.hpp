#pragma once
/// \file
/// Whole-or-nothing file output: the content goes to "<path>.tmp.<pid>", which is renamed over
/// `path` only after it was written and flushed without error.

#include <functional>
#include <ostream>
#include <string>

namespace cairn::io {

/// Calls `write(stream)` on a temporary file beside `path`, then renames it to `path`.
/// Throws ParseError(path, 0, ...) when the file cannot be created, written or renamed; the
/// temporary file is removed in every failure case, and exceptions from `write` propagate.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write);

}  // namespace cairn::io
