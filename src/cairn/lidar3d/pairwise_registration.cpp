#include "cairn/lidar3d/pairwise_registration.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>

#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/lidar3d/gicp.hpp"
#include "cairn/lidar3d/registration.hpp"
#include "cairn/lidar3d/scan_context.hpp"
#include "cairn/lidar3d/slam.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Points = std::vector<Eigen::Vector3d>;

/// The two clouds as registered: cropped to [min, max] range, one point per voxel.
struct PreparedPair {
  Points source_cropped;  // in range, every point: GICP's support and Scan Context read these
  Points target_cropped;
  Points source_sensor;
  Points target_sensor;
  VoxelHashMap target_map{VoxelHashMapOptions{1.0, 20}};  // KISS-ICP's map, as the benchmark's ICP
};

Points crop(const io::PointCloud& cloud, double min_range_m, double max_range_m) {
  Points points;
  points.reserve(cloud.size());
  for (const Eigen::Vector3f& p : cloud.points) {
    const double r = p.cast<double>().norm();
    if (r > min_range_m && r <= max_range_m) points.push_back(p.cast<double>());
  }
  return points;
}

PreparedPair prepare(const io::PointCloud& source, const io::PointCloud& target, const PairwiseRegistrationOptions& o) {
  PreparedPair pair;
  pair.source_cropped = crop(source, o.min_range_m, o.max_range_m);
  pair.target_cropped = crop(target, o.min_range_m, o.max_range_m);
  pair.source_sensor = voxel_downsample(pair.source_cropped, o.source_voxel_m);
  pair.target_sensor = voxel_downsample(pair.target_cropped, o.target_voxel_m);
  pair.target_map.add_points(pair.target_sensor);
  return pair;
}

/// The chosen method from `guess` at correspondence distance `max_m`: the pose and whether it
/// converged.
std::pair<core::SE3, bool> refine(const PreparedPair& pair, const GicpCloud* source_gicp, const GicpCloud* target_gicp,
                                  const core::SE3& guess, double max_m, const PairwiseRegistrationOptions& o,
                                  int* iterations) {
  if (o.method == PairwiseMethod::kGicp) {
    GicpOptions gicp;
    gicp.max_correspondence_m = max_m;
    gicp.max_iterations = o.max_iterations;
    const GicpResult r = register_gicp(*target_gicp, *source_gicp, guess, gicp);
    *iterations += r.iterations;
    return {r.T_target_source, r.converged};
  }
  RegistrationOptions icp;
  icp.metric = IcpMetric::kPointToPlane;
  icp.max_iterations = o.max_iterations;
  const RegistrationResult r = register_scan(pair.target_map, pair.source_sensor, guess, max_m, max_m / 3.0, icp);
  *iterations += r.iterations;
  return {r.T_map_sensor, r.converged};
}

/// Fitness and inlier RMSE as Open3D defines them (the share of source points whose nearest
/// target point lies within the correspondence distance, and their RMS distance), for every
/// method alike.
void measure_fit(const PreparedPair& pair, double max_m, PairwiseRegistrationResult& result) {
  std::size_t inliers = 0;
  double squared_sum = 0.0;
  for (const Eigen::Vector3d& p : pair.source_sensor) {
    Eigen::Vector3d q;
    double d2 = 0.0;
    if (pair.target_map.nearest(result.T_target_source * p, &q, &d2, nullptr) && d2 <= max_m * max_m) {
      ++inliers;
      squared_sum += d2;
    }
  }
  result.correspondences = inliers;
  result.fitness = pair.source_sensor.empty() ? 0.0 : static_cast<double>(inliers) / static_cast<double>(pair.source_sensor.size());
  result.inlier_rmse_m = inliers > 0 ? std::sqrt(squared_sum / static_cast<double>(inliers)) : 0.0;
}

/// Degeneracy and covariance at the final pose from one point-to-plane linearisation there
/// (registration.hpp; its step is not taken): the same measure for every method.
void measure_constraints(const PreparedPair& pair, double max_m, PairwiseRegistrationResult& result) {
  RegistrationOptions one;
  one.max_iterations = 1;
  const RegistrationResult r = register_scan(pair.target_map, pair.source_sensor, result.T_target_source, max_m, max_m / 3.0, one);
  result.degeneracy = r.degeneracy;
  result.degenerate_directions = r.degenerate_directions;
  if (r.characteristic_length_m > 0.0) {
    result.weakest_direction = name_direction(r.weakest_direction, result.T_target_source.so3(), r.characteristic_length_m);
  }
  const std::size_t n = r.correspondences;
  if (n <= 6) return;
  // sigma^2 from the residuals (point-to-plane distances), with 6 degrees of freedom removed.
  const double sigma2 = r.rms_m * r.rms_m * static_cast<double>(n) / static_cast<double>(n - 6);
  const Eigen::LDLT<Matrix6> ldlt(r.hessian);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) return;
  result.covariance = sigma2 * ldlt.solve(Matrix6::Identity());
}

/// The refusal of an unusable input, or empty.
std::string input_problem(const PreparedPair& pair) {
  if (pair.source_sensor.size() < 20) return "the source has " + std::to_string(pair.source_sensor.size()) + " points in range after thinning (20 needed)";
  if (pair.target_sensor.size() < 20) return "the target has " + std::to_string(pair.target_sensor.size()) + " points in range after thinning (20 needed)";
  return "";
}

struct Session {
  PreparedPair pair;
  std::optional<GicpCloud> source_gicp, target_gicp;
};

/// GICP's local covariances come from the denser target-voxel sampling for both clouds: the
/// sparse source alone gives PCL's and Open3D's GICP accuracy (4.85 cm median on the KITTI pairs),
/// the source's 0.5 m sampling 3.28 cm (docs/benchmarks.md). The 0.5 m sampling is nested in the
/// 1 m one, so the support costs no extra points.
Session open_session(const io::PointCloud& source, const io::PointCloud& target, const PairwiseRegistrationOptions& o) {
  Session s{prepare(source, target, o), std::nullopt, std::nullopt};
  if (o.method == PairwiseMethod::kGicp && input_problem(s.pair).empty()) {
    const GicpOptions gicp;
    Points support = voxel_downsample(s.pair.source_cropped, std::min(o.target_voxel_m, o.source_voxel_m));
    s.source_gicp.emplace(s.pair.source_sensor, std::move(support), gicp);
    s.target_gicp.emplace(s.pair.target_sensor, gicp);
  }
  return s;
}

PairwiseRegistrationResult refine_from(const Session& s, const core::SE3& guess, const PairwiseRegistrationOptions& o) {
  PairwiseRegistrationResult result;
  result.method = o.method;
  result.source_points = s.pair.source_sensor.size();
  result.target_points = s.pair.target_sensor.size();
  result.T_target_source = guess;
  result.refusal = input_problem(s.pair);
  if (!result.refusal.empty()) return result;
  const auto [T, converged] = refine(s.pair, s.source_gicp ? &*s.source_gicp : nullptr,
                                     s.target_gicp ? &*s.target_gicp : nullptr, guess, o.max_correspondence_m, o,
                                     &result.iterations);
  result.T_target_source = T;
  result.converged = converged;
  measure_fit(s.pair, o.max_correspondence_m, result);
  if (!converged) result.refusal = "did not converge in " + std::to_string(o.max_iterations) + " iterations";
  return result;
}

bool far_apart(const core::SE3& a, const core::SE3& b, const PairwiseRegistrationOptions& o) {
  const core::SE3 d = a.inverse() * b;
  return d.translation().norm() > o.global_separation_m || d.so3().angle() > o.global_separation_rad;
}

}  // namespace

std::string_view to_string(PairwiseMethod method) {
  return method == PairwiseMethod::kGicp ? "gicp" : "point-to-plane";
}

bool PairwiseRegistrationOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (!(min_range_m >= 0.0)) problems.add("min_range_m must be >= 0");
  if (!(max_range_m > min_range_m)) problems.add("max_range_m must exceed min_range_m");
  problems.require_positive(target_voxel_m, "target_voxel_m");
  problems.require_positive(source_voxel_m, "source_voxel_m");
  problems.require_positive(max_correspondence_m, "max_correspondence_m");
  if (max_iterations < 1) problems.add("max_iterations must be >= 1");
  if (global_yaw_proposals < 1) problems.add("global_yaw_proposals must be >= 1");
  if (!(global_min_fitness >= 0.0 && global_min_fitness <= 1.0)) problems.add("global_min_fitness must be in [0, 1]");
  if (!(global_ambiguity_margin >= 0.0)) problems.add("global_ambiguity_margin must be >= 0");
  return problems.report(why);
}

PairwiseRegistrationResult register_pair(const io::PointCloud& source, const io::PointCloud& target,
                                         const core::SE3& T_target_source_guess, const PairwiseRegistrationOptions& options) {
  const auto start = core::Clock::now();
  const Session session = open_session(source, target, options);
  PairwiseRegistrationResult result = refine_from(session, T_target_source_guess, options);
  if (input_problem(session.pair).empty()) measure_constraints(session.pair, options.max_correspondence_m, result);
  result.time_s = core::seconds_since(start);
  return result;
}

PairwiseRegistrationResult register_pair_globally(const io::PointCloud& source, const io::PointCloud& target,
                                                  const PairwiseRegistrationOptions& options) {
  const auto start = core::Clock::now();
  const Session session = open_session(source, target, options);
  const ScanContextOptions sc = slam_scan_context_options();
  const ScanContextMatch match = compare(make_scan_context(session.pair.source_cropped, sc),
                                         make_scan_context(session.pair.target_cropped, sc), sc);
  PairwiseRegistrationResult best;
  std::vector<GlobalProposal> proposals;
  for (int k = 0; k < options.global_yaw_proposals; ++k) {
    // The descriptor's yaw first, then the rest of the circle evenly: a symmetric place shows
    // as another proposal fitting as well.
    const double yaw = match.yaw_rad + 2.0 * std::numbers::pi * k / options.global_yaw_proposals;
    const core::SE3 guess(core::SO3::exp(Eigen::Vector3d(0.0, 0.0, yaw)), match.t_candidate_query);
    // Coarse to fine, as the loop verification (slam.cpp): point-to-plane at 3x the distance first.
    PairwiseRegistrationOptions coarse = options;
    coarse.method = PairwiseMethod::kPointToPlane;
    coarse.max_correspondence_m = 3.0 * options.max_correspondence_m;
    const PairwiseRegistrationResult rough = refine_from(session, guess, coarse);
    PairwiseRegistrationResult r = refine_from(session, rough.T_target_source, options);
    proposals.push_back({k == 0 ? match.distance : 1.0, yaw, r.T_target_source, r.fitness, r.inlier_rmse_m, r.converged});
    if (k == 0 || r.fitness > best.fitness) best = std::move(r);
  }
  best.proposals = proposals;
  for (const GlobalProposal& p : proposals) {
    if (p.converged && far_apart(p.T_target_source, best.T_target_source, options) &&
        p.fitness > best.fitness - options.global_ambiguity_margin) {
      best.ambiguous = true;
    }
  }
  if (best.refusal.empty() && best.ambiguous) best.refusal = "ambiguous: another yaw fits almost as well elsewhere";
  if (best.refusal.empty() && best.fitness < options.global_min_fitness) {
    best.refusal = "fitness " + std::to_string(best.fitness) + " below " + std::to_string(options.global_min_fitness);
  }
  if (input_problem(session.pair).empty()) measure_constraints(session.pair, options.max_correspondence_m, best);
  best.time_s = core::seconds_since(start);
  return best;
}

nlohmann::json pairwise_registration_json(const PairwiseRegistrationResult& r) {
  nlohmann::json matrix = nlohmann::json::array();
  const Matrix4 T = r.T_target_source.matrix();
  for (int i = 0; i < 4; ++i) matrix.push_back({T(i, 0), T(i, 1), T(i, 2), T(i, 3)});
  const Eigen::Vector3d rpy = r.T_target_source.so3().to_rpy() * (180.0 / std::numbers::pi);
  const Eigen::Vector3d& t = r.T_target_source.translation();
  nlohmann::json covariance = nlohmann::json::array();
  for (int i = 0; i < 6; ++i) {
    covariance.push_back({r.covariance(i, 0), r.covariance(i, 1), r.covariance(i, 2), r.covariance(i, 3),
                          r.covariance(i, 4), r.covariance(i, 5)});
  }
  nlohmann::json proposals = nlohmann::json::array();
  for (const GlobalProposal& p : r.proposals) {
    const Eigen::Vector3d& pt = p.T_target_source.translation();
    proposals.push_back({{"descriptor_distance", p.descriptor_distance}, {"start_yaw_deg", p.yaw_rad * 180.0 / std::numbers::pi},
                         {"translation_m", {pt.x(), pt.y(), pt.z()}}, {"fitness", p.fitness},
                         {"inlier_rmse_m", p.inlier_rmse_m}, {"converged", p.converged}});
  }
  return {{"method", std::string(to_string(r.method))},
          {"accepted", r.accepted()},
          {"refusal", r.refusal},
          {"T_target_source", matrix},
          {"translation_m", {t.x(), t.y(), t.z()}},
          {"roll_pitch_yaw_deg", {rpy.x(), rpy.y(), rpy.z()}},
          {"converged", r.converged},
          {"iterations", r.iterations},
          {"source_points", r.source_points},
          {"target_points", r.target_points},
          {"correspondences", r.correspondences},
          {"fitness", r.fitness},
          {"inlier_rmse_m", r.inlier_rmse_m},
          {"degeneracy", r.degeneracy},
          {"degenerate_directions", r.degenerate_directions},
          {"weakest_direction", r.weakest_direction},
          {"covariance", covariance},
          {"global_proposals", proposals},
          {"ambiguous", r.ambiguous},
          {"time_s", r.time_s}};
}

}  // namespace cairn::lidar3d
