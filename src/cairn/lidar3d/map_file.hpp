#pragma once
/// \file
/// The saved 3D LiDAR map file (`cairn slam3d --save-map`, read by `cairn localize3d`): a
/// SavedMap3D (saved_map.hpp) in the versioned, checksummed container the 2D map uses
/// (io/map_container.hpp; slam2d/map_file.hpp is the model). The layout, byte by byte, is in
/// docs/formats.md ("cairn 3D LiDAR map"); in short:
///
///   "CAIRN3DM" | u32 version | u32 flags | u64 file size | u64 payload size |
///   zlib stream of the payload | u32 CRC-32 of everything before it
///
/// and the payload (little endian) holds the sensor model, the Scan Context options, the map
/// voxel, the mapping run's configuration and source, the global map's points and normals (f32),
/// the keyframes (time, scan index, pose, segment, descriptor) and the pose graph's edges
/// (endpoints, measurement, information, loop flag).
///
/// Reading checks the container first (size, magic, version, flags, checksum, zlib stream), then
/// every field before it is used: counts bounded by the bytes left before anything is allocated,
/// enum codes known, options valid (LidarOdometryOptions::is_valid and ScanContextOptions::is_valid
/// rules), numbers finite and in range, quaternions unit to 1e-6, normals zero or unit to 1e-3,
/// descriptors >= 0, edge ends existing keyframes, information matrices positive definite, no
/// byte left over. Any failure is an io::ParseError naming the file, the payload byte offset and
/// the field; a corrupt file can neither crash the reader nor make it allocate more than the data
/// it holds. Everything reads back bit for bit (quaternions are normalised on input, which keeps
/// a unit quaternion as it is: docs/conventions.md).

#include <cstdint>
#include <string>

#include "cairn/lidar3d/saved_map.hpp"

namespace cairn::lidar3d {

/// The format version this build writes and the newest it reads.
inline constexpr std::uint32_t kMap3dFileVersion = 1;

/// Writes `map` to `path` through io::write_output (whole or not at all; "-" is standard output).
/// Throws io::ParseError when the file cannot be written. Preconditions (as make_saved_map()
/// makes the map): sensor.front_end is not kAuto; as many normals as points; every keyframe's
/// descriptor is scan_context.rings x scan_context.sectors; edge ends are keyframe indices;
/// numbers finite; each information matrix symmetric (its upper triangle is written); source at
/// most 64 KiB, configuration_json at most 1 MiB.
void write_saved_map(const std::string& path, const SavedMap3D& map);

/// The bytes write_saved_map writes (for tests and for callers that store the map elsewhere).
std::string encode_saved_map(const SavedMap3D& map);

/// Reads a map file ("-" is standard input). Throws io::ParseError(path, 0, "...") for a file
/// that cannot be read, is empty, is not a cairn 3D LiDAR map (magic; a cairn 2D map is named as
/// such), has a version other than kMap3dFileVersion, a wrong size, a checksum mismatch, corrupt
/// compressed data, or any field out of range (the message gives the payload byte offset and the
/// field).
SavedMap3D read_saved_map(const std::string& path);

/// Decodes bytes as read_saved_map does; `name` is the file named in errors.
SavedMap3D decode_saved_map(const std::string& bytes, const std::string& name);

}  // namespace cairn::lidar3d
