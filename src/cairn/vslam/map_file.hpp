#pragma once
/// \file
/// The saved visual map file (`cairn vslam --save-map`, read by `cairn vslam --localize-in`): a
/// SavedVisualMap (saved_map.hpp) in the versioned, checksummed container the 2D and 3D LiDAR maps
/// use (io/map_container.hpp; lidar3d/map_file.hpp is the model). The layout, byte by byte, is in
/// docs/formats.md ("cairn visual map"); in short:
///
///   "CAIRNVSM" | u32 version | u32 flags | u64 file size | u64 payload size |
///   zlib stream of the payload | u32 CRC-32 of everything before it
///
/// and the payload (little endian) holds the sequence kind, the camera calibration, the ORB
/// options, the close-depth threshold, the vocabulary's identity, the mapping run's configuration
/// and source, the keyframes (time, frame index, pose, keypoints with their measurements, map
/// point and descriptor), the map points (position, normal, scale-invariance distances,
/// descriptor, reference keyframe, tracking statistics, observations) and the covisibility graph
/// (keyframe pairs and the points they share).
///
/// Reading checks the container first (size, magic, version, flags, checksum, zlib stream), then
/// every field before it is used: counts bounded by the bytes left before anything is allocated,
/// the kind code known, the calibration valid (CameraCalibration::is_valid, width and height > 0,
/// and what VisualSlam needs of the kind: a baseline for stereo, a depth scale and a virtual
/// baseline for RGB-D), the ORB options valid (OrbOptions::is_valid), the vocabulary identity
/// either none (all zero) or a vocabulary's (branching in [2, 64], depth in [1, 12]), numbers
/// finite and in range, quaternions unit to 1e-6, octaves in [0, orb.levels), at least one
/// keyframe, a keypoint's map point -1 or an existing point, point normals unit to 1e-3,
/// 0 <= min_distance <= max_distance, 0 <= found <= visible, visible >= 1, reference keyframes
/// existing, observations (at least one per point, at most one per keyframe) naming an existing
/// keyframe and keypoint whose map point is that point, and every keypoint with a map point
/// observed by it; covisibility pairs a < b, existing, once each, shared >= 1; no byte left over.
/// Any failure is an io::ParseError naming the file, the payload byte offset and the field; a
/// corrupt file can neither crash the reader nor make it allocate more than the data it holds.
/// Everything reads back bit for bit (quaternions are normalised on input, which keeps a unit
/// quaternion as it is: docs/conventions.md).

#include <cstdint>
#include <string>

#include "cairn/vslam/saved_map.hpp"

namespace cairn::vslam {

/// The format version this build writes and the newest it reads.
inline constexpr std::uint32_t kVisualMapFileVersion = 1;

/// Writes `map` to `path` through io::write_output (whole or not at all; "-" is standard output).
/// Throws io::ParseError when the file cannot be written. Preconditions (what the reader checks,
/// above): at least one keyframe; the camera valid with width and height set; the ORB options
/// valid; numbers finite; unit quaternions and point normals; octaves in [0, orb.levels);
/// keypoints' map points -1 or point indices, and a point's observations exactly the keypoints
/// whose map point it is, at most one per keyframe; reference keyframes and covisibility ends
/// keyframe indices, pairs a < b listed once; at most 2^32 - 1 of anything counted; source at
/// most 64 KiB, configuration_json at most 1 MiB.
void write_saved_map(const std::string& path, const SavedVisualMap& map);

/// The bytes write_saved_map writes (for tests and for callers that store the map elsewhere).
std::string encode_saved_map(const SavedVisualMap& map);

/// Reads a map file ("-" is standard input). Throws io::ParseError(path, 0, "...") for a file
/// that cannot be read, is empty, is not a cairn visual map (magic; a cairn 2D map or 3D LiDAR map
/// is named as such), has a version other than kVisualMapFileVersion, a wrong size, a checksum
/// mismatch, corrupt compressed data, or any field out of range (the message gives the payload
/// byte offset and the field).
SavedVisualMap read_saved_map(const std::string& path);

/// Decodes bytes as read_saved_map does; `name` is the file named in errors.
SavedVisualMap decode_saved_map(const std::string& bytes, const std::string& name);

}  // namespace cairn::vslam
