#pragma once
/// \file
/// Generalized-ICP (Segal, Haehnel & Thrun, "Generalized-ICP", RSS 2009), the plane-to-plane
/// variant, with the data layout and solver of small_gicp (Koide, "small_gicp: Efficient and
/// parallel algorithms for point cloud registration", JOSS 2024).
///
/// Each point a_i of the source and b_i of the target carries a covariance C_i from its k nearest
/// neighbours, regularised to a plane (Sec. III-B): the eigenvalues of the neighbourhood's
/// covariance are replaced by (1, 1, eps), eps along the normal, so that a point may slide within
/// its local plane but not across it. Registration minimises the MLE cost of Sec. III-A, eq. (2),
///   T_target_source = argmin_T  sum_i d_i^T (C_i^B + R C_i^A R^T)^{-1} d_i,   d_i = b_i - T a_i,
/// pairing every moved source point with its nearest target point within max_correspondence_m,
/// re-found at every Gauss-Newton iteration, with the right perturbation T <- T exp(delta),
/// delta = (rho, phi) translation first as core::SE3.
///
/// GicpCloud is built once per cloud (k-d trees; covariances on first use) and can serve as target
/// or as source in any number of registrations, e.g. a scan as source now and as target next.
///
/// Measured on the 109 consecutive KITTI 00 key-frame pairs as bench/registration_vs_peers.cpp
/// prepares them (target at 0.5 m, source at 1 m, 1 m correspondences, constant-velocity guess),
/// median / mean error against the GNSS/INS reference, 10 neighbours:
///  - source covariances from its scan at 0.5 m (a support cloud), target's from itself:
///    3.28 / 4.27 cm, 0.105 / 0.123 deg, 0.8 times register_scan's time (same run, 2 threads,
///    subsampling not timed);
///  - both from their scans at 0.25 m: 3.39 / 4.17 cm, 0.098 / 0.122 deg, 1.2 times;
///  - both from the 0.5 m / 1 m clouds themselves: 3.66 / 4.79 cm, 0.114 / 0.140 deg, 0.7 times;
///    with 20 neighbours 4.85 / 5.93 cm (as PCL's and Open3D's GICP on those clouds), since 20
///    neighbours 1 m apart span several metres;
///  - register_scan's point-to-plane: 4.13 / 4.67 cm, 0.152 / 0.170 deg; Open3D's point-to-plane
///    3.94 / 4.63 cm, 0.116 / 0.142 deg (docs/benchmarks.md).

#include <Eigen/Core>
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/types.hpp"

namespace cairn::lidar3d {

struct GicpOptions {
  /// Neighbours (including the point itself) whose covariance gives a point's covariance, >= 3.
  /// Segal et al. use 20 (Sec. III-B), small_gicp 10 (on clouds subsampled at 0.25 m). On the
  /// KITTI pairs (see above) 10 and 20 do equally well with 0.25 m support clouds (3.39 / 3.32 cm,
  /// 0.098 / 0.093 deg median) and 10 costs less; without support 10 gets 3.66 cm, 20 4.85 cm.
  int covariance_neighbours = 10;
  /// Eigenvalue along the normal of the regularised covariances, relative to 1 in the plane, in
  /// (0, 1]. fast_gicp and small_gicp use 1e-3.
  double covariance_epsilon = 1e-3;
  /// A moved source point pairs with its nearest target point only if it lies within this
  /// distance, metres (> 0).
  double max_correspondence_m = 1.0;
  /// Gauss-Newton iterations at most (>= 1).
  int max_iterations = 64;
  /// Converged when a step moves by less than both tolerances: |rho| < translation_tolerance_m
  /// and |phi| < rotation_tolerance_rad (> 0 each).
  double translation_tolerance_m = 1e-4;
  double rotation_tolerance_rad = 1e-4;
  /// Coarse to fine over the source's points (>= 1; 1: off): the first iterations use every
  /// `sparse_stride`-th source point only, until a step falls below `sparse_tolerance_factor`
  /// times both tolerances (or closes a cycle); the iterations then go on with every point until
  /// they converge as above, so the result and its correspondences, fitness and Hessian are those
  /// of all points. Iterations of both kinds count towards max_iterations; too few
  /// correspondences or a singular system among the sparse points switch to all points at once.
  /// Most of an iteration's time is the nearest-neighbour search of each source point, and the
  /// first iterations from a guess off by decimetres need only a good direction: the idea of a
  /// coarse-to-fine pyramid, here over the source's points alone (the target and its covariances
  /// stay as they are).
  int sparse_stride = 1;
  double sparse_tolerance_factor = 10.0;

  /// True when every field is in range; otherwise false with every problem, joined by "; ".
  bool is_valid(std::string* why) const;
};

/// Points (in the cloud's own frame, finite) with one regularised covariance each and a k-d tree
/// for nearest-neighbour queries.
///
/// A point's covariance is computed when it is first asked for, then kept: a registration needs
/// those of every source point but only of the target points that pair with one (29 % of a KITTI
/// target at 0.5 m paired with a source at 1 m), and the k nearest-neighbour search behind each
/// covariance is most of GICP's time. Computing one is thread-safe (a point's state is claimed
/// atomically; a thread that loses the race uses its own copy of the same value), so one cloud may
/// serve concurrent registrations, and the values, hence the results, do not depend on who
/// computed them.
class GicpCloud {
 public:
  /// Covariances from each point's covariance_neighbours nearest points of `points_cloud` itself
  /// (all of them when there are fewer). Throws std::invalid_argument for invalid options or a
  /// non-finite point. Empty is allowed (registration then finds no correspondences).
  explicit GicpCloud(std::vector<Eigen::Vector3d> points_cloud, const GicpOptions& options = {});
  /// Covariances from each point's nearest neighbours in `support_cloud` (kept by the cloud), a
  /// denser sampling of the same surfaces in the same frame, e.g. the scan subsampled at 0.25 m
  /// when the points are at 1 m, so that a sparse cloud still gets the local planes of a small
  /// neighbourhood. Correspondences are searched among `points_cloud` only. Same exceptions, also
  /// for a non-finite support point; an empty support means the points themselves.
  GicpCloud(std::vector<Eigen::Vector3d> points_cloud, std::vector<Eigen::Vector3d> support_cloud,
            const GicpOptions& options = {});
  ~GicpCloud();
  GicpCloud(GicpCloud&&) noexcept;
  GicpCloud& operator=(GicpCloud&&) noexcept;

  std::size_t size() const { return points_.size(); }
  bool empty() const { return points_.empty(); }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  /// Point `index`'s covariance (index < size()): symmetric positive definite with eigenvalues
  /// (covariance_epsilon, 1, 1), the first along the normal of its neighbourhood.
  Eigen::Matrix3d covariance(std::size_t index) const;
  /// Computes every point's covariance now (in parallel on the calling thread's TBB arena)
  /// rather than on first use: for a target that serves many registrations, or to time them.
  void compute_covariances() const;

  /// The index of the point nearest to `query_cloud` if its squared distance is at most
  /// `max_squared_distance_m2`, with that squared distance; false otherwise (and for an empty
  /// cloud or a non-finite query).
  bool nearest(const Eigen::Vector3d& query_cloud, double max_squared_distance_m2, std::size_t* index,
               double* squared_distance_m2) const;

 private:
  struct Search;
  std::vector<Eigen::Vector3d> points_;
  std::unique_ptr<Search> search_;  // trees and covariances; points into points_'s buffer, which a move keeps
};

struct GicpResult {
  core::SE3 T_target_source;
  int iterations = 0;
  /// The last step was below both tolerances, or returned to within them of a pose visited in the
  /// last 8 steps (correspondences switching back and forth; the result is then the mean of that
  /// cycle's poses). False: the iteration limit was reached, fewer than 6 correspondences were
  /// found, or the system was singular.
  bool converged = false;
  /// Source points with a target point within max_correspondence_m, at the last linearisation
  /// (the pose before the last step, which converged is below the tolerances); of the sparse
  /// points only if max_iterations ended the iterations in the sparse phase.
  std::size_t correspondences = 0;
  std::size_t source_points = 0;
  /// correspondences over the source points that linearisation paired (0 for an empty source).
  double fitness = 0.0;
  /// Root mean square Euclidean distance |b_i - T a_i| of the correspondences, metres.
  double inlier_rmse_m = 0.0;
  /// sum_i d_i^T (C_i^B + R C_i^A R^T)^{-1} d_i over the correspondences (eq. 2), at the last
  /// linearisation.
  double cost = 0.0;
  /// J^T W J of eq. (2) at the last linearisation, tangent translation first, right perturbation
  /// (T exp(delta)). W uses the unit-free regularised covariances, so H^{-1} is the covariance of
  /// T only up to a scale, e.g. cost / (correspondences - 6) as the residuals' variance; its
  /// smallest eigenvalues name the weakly constrained directions.
  Matrix6 hessian = Matrix6::Zero();
};

/// Registers `source` to `target` from `T_target_source_guess` (see the file comment). Throws
/// std::invalid_argument for invalid options or a non-finite guess; empty or non-overlapping
/// clouds give converged = false. Sums are reduced over fixed chunks in a fixed order on the
/// calling thread's TBB arena, so the result does not depend on the number of threads.
GicpResult register_gicp(const GicpCloud& target, const GicpCloud& source, const core::SE3& T_target_source_guess,
                         const GicpOptions& options = {});

}  // namespace cairn::lidar3d
