#include "cairn/lidar3d/saved_map.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <unordered_map>
#include <limits>
#include <stdexcept>
#include <string>

#include "cairn/lidar3d/outputs.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/slam_run.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

std::vector<Eigen::Vector3f> estimate_normals(const std::vector<Eigen::Vector3f>& points, double voxel_m) {
  // VoxelHashMapOptions' defaults: the plane rule of the matching map.
  const VoxelHashMapOptions rule;
  const double inverse = 1.0 / voxel_m;
  std::unordered_map<Voxel, std::vector<std::size_t>, VoxelHash> voxels;
  for (std::size_t i = 0; i < points.size(); ++i) voxels[voxel_of(points[i].cast<double>(), inverse)].push_back(i);
  std::vector<Eigen::Vector3f> normals(points.size(), Eigen::Vector3f::Zero());
  for (const auto& [voxel, members] : voxels) {
    if (members.size() < static_cast<std::size_t>(rule.min_points_for_normal)) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const std::size_t i : members) mean += points[i].cast<double>();
    mean /= static_cast<double>(members.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const std::size_t i : members) {
      const Eigen::Vector3d d = points[i].cast<double>() - mean;
      covariance.noalias() += d * d.transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance / static_cast<double>(members.size()));
    if (!(eigen.eigenvalues()(0) < rule.planarity_ratio * eigen.eigenvalues()(1))) continue;
    const Eigen::Vector3f normal = eigen.eigenvectors().col(0).normalized().cast<float>();
    for (const std::size_t i : members) normals[i] = normal;
  }
  return normals;
}

namespace {

/// The odometry's preprocessing and voxel, with the front end it actually used.
SavedSensorModel sensor_model(const LidarSlam& slam) {
  const LidarOdometryOptions& o = slam.options().odometry;
  SavedSensorModel sensor;
  sensor.front_end = slam.front_end() == FrontEnd::kAuto ? FrontEnd::kDense : slam.front_end();
  sensor.rings_from_kitti_order = o.rings_from_kitti_order;
  sensor.min_range_m = o.min_range_m;
  sensor.max_range_m = o.max_range_m;
  sensor.deskew = o.deskew;
  sensor.vertical_angle_correction_rad = o.vertical_angle_correction_rad;
  sensor.sweep_period_s = o.sweep_period_s;
  sensor.voxel_size_m = o.voxel_size_m;
  sensor.max_points_per_voxel = o.max_points_per_voxel;
  return sensor;
}

}  // namespace

SavedMap3D make_saved_map(const LidarSlam& slam, const SlamRun& run, const std::string& configuration_json,
                          const std::string& source, const std::vector<bool>* keep) {
  SavedMap3D map;
  const LidarOdometryOptions& o = slam.options().odometry;
  map.sensor = sensor_model(slam);
  map.scan_context = slam.options().scan_context;
  map.map_voxel_m = run.map_voxel_m();

  const std::vector<core::SE3> poses = slam.keyframe_poses();
  const std::vector<std::size_t> scans = slam.keyframe_scans();
  if (keep != nullptr && keep->size() != poses.size()) {
    throw std::invalid_argument("make_saved_map: " + std::to_string(keep->size()) + " keep flags for " +
                                std::to_string(poses.size()) + " keyframes");
  }
  // The keyframes' points as the odometry registered them (corrected, deskewed), at their
  // optimised poses, one per voxel: what a localiser's scans, treated the same way, must match.
  GlobalMap points(run.map_voxel_m());
  std::vector<int> renumbered(poses.size(), -1);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (keep != nullptr && !(*keep)[k]) continue;
    renumbered[k] = static_cast<int>(map.keyframes.size());
    points.add_scan(slam.keyframe_points(k), poses[k]);
    SavedKeyframe3D kf;
    kf.time_s = run.scans().at(scans[k]).time_s;
    kf.scan = run.sequence_indices().at(scans[k]);
    kf.T_world_sensor = poses[k];
    kf.segment = slam.keyframe_segment(k);
    // As LidarSlam's loop search makes them (slam.cpp, close_loops).
    kf.scan_context = make_scan_context(slam.keyframe_points(k), map.scan_context).descriptor;
    map.keyframes.push_back(std::move(kf));
  }
  map.points_world = points.points();
  if (run.dynamic_options()) {
    // The run's maps leave out what moved: so does the saved one (the same rays, its own points).
    const std::vector<bool> dynamic = find_dynamic_points(map.points_world, keyframe_rays(slam), *run.dynamic_options());
    std::vector<Eigen::Vector3f> kept;
    for (std::size_t i = 0; i < map.points_world.size(); ++i) {
      if (!dynamic[i]) kept.push_back(map.points_world[i]);
    }
    map.points_world = std::move(kept);
  }
  map.normals_world = estimate_normals(map.points_world, o.voxel_size_m);
  std::vector<bool> is_loop;
  const io::PoseGraph3D graph = slam.pose_graph(&is_loop);
  for (std::size_t e = 0; e < graph.edges.size(); ++e) {
    const auto& edge = graph.edges[e];
    const int from = renumbered[static_cast<std::size_t>(edge.from)], to = renumbered[static_cast<std::size_t>(edge.to)];
    if (from < 0 || to < 0) continue;
    // Symmetric to the last bit (the file keeps the upper triangle).
    const Eigen::Matrix<double, 6, 6> information = 0.5 * (edge.information + edge.information.transpose());
    map.edges.push_back({from, to, edge.T_from_to, information, is_loop[e]});
  }
  map.configuration_json = configuration_json;
  map.source = source;
  return map;
}

}  // namespace cairn::lidar3d
