#pragma once
/// \file
/// 3D LiDAR point clouds from PCD (v0.7, as PCL writes it), PLY and KITTI Velodyne `.bin` files.
///
/// The format comes from the file's first bytes: "# .PCD" or "VERSION" is PCD, "ply" on the
/// first line is PLY; otherwise a name ending in `.bin` (before any `.xz`, `.gz`, `.bz2`) is a
/// KITTI scan: float32 x y z intensity, little endian, 16 bytes per point, no header. gzip,
/// bzip2 and xz files are decompressed transparently by their magic bytes
/// (io/compressed_file.hpp); "-" reads standard input (PCD or PLY only: it has no name).
///
/// What is read (docs/formats.md, "Point clouds"):
///   * PCD: DATA ascii, binary and binary_compressed (LZF, fields stored column by column);
///     TYPE/SIZE F4 F8 U1 U2 U4 I1 I2 I4; fields x y z (required), intensity or i, ring,
///     time or t; any other field is skipped by its SIZE * COUNT.
///   * PLY: format ascii 1.0 and binary_little_endian 1.0; element vertex with scalar properties
///     x y z (required), intensity (or i, or CloudCompare's scalar_intensity), ring, time or t;
///     other elements (faces with list properties included) are skipped.
///
/// Points with a non-finite coordinate (PCL writes NaN for a missing return) are dropped and
/// counted in the report; bytes after the last record of a binary file (PCL pads binary PCD
/// files) are ignored and counted. Every other defect throws ParseError naming the file, the
/// header line (or 0 and the byte offset for binary data), what was expected and what was found:
/// an empty or truncated file, binary garbage, an unknown keyword or type, missing x/y/z, counts
/// that disagree or that the file cannot hold (checked before anything is allocated), corrupt
/// compressed data, big-endian PLY.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace cairn::io {

/// A LiDAR scan in the sensor frame: x forward, y left, z up, metres. The optional attributes
/// are either empty or hold one value per point, in the order of `points`.
struct PointCloud {
  /// Point coordinates in the sensor frame, metres. Always finite.
  std::vector<Eigen::Vector3f> points;
  /// Return intensity (reflectance) in the file's own unit and scale: KITTI writes 0..1, PCL and
  /// Velodyne drivers 0..255; not rescaled. Empty if the file has no intensity field.
  std::vector<float> intensity;
  /// Acquisition time of each point in seconds, relative to the start of the sweep (the
  /// Velodyne driver's `time` field; Ouster's integer `t` in nanoseconds is converted). Empty if
  /// absent; recover_kitti_ring_and_time() fills it for KITTI scans.
  std::vector<float> time_s;
  /// Laser (ring) index of each point, as the file numbers them. Empty if absent.
  std::vector<std::uint16_t> ring;

  std::size_t size() const { return points.size(); }
};

/// What read_point_cloud() found besides the points.
struct PointCloudReadReport {
  /// Points dropped because x, y or z was NaN or infinite (invalid returns in organised PCD
  /// files).
  std::size_t dropped_non_finite = 0;
  /// Bytes after the last record of a binary file, ignored (the KITTI key frames written by
  /// PCL carry 3,922 zero bytes).
  std::size_t trailing_bytes = 0;
  /// The format that was read: "pcd ascii", "pcd binary", "pcd binary_compressed",
  /// "ply ascii", "ply binary_little_endian" or "kitti bin".
  std::string format;
};

/// Reads a point cloud from `path` (format and compression from the file's bytes, see above).
/// `report`, if given, receives the counts of dropped points and ignored bytes. Throws ParseError.
PointCloud read_point_cloud(const std::string& path, PointCloudReadReport* report = nullptr);

/// Parses a point cloud already in memory (decompressed), naming `path` in errors; `path`'s
/// extension decides only when the bytes match no header (`.bin`: KITTI).
PointCloud parse_point_cloud(const std::string& path, const std::string& contents,
                             PointCloudReadReport* report = nullptr);

/// Writes `points` as a binary little-endian PLY (format binary_little_endian 1.0, element vertex
/// with float x y z), readable by read_point_cloud, CloudCompare, PCL and Open3D. `comment` (one
/// line, no newline) goes into the header if not empty. Stream errors are the caller's to check.
void write_ply(std::ostream& out, const std::vector<Eigen::Vector3f>& points, const std::string& comment = "");

/// Writes `cloud` as a binary PCD v0.7 (DATA binary, little endian, WIDTH = POINTS, HEIGHT 1):
/// FIELDS x y z (float32), then intensity (float32), ring (uint16) and time (float32 seconds)
/// for each attribute that is not empty, readable by read_point_cloud and PCL. The header starts
/// with PCL's "# .PCD v0.7" line; `comment` (one line, no newline) follows as a `#` line if not
/// empty. Stream errors are the caller's
/// to check. Precondition: each non-empty attribute has one value per point.
void write_pcd(std::ostream& out, const PointCloud& cloud, const std::string& comment = "");

/// Fills `cloud.ring` and `cloud.time_s` of a KITTI Velodyne HDL-64E scan from its point order.
/// Approximate, and meaningful only for points in KITTI's original order (a `.bin` file, or a
/// PCD re-serialisation that kept the order, as the KITTI key frames in ../shared/data do).
///
/// Ring: KITTI stores the 64 lasers one after another, highest elevation first. Within a ring
/// the azimuth atan2(y, x) increases counter-clockwise, starting just left of straight ahead
/// (azimuth slightly above 0), wrapping from +pi to -pi behind the car (a step back of more than
/// pi), and ending just right of straight ahead (slightly below 0). The next ring starts at the
/// first step from a negative to a non-negative azimuth (by less than pi) after such a wrap. The
/// wrap behind the car is therefore *inside* a ring: counting wraps alone gives 65 groups whose
/// first and last are half rings (measured on the key frames: the elevation is continuous across
/// the wrap and steps by one laser at the front). Rings are numbered in file order, 0 = first
/// (highest elevation, about +2 deg) to 63 (about -24.8 deg), the reverse of the Velodyne ROS
/// driver's numbering. Points of lasers without returns are absent, so a ring can be short, and
/// a ring with no point on one side of the car merges with its neighbour. Saturates at 65535.
///
/// Time: the sensor spins clockwise seen from above and a KITTI sweep starts and ends facing
/// backward (KITTI raw devkit: timestamps_start / timestamps_end), so
/// time_s = (pi - azimuth) / (2 pi) * sweep_period_s, in [0, sweep_period_s], 0 behind the car,
/// period/2 straight ahead. This is the deskewing model of KISS-ICP (Vizzo et al., RA-L 2023,
/// `get_timestamps` in its KITTI dataloader). It ignores the firing order within a column and
/// any change of the rotation rate during the sweep (about 10 Hz).
/// Precondition: sweep_period_s > 0 and finite.
void recover_kitti_ring_and_time(PointCloud& cloud, double sweep_period_s = 0.1);

}  // namespace cairn::io
