#pragma once
/// \file
/// Timed trajectories and the three text formats evaluation tools exchange them in.
///
/// | format | one pose per line                               | quaternion | stamps              |
/// |--------|-------------------------------------------------|------------|---------------------|
/// | TUM    | `timestamp tx ty tz qx qy qz qw` (spaces)       | x y z w    | decimal seconds     |
/// | KITTI  | `r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz`  | (matrix)   | optional times file |
/// | EuRoC  | `ns,px,py,pz,qw,qx,qy,qz[,more columns...]`     | w x y z    | integer nanoseconds |
///
/// Every pose is T_world_body: it maps points from the tracked body frame at that instant into
/// the trajectory's fixed frame, and its translation is the body's origin in that frame.
///  - TUM RGB-D: body = the camera's optical centre, world = the motion-capture frame (ground
///    truth) or whatever frame the estimator chose (estimates).
///  - KITTI odometry: body = left camera at frame i, world = left camera at frame 0, so the
///    first pose is (about) the identity. The times file gives seconds since the sequence start.
///  - EuRoC MAV (ASL) ground truth: p_RS_R and q_RS, i.e. T_R_S with body = the IMU frame S and
///    world = the Vicon/Leica reference frame R.
///
/// Readers are strict (STYLE.md section 3): any malformed line rejects the whole file with a
/// ParseError naming file, line, what was expected and what was found. Timestamps must strictly
/// increase and lie within 9.2e9 s of the epoch (so every format can hold them). What readers
/// tolerate is listed per reader and summarised in a TrajectoryReadReport.

#include <cstddef>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"

namespace cairn::io {

/// Poses with optional timestamps. Invariant: `stamps` is empty or has one strictly increasing
/// stamp per pose (readers guarantee it; writers assert the size and check the order).
struct Trajectory {
  /// Empty when the format had none (KITTI without a times file).
  std::vector<core::Timestamp> stamps;
  /// T_world_body per the format's frames (see the file comment).
  std::vector<core::SE3> poses;

  bool has_stamps() const { return !stamps.empty(); }
  std::size_t size() const { return poses.size(); }
};

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

/// "tum", "kitti" or "euroc": the names the CLI and configs use.
std::string_view to_string(TrajectoryFormat format);
/// Inverse of to_string (lower case only); nullopt for any other name.
std::optional<TrajectoryFormat> trajectory_format_from_name(std::string_view name);

/// What a reader accepted without complaint but a careful user may want to know.
struct TrajectoryReadReport {
  /// Poses read (= Trajectory::size()).
  std::size_t poses = 0;
  /// Lines skipped because they were blank or started with '#' (EuRoC header included; KITTI
  /// counts the pose file and the times file).
  std::size_t comment_lines = 0;
  /// Quaternions whose norm differed from 1 by more than kQuaternionNormTolerance. All
  /// quaternions are normalised; rounding to 4-6 decimals (TUM files) stays below the tolerance,
  /// so a count here means the writer did not write unit quaternions at all.
  std::size_t quaternions_normalised = 0;
  /// KITTI only: max over poses of max_ij |(R^T R - I)_ij| before R was projected onto SO(3).
  /// KITTI_00 ground truth (7 significant digits) gives 2e-7, an ORB-SLAM estimate 8e-7.
  double max_rotation_orthonormality_error = 0;
  /// TUM and EuRoC: poses dropped because their timestamp repeated the previous line's (the
  /// first pose of each stamp is kept). KITTI times files refuse repeats.
  std::size_t repeated_stamps_dropped = 0;
  /// Human-readable, "file:line: ...". At most one per kind of problem.
  std::vector<std::string> warnings;
};

/// |norm - 1| above which a quaternion counts in TrajectoryReadReport::quaternions_normalised.
inline constexpr double kQuaternionNormTolerance = 1e-3;
/// max |R^T R - I| above which a KITTI rotation block is rejected rather than projected: far
/// beyond rounding to 6 digits (~1e-6), small enough that projecting cannot hide a wrong
/// matrix layout (a scale, shear or transposed translation).
inline constexpr double kMaxRotationOrthonormalityError = 1e-2;

/// TUM RGB-D: `timestamp tx ty tz qx qy qz qw`, separated by spaces or tabs; blank lines and
/// lines starting with '#' are skipped. Timestamps (decimal seconds, read exactly to the ns)
/// must strictly increase. Throws ParseError on anything else, and on a file without poses.
Trajectory read_tum(const std::string& path, TrajectoryReadReport* report = nullptr);

/// KITTI odometry: 12 numbers per line, the top 3x4 of T_world_body in row-major order. Blank
/// and '#' lines are skipped (as numpy.loadtxt, which evo uses, does). The rotation block is
/// projected onto SO(3); more than kMaxRotationOrthonormalityError away, or a reflection, is an
/// error. `times_path`, when given, holds one time in seconds per line (blank and '#' lines
/// skipped), strictly increasing, exactly one per pose; without it the stamps stay empty.
Trajectory read_kitti(const std::string& path, const std::string& times_path = "",
                      TrajectoryReadReport* report = nullptr);

/// EuRoC MAV / ASL CSV: `timestamp_ns,px,py,pz,qw,qx,qy,qz` and any further columns
/// (ground-truth files add velocity and IMU biases), which are ignored without being parsed:
/// cairn stores poses only, so their content cannot matter. Blank and '#' lines (the header)
/// are skipped. Timestamps are integer nanoseconds and must strictly increase.
Trajectory read_euroc(const std::string& path, TrajectoryReadReport* report = nullptr);

/// Writers go through io::OutputFile: a regular file is replaced atomically (a hidden temporary,
/// then rename, through symlinks), so a crash never leaves half a file; "-", FIFOs and devices
/// are written in place (docs/conventions.md, "Outputs"). Numbers are written as the shortest text that parses back to the same
/// double, stamps exactly (seconds with 9 decimals; EuRoC integer ns), so reading the file back
/// gives bit-identical stamps, translations and (unit) quaternions. KITTI stores the matrix,
/// which is rebuilt from the quaternion and re-projected on reading: equal to ~1e-15, not bits.
/// Throws ParseError(path, 0, "cannot write: ...") when the file cannot be written, or the
/// trajectory could not be read back: empty, stamps missing (TUM, EuRoC), not increasing or
/// more than 9.2e9 s from the epoch.
/// Precondition: stamps empty or stamps.size() == poses.size().
void write_tum(const std::string& path, const Trajectory& trajectory);
/// Poses to `path`; stamps to `times_path` when it is not empty (both replaced atomically).
void write_kitti(const std::string& path, const Trajectory& trajectory,
                 const std::string& times_path = "");
/// Writes the 8 pose columns with a '#' header; columns beyond them were not kept on reading.
void write_euroc(const std::string& path, const Trajectory& trajectory);

/// Stream versions of the writers (same text, same checks; errors name the file "<stream>").
void write_tum(std::ostream& out, const Trajectory& trajectory);
void write_kitti(std::ostream& poses_out, const Trajectory& trajectory,
                 std::ostream* times_out = nullptr);
void write_euroc(std::ostream& out, const Trajectory& trajectory);

}  // namespace cairn::io
