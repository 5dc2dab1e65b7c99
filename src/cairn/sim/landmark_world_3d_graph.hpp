#pragma once
/// \file
/// 3D landmark graph SLAM on the simulator's 3D landmark world (sim/landmark_world_3d.hpp):
/// the factor graph built from its measurements, initialised by dead reckoning and each
/// landmark's first observation, and the errors of an estimate against its ground truth. For the
/// tests and benchmarks of the back end's 3D landmark elimination (backend/landmark_graph_3d.hpp).

#include <cstddef>
#include <vector>

#include "cairn/backend/landmark_graph_3d.hpp"
#include "cairn/sim/landmark_world_3d.hpp"

namespace cairn::sim {

struct WorldGraph3D {
  /// Pose 0 at the true pose 0 (it fixes the gauge, so no alignment is needed), the others
  /// composed from odometry; one variable per landmark observed at least once.
  backend::LandmarkGraph3D graph;
  /// World landmark index of each landmark variable.
  std::vector<std::size_t> world_landmark;
};

WorldGraph3D graph_from_world(const LandmarkWorld3D& world);

struct Errors3D {
  double position_rms_m = 0.0;   ///< poses, RMS of |t_est - t_true|
  double rotation_rms_rad = 0.0; ///< poses, RMS of |log(R_true^T R_est)|
  double landmark_rms_m = 0.0;   ///< landmark variables, RMS of |p_est - p_true|
};

/// Precondition: `graph` has the poses and landmark variables of `built` (maybe optimised).
Errors3D errors(const LandmarkWorld3D& world, const WorldGraph3D& built, const backend::LandmarkGraph3D& graph);

}  // namespace cairn::sim
