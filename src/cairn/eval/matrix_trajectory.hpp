#pragma once
/// \file
/// Trajectories as evo and the KITTI devkit hold them: 4x4 homogeneous matrices, rotation
/// blocks exactly as read.
///
/// cairn's readers project every KITTI rotation block onto SO(3) (io/trajectory.hpp). The files
/// hold 6-7 significant digits, so the blocks are off SO(3) by up to ~1e-6, and evo and the
/// devkit use them unprojected: for RPE over 10 m on KITTI 00 the projection alone moves the
/// per-pair errors by up to 2e-6 relative, more than the 1e-6 agreement we promise. So the
/// metrics work on matrices, and read_kitti_matrices keeps the blocks as written. TUM and EuRoC
/// poses are quaternions: their matrices are exact rotations either way (evo normalises the
/// quaternion too).

#include <string>
#include <vector>

#include "cairn/core/time.hpp"
#include "cairn/core/types.hpp"
#include "cairn/eval/status.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::eval {

struct MatrixTrajectory {
  MatrixTrajectory() = default;
  /// From cairn's trajectory: T_world_body as 4x4 matrices, same stamps. Implicit on purpose:
  /// every metric accepts an io::Trajectory where it takes a MatrixTrajectory.
  MatrixTrajectory(const io::Trajectory& trajectory);  // NOLINT(google-explicit-constructor)

  /// Empty or one per pose, strictly increasing (validate() checks).
  std::vector<core::Timestamp> stamps;
  /// T_world_body; the bottom row is (0 0 0 1).
  std::vector<Matrix4> poses;

  bool has_stamps() const { return !stamps.empty(); }
  std::size_t size() const { return poses.size(); }
};

/// Reads a KITTI pose file (and optional times file) with every check of io::read_kitti, but
/// keeps each 3x4 block exactly as written instead of projecting its rotation onto SO(3).
/// Throws io::ParseError as io::read_kitti does.
MatrixTrajectory read_kitti_matrices(const std::string& path, const std::string& times_path = "");

/// Non-empty; stamps absent or one per pose and strictly increasing; every entry finite.
/// `name` ("reference", "estimate") starts the message.
Outcome validate_trajectory(const MatrixTrajectory& trajectory, const char* name);

/// evo's lie_algebra.se3_inverse: (R^T, -R^T t). For an exact rotation this is the inverse;
/// for a block slightly off SO(3) it is what evo computes.
Matrix4 se3_inverse(const Matrix4& T);

}  // namespace cairn::eval
