#pragma once
/// \file
/// The saved 2D map file (`cairn slam2d --save-map`, read by `cairn localize2d --map`): a
/// SavedMap2D (saved_map.hpp) in a versioned, checksummed binary format. The layout, byte by
/// byte, is in docs/formats.md ("cairn 2D map"); in short:
///
///   "CAIRNMAP" | u32 version | u32 flags | u64 file size | u64 payload size |
///   zlib stream of the payload | u32 CRC-32 of everything before it
///
/// and the payload (little endian) holds the settings the map was built with, the keyframes,
/// and per submap its pose, the observed part of its grid (a known-cell bit mask and the float
/// log-odds of the known cells, exactly as the grid stores them) and its points.
///
/// Reading checks everything before it is used: size, magic, version, flags, the checksum (so a
/// flipped bit anywhere is caught first), the zlib stream, then every field (counts bounded by
/// the bytes left, numbers finite and in range, indices valid, no byte left over). Any failure
/// is an io::ParseError naming the file and what was expected; a corrupt file can neither crash
/// the reader nor make it allocate more than the data it holds.
///
/// A grid is restored to its observed cells: its extent becomes the bounding box of its known
/// cells (the grid in memory grows by doubling and is mostly unknown), so every cell's known
/// flag and log-odds are bit for bit the same at the same global index; width(), height() and
/// the offsets may differ. Everything else reads back bit for bit.

#include <cstdint>
#include <string>

#include "cairn/slam2d/saved_map.hpp"

namespace cairn::slam2d {

/// The format version this build writes and the newest it reads.
inline constexpr std::uint32_t kMapFileVersion = 1;

/// Writes `map` to `path` through io::write_output (whole or not at all; "-" is standard
/// output). Throws io::ParseError when the file cannot be written. Preconditions: the map's
/// numbers are finite (as Slam2d::export_map() makes them).
void write_saved_map(const std::string& path, const SavedMap2D& map);

/// The bytes write_saved_map writes (for tests and for callers that store the map elsewhere).
std::string encode_saved_map(const SavedMap2D& map);

/// Reads a map file. Throws io::ParseError(path, 0, "...") for a file that cannot be read, is
/// empty, is not a cairn map (magic), has a version other than kMapFileVersion, a wrong size, a
/// checksum mismatch, corrupt compressed data, or any field out of range (the message gives the
/// payload byte offset and the field).
SavedMap2D read_saved_map(const std::string& path);

/// Decodes bytes as read_saved_map does; `name` is the file named in errors.
SavedMap2D decode_saved_map(const std::string& bytes, const std::string& name);

}  // namespace cairn::slam2d
