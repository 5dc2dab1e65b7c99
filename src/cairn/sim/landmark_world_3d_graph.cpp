#include "cairn/sim/landmark_world_3d_graph.hpp"

#include <cmath>
#include <optional>

#include "cairn/core/so3.hpp"

namespace cairn::sim {

WorldGraph3D graph_from_world(const LandmarkWorld3D& world) {
  WorldGraph3D out;
  backend::LandmarkGraph3D& graph = out.graph;
  if (world.T_world_body.empty()) return out;
  graph.poses.push_back(world.T_world_body.front());
  const Matrix6 odometry_information = world.odometry_covariance.inverse();
  for (std::size_t k = 0; k < world.odometry.size(); ++k) {
    graph.poses.push_back(graph.poses.back() * world.odometry[k]);
    graph.odometry.push_back({k, k + 1, world.odometry[k], odometry_information});
  }
  const Matrix3 observation_information = world.observation_covariance.inverse();
  const backend::LandmarkModel3D model = world.sensor == sim::LandmarkSensor3D::kPoint
                                             ? backend::LandmarkModel3D::kPoint
                                             : backend::LandmarkModel3D::kRangeBearingElevation;
  std::vector<std::optional<std::size_t>> variable_of(world.p_world.size());
  for (const sim::LandmarkObservation3D& o : world.observations) {
    backend::LandmarkFactor3D factor;
    factor.pose = o.pose;
    factor.model = model;
    factor.z = o.z;
    factor.information = observation_information;
    if (!variable_of[o.landmark]) {
      variable_of[o.landmark] = graph.landmarks.size();
      graph.landmarks.push_back(backend::landmark_from_observation_3d(graph.poses[o.pose], factor));
      out.world_landmark.push_back(o.landmark);
    }
    factor.landmark = *variable_of[o.landmark];
    graph.observations.push_back(factor);
  }
  return out;
}

Errors3D errors(const LandmarkWorld3D& world, const WorldGraph3D& built, const backend::LandmarkGraph3D& graph) {
  Errors3D e;
  if (graph.poses.empty()) return e;
  double position = 0.0;
  double rotation = 0.0;
  for (std::size_t k = 0; k < graph.poses.size(); ++k) {
    position += (graph.poses[k].translation() - world.T_world_body[k].translation()).squaredNorm();
    const Matrix3 R_delta = world.T_world_body[k].rotation_matrix().transpose() * graph.poses[k].rotation_matrix();
    rotation += core::SO3::from_matrix(R_delta).log().squaredNorm();
  }
  const double n = static_cast<double>(graph.poses.size());
  e.position_rms_m = std::sqrt(position / n);
  e.rotation_rms_rad = std::sqrt(rotation / n);
  double landmark = 0.0;
  for (std::size_t l = 0; l < graph.landmarks.size(); ++l) {
    landmark += (graph.landmarks[l] - world.p_world[built.world_landmark[l]]).squaredNorm();
  }
  e.landmark_rms_m = graph.landmarks.empty() ? 0.0 : std::sqrt(landmark / static_cast<double>(graph.landmarks.size()));
  return e;
}

}  // namespace cairn::sim
