#pragma once
/// \file
/// Registration of one point cloud onto another, from a guess or from nothing (`cairn register`,
/// issue 42): the source and target are cropped and thinned as the odometry's scans are
/// (voxel_downsample), then
///   * from a guess: point-to-plane ICP on a voxel-hash map of the target (registration.hpp, as
///     KISS-ICP and the odometry do) or Generalized-ICP (gicp.hpp; Segal, Haehnel & Thrun, RSS
///     2009) on the two clouds' local covariances;
///   * from nothing (`global`): Scan Context (Kim & Kim, IROS 2018) compares the two clouds'
///     polar descriptors and proposes yaws (the best column shifts); each is refined by the chosen
///     registration, and the result is accepted only when one proposal fits clearly best. Two
///     proposals that fit almost as well at different places (a corridor, a symmetric room) are
///     refused as ambiguous rather than guessed between.
/// The result states how well it fits (fitness: the share of source points with a target point
/// within the correspondence distance; inlier RMSE), how well the geometry constrains each
/// direction (the degeneracy of registration.hpp, with the weakest direction named) and a
/// covariance: sigma^2 H^-1 of the last Gauss-Newton system, sigma^2 from the residuals
/// (an approximation: it assumes independent residuals and ignores the robust weights).

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/point_cloud.hpp"

namespace cairn::lidar3d {

enum class PairwiseMethod {
  kPointToPlane,  ///< ICP on the target's voxel-hash map (the odometry's)
  kGicp,          ///< Generalized-ICP
};

std::string_view to_string(PairwiseMethod method);

struct PairwiseRegistrationOptions {
  PairwiseMethod method = PairwiseMethod::kGicp;
  double min_range_m = 0.0;        ///< points nearer the sensor are dropped (>= 0)
  double max_range_m = 100.0;      ///< points farther are dropped (> min_range_m)
  double target_voxel_m = 0.5;     ///< one target point per voxel (> 0)
  double source_voxel_m = 1.0;     ///< one source point per voxel (> 0)
  double max_correspondence_m = 1.0;  ///< (> 0)
  int max_iterations = 100;        ///< (>= 1)
  /// Global: the yaws Scan Context proposes (best column shifts first), each refined.
  int global_yaw_proposals = 3;
  /// Global: accepted only with at least this fitness ...
  double global_min_fitness = 0.5;
  /// ... and when every proposal that converged elsewhere (farther than the separation below)
  /// fits worse by at least this margin.
  double global_ambiguity_margin = 0.05;
  double global_separation_m = 2.0;
  double global_separation_rad = 0.2;

  bool is_valid(std::string* why) const;
};

/// One refined proposal of a global registration.
struct GlobalProposal {
  double descriptor_distance = 1.0;  ///< Scan Context's D in [0, 1]
  double yaw_rad = 0.0;              ///< the starting yaw
  core::SE3 T_target_source;         ///< after refinement
  double fitness = 0.0;
  double inlier_rmse_m = 0.0;
  bool converged = false;
};

struct PairwiseRegistrationResult {
  core::SE3 T_target_source;
  PairwiseMethod method = PairwiseMethod::kGicp;
  bool converged = false;
  int iterations = 0;
  std::size_t source_points = 0;   ///< after cropping and thinning
  std::size_t target_points = 0;
  std::size_t correspondences = 0;
  double fitness = 0.0;            ///< correspondences / source points
  double inlier_rmse_m = 0.0;
  /// The smallest eigenvalue of the normalised point-to-plane information (registration.hpp's
  /// degeneracy; 0 when not computed) and the weakest translation direction, named.
  double degeneracy = 0.0;
  int degenerate_directions = 0;
  std::string weakest_direction;
  /// Covariance of the left perturbation T <- exp(delta) T, delta = (translation, rotation), in
  /// the target frame: sigma^2 H^-1; zero when H is singular.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
  /// Global registrations: every refined proposal, and the outcome.
  std::vector<GlobalProposal> proposals;
  bool ambiguous = false;
  /// Empty when accepted; otherwise why the registration is not trusted.
  std::string refusal;
  double time_s = 0.0;

  bool accepted() const { return converged && refusal.empty(); }
};

/// Registers `source` onto `target` from `T_target_source_guess`. Precondition:
/// options.is_valid(). Never throws for degenerate input: an empty or tiny cloud gives a result
/// that is not converged, with the reason in `refusal`.
PairwiseRegistrationResult register_pair(const io::PointCloud& source, const io::PointCloud& target,
                                         const core::SE3& T_target_source_guess,
                                         const PairwiseRegistrationOptions& options = {});

/// Registers with no guess: Scan Context's yaw proposals, each refined (see the file comment).
PairwiseRegistrationResult register_pair_globally(const io::PointCloud& source, const io::PointCloud& target,
                                                  const PairwiseRegistrationOptions& options = {});

/// The result as `cairn register --json` writes it: the transform (4 x 4, row by row, and as
/// translation + roll/pitch/yaw in degrees), fit, degeneracy, covariance, proposals, refusal.
nlohmann::json pairwise_registration_json(const PairwiseRegistrationResult& result);

}  // namespace cairn::lidar3d
