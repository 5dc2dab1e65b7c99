#include "cairn/slam2d/foxglove_output.hpp"

#include <cmath>

#include "cairn/bag/foxglove_results.hpp"
#include "cairn/slam2d/probability_grid.hpp"

namespace cairn::slam2d {
namespace {

core::SE3 lift(const core::SE2& T) {
  return core::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(T.angle(), Eigen::Vector3d::UnitZ())),
                   Eigen::Vector3d(T.x(), T.y(), 0.0));
}

bag::OccupancyGrid occupancy(const ProbabilityGrid& grid) {
  bag::OccupancyGrid out;
  out.resolution_m = grid.resolution();
  out.width = static_cast<std::size_t>(grid.width());
  out.height = static_cast<std::size_t>(grid.height());
  out.origin_m = grid.origin();
  out.cells.reserve(out.width * out.height);
  for (int j = 0; j < grid.height(); ++j) {
    for (int i = 0; i < grid.width(); ++i) {
      out.cells.push_back(grid.cell_known(i, j) ? static_cast<std::int8_t>(std::lround(100.0 * grid.cell_probability(i, j)))
                                                : std::int8_t{-1});
    }
  }
  return out;
}

}  // namespace

void write_foxglove_mcap(const std::string& path, const Slam2d& slam, const Slam2dOptions& options) {
  bag::FoxgloveResults results;
  results.body_frame_id = "laser";
  for (const ScanResult& scan : slam.trajectory()) {
    results.stamps_ns.push_back(scan.time.nanoseconds());
    results.T_frame_body.push_back(lift(scan.T_world_laser));
    results.health.emplace_back(core::to_string(scan.health));
  }
  ProbabilityGridOptions map_options = options.grid;
  map_options.resolution_m = options.output_map_resolution_m;
  results.grid = occupancy(slam.render_map(map_options));
  const io::PoseGraph2D graph = slam.pose_graph();
  for (const auto& edge : graph.edges) {
    if (edge.to == edge.from + 1) continue;
    const Eigen::Vector2d a = graph.vertices[static_cast<std::size_t>(edge.from)].T_world_pose.translation();
    const Eigen::Vector2d b = graph.vertices[static_cast<std::size_t>(edge.to)].T_world_pose.translation();
    results.loop_closures.emplace_back(Eigen::Vector3d(a.x(), a.y(), 0.0), Eigen::Vector3d(b.x(), b.y(), 0.0));
  }
  bag::write_foxglove_mcap(path, results);
}

}  // namespace cairn::slam2d
