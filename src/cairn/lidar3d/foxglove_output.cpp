#include "cairn/lidar3d/foxglove_output.hpp"

#include "cairn/bag/foxglove_results.hpp"
#include "cairn/core/time.hpp"

namespace cairn::lidar3d {

void write_foxglove_mcap(const std::string& path, const LidarSlam& slam, const SlamRun& run) {
  bag::FoxgloveResults results;
  results.body_frame_id = "lidar";
  for (const OdometryScanResult& r : run.scans()) {
    results.stamps_ns.push_back(core::Timestamp::from_seconds(r.time_s).nanoseconds());
    results.T_frame_body.push_back(r.T_world_sensor);
    results.health.emplace_back(to_string(r.health));
  }
  results.map_points = run.global_map().points();
  const std::vector<core::SE3> keyframes = slam.keyframe_poses();
  for (const LoopCandidateRecord& loop : slam.summary().candidates) {
    if (!loop.accepted || loop.rejected_by_gnc) continue;
    const auto query = static_cast<std::size_t>(loop.query_keyframe);
    const auto candidate = static_cast<std::size_t>(loop.candidate_keyframe);
    if (query >= keyframes.size() || candidate >= keyframes.size()) continue;
    results.loop_closures.emplace_back(keyframes[query].translation(), keyframes[candidate].translation());
  }
  bag::write_foxglove_mcap(path, results);
}

}  // namespace cairn::lidar3d
