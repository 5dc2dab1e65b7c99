#include "cairn/vslam/foxglove_output.hpp"

#include <algorithm>

#include "cairn/bag/foxglove_results.hpp"

namespace cairn::vslam {

void write_foxglove_mcap(const std::string& path, const VisualSlam& slam, const RunRecord& run) {
  bag::FoxgloveResults results;
  results.body_frame_id = "camera";
  const std::vector<core::SE3> poses = slam.trajectory();
  const std::size_t n = std::min(poses.size(), run.frames.size());
  for (std::size_t k = 0; k < n; ++k) {
    results.stamps_ns.push_back(run.frames[k].time.nanoseconds());
    results.T_frame_body.push_back(poses[k]);
    results.health.emplace_back(core::to_string(run.frames[k].health));
  }
  for (const Eigen::Vector3d& p : slam.map_points()) results.map_points.push_back(p.cast<float>());
  bag::write_foxglove_mcap(path, results);
}

}  // namespace cairn::vslam
