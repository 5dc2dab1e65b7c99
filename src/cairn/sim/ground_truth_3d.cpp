#include "cairn/sim/ground_truth_3d.hpp"

#include <cmath>

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::sim {
namespace {

/// Yaw of a pose: the heading of its x axis projected on the ground plane.
double yaw(const core::SE3& T) {
  const Vector3 x = T.so3() * Vector3::UnitX();
  return std::atan2(x.y(), x.x());
}

}  // namespace

std::vector<TrueLoop> find_true_loops(const std::vector<core::SE3>& T_world_lidar, const std::vector<double>& times_s,
                                      const LoopTruthOptions& options) {
  CAIRN_ASSERT(T_world_lidar.size() == times_s.size(), "find_true_loops: one time per pose");
  std::vector<TrueLoop> loops;
  for (std::size_t j = 0; j < T_world_lidar.size(); ++j) {
    for (std::size_t i = 0; i < j; ++i) {
      const double dt = times_s[j] - times_s[i];
      if (dt < options.min_separation_s) break;  // times increase: later i are closer still
      const double distance = (T_world_lidar[j].translation() - T_world_lidar[i].translation()).norm();
      if (distance > options.max_distance_m) continue;
      loops.push_back({i, j, distance, std::abs(core::wrap_angle(yaw(T_world_lidar[j]) - yaw(T_world_lidar[i]))), dt});
    }
  }
  return loops;
}

PassageScans find_passage_scans(const Passage3D& passage, const std::vector<core::SE3>& T_world_lidar,
                                const std::vector<double>& times_s, double max_range_m) {
  PassageScans out;
  out.passage = passage;
  for (std::size_t k = 0; k < T_world_lidar.size(); ++k) {
    const double s = passage.axis.dot(T_world_lidar[k].translation().head<2>() - passage.entry);
    if (s >= 0.0 && s <= passage.length_m) {
      if (!out.any_inside) {
        out.first_inside = k;
        out.first_inside_time_s = times_s[k];
      }
      out.any_inside = true;
      out.last_inside = k;
      out.last_inside_time_s = times_s[k];
    }
    if (s > max_range_m && s < passage.length_m - max_range_m) {
      if (!out.any_blind) out.first_blind = k;
      out.any_blind = true;
      out.last_blind = k;
    }
  }
  return out;
}

}  // namespace cairn::sim
