#pragma once
/// \file
/// Whole-file reading that decompresses gzip (zlib), bzip2 (libbz2) and xz (liblzma)
/// transparently, chosen by the file's magic bytes (1F 8B, "BZh", FD 37 7A 58 5A 00), not its
/// name. For data that is distributed compressed (the Freiburg benchmark's .clf.bz2, the KITTI
/// key frames' .pcd.xz), so it is read in place.

#include <cstddef>
#include <string>

namespace cairn::io {

/// Contents of `path`, decompressed if it is gzip, bzip2 or xz (concatenated streams are read one
/// after the other). Throws ParseError(path, 0, ...) when it cannot be opened, when the
/// compressed data is corrupt or truncated, or when the result would exceed `max_bytes`.
/// "-" reads standard input uncompressed (compressed data there is refused).
std::string read_maybe_compressed(const std::string& path, std::size_t max_bytes = std::size_t{4} << 30);

}  // namespace cairn::io
