#pragma once
/// \file
/// Whole-file reading that decompresses gzip (zlib) and bzip2 (libbz2) transparently, chosen by
/// the file's magic bytes, not its name. For logs that are distributed compressed (the Freiburg
/// benchmark's .clf.bz2), so they are read in place.

#include <cstddef>
#include <string>

namespace cairn::io {

/// Contents of `path`, decompressed if it is gzip or bzip2. Throws ParseError(path, 0, ...) when
/// it cannot be opened, when the compressed data is corrupt or truncated, or when the result
/// would exceed `max_bytes`.
std::string read_maybe_compressed(const std::string& path, std::size_t max_bytes = std::size_t{4} << 30);

}  // namespace cairn::io
