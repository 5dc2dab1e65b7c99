#include "cairn/lidar3d/gicp.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <nanoflann.hpp>
#include <stdexcept>

#include "cairn/core/problems.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::lidar3d {

bool GicpOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (covariance_neighbours < 3) problems.add("covariance_neighbours must be >= 3");
  if (!(covariance_epsilon > 0.0 && covariance_epsilon <= 1.0)) problems.add("covariance_epsilon must be in (0, 1]");
  problems.require_positive(max_correspondence_m, "max_correspondence_m");
  if (max_iterations < 1) problems.add("max_iterations must be >= 1");
  problems.require_positive(translation_tolerance_m, "translation_tolerance_m");
  problems.require_positive(rotation_tolerance_rad, "rotation_tolerance_rad");
  if (sparse_stride < 1) problems.add("sparse_stride must be >= 1");
  if (!(sparse_tolerance_factor >= 1.0 && std::isfinite(sparse_tolerance_factor))) {
    problems.add("sparse_tolerance_factor must be finite and >= 1");
  }
  return problems.report(why);
}

namespace {

// nanoflann's dataset interface over points it does not own. It holds the vector's buffer, not
// the vector, so that moving a GicpCloud (which moves the buffer) keeps the tree valid.
struct PointsAdaptor {
  const Eigen::Vector3d* points = nullptr;
  std::size_t count = 0;
  std::size_t kdtree_get_point_count() const { return count; }
  double kdtree_get_pt(std::size_t index, std::size_t dimension) const {
    return points[index][static_cast<Eigen::Index>(dimension)];
  }
  template <class BoundingBox>
  bool kdtree_get_bbox(BoundingBox& /*box*/) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointsAdaptor>,
                                                   PointsAdaptor, 3, std::size_t>;

// The nearest point within a radius: starting the search with the radius as the worst distance
// prunes every branch farther away, so a point with no partner costs little.
struct NearestWithin {
  double worst;
  std::size_t index = 0;
  bool found = false;
  double worstDist() const { return worst; }
  bool addPoint(double squared_distance, std::size_t i) {
    if (squared_distance <= worst) {
      worst = squared_distance;
      index = i;
      found = true;
    }
    return true;
  }
  bool full() const { return found; }
};

void require_finite(const std::vector<Eigen::Vector3d>& points, const char* what) {
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite()) {
      throw std::invalid_argument(std::string("GicpCloud: ") + what + " point " + std::to_string(i) +
                                  " is not finite");
    }
  }
}

void require_valid(const GicpOptions& options) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid GICP options: " + why);
}

// Leaf size 20 as small_gicp's k-d tree: measured 10 % faster than nanoflann's default 10 for the
// 20-neighbour queries on a KITTI scan, the same for the nearest-neighbour ones.
std::unique_ptr<KdTree> build_tree(PointsAdaptor& adaptor) {
  return std::make_unique<KdTree>(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(20));
}

// The plane-to-plane covariance of Segal et al. 2009, Sec. III-B: the neighbourhood's sample
// covariance with its eigenvalues replaced by (1, 1, eps), eps along the eigenvector of the
// smallest one (the normal). The neighbourhood is centred first so that far points (tens of
// metres from the origin) lose no precision.
Eigen::Matrix3d plane_covariance(const std::vector<Eigen::Vector3d>& support, const std::size_t* neighbours,
                                 std::size_t count, double epsilon) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t j = 0; j < count; ++j) mean += support[neighbours[j]];
  mean /= static_cast<double>(std::max<std::size_t>(count, 1));
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (std::size_t j = 0; j < count; ++j) {
    const Eigen::Vector3d centred = support[neighbours[j]] - mean;
    scatter.noalias() += centred * centred.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(scatter);  // eigenvalues ascending; the scale of scatter does not matter
  const Eigen::Matrix3d& U = eigen.eigenvectors();
  return U * Eigen::Vector3d(epsilon, 1.0, 1.0).asDiagonal() * U.transpose();
}

enum : std::uint8_t { kNotComputed = 0, kWriting = 1, kReady = 2 };

}  // namespace

// Lives on the heap so that the trees' pointers into points_ and support stay valid when the
// cloud moves; the covariance cache is written from const methods under the atomic states.
struct GicpCloud::Search {
  PointsAdaptor adaptor;
  std::unique_ptr<KdTree> index;
  std::vector<Eigen::Vector3d> support;  // empty: the points themselves
  PointsAdaptor support_adaptor;
  std::unique_ptr<KdTree> support_index;
  std::size_t neighbours = 0;
  double epsilon = 0.0;
  std::vector<Eigen::Matrix3d> covariances;
  std::unique_ptr<std::atomic<std::uint8_t>[]> states;
};

GicpCloud::~GicpCloud() = default;
GicpCloud::GicpCloud(GicpCloud&&) noexcept = default;
GicpCloud& GicpCloud::operator=(GicpCloud&&) noexcept = default;

GicpCloud::GicpCloud(std::vector<Eigen::Vector3d> points_cloud, const GicpOptions& options)
    : GicpCloud(std::move(points_cloud), {}, options) {}

// GCC 12 reports a null dereference inside nanoflann's std::vector::resize once it is inlined
// (as in scan_context.cpp: a false positive); the pragma scopes the exemption to this function.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
GicpCloud::GicpCloud(std::vector<Eigen::Vector3d> points_cloud, std::vector<Eigen::Vector3d> support_cloud,
                     const GicpOptions& options)
    : points_(std::move(points_cloud)), search_(std::make_unique<Search>()) {
  require_valid(options);
  require_finite(points_, "cloud");
  require_finite(support_cloud, "support");
  Search& s = *search_;
  s.adaptor = PointsAdaptor{points_.data(), points_.size()};
  s.index = build_tree(s.adaptor);
  if (!support_cloud.empty()) {
    s.support = std::move(support_cloud);
    s.support_adaptor = PointsAdaptor{s.support.data(), s.support.size()};
    s.support_index = build_tree(s.support_adaptor);
  }
  const std::size_t support_size = s.support.empty() ? points_.size() : s.support.size();
  s.neighbours = std::min(static_cast<std::size_t>(options.covariance_neighbours), support_size);
  s.epsilon = options.covariance_epsilon;
  s.covariances.resize(points_.size());
  s.states = std::make_unique<std::atomic<std::uint8_t>[]>(points_.size());  // value-initialised: 0
}

Eigen::Matrix3d GicpCloud::covariance(std::size_t index) const {
  Search& s = *search_;
  std::atomic<std::uint8_t>& state = s.states[index];
  if (state.load(std::memory_order_acquire) == kReady) return s.covariances[index];
  const bool own = s.support.empty();
  // On the stack for the usual neighbourhoods: this runs once per point of every registration.
  constexpr std::size_t kStack = 32;
  std::array<std::size_t, kStack> stack_neighbours;
  std::array<double, kStack> stack_distances;
  std::vector<std::size_t> heap_neighbours(s.neighbours > kStack ? s.neighbours : 0);
  std::vector<double> heap_distances(heap_neighbours.size());
  std::size_t* neighbours = heap_neighbours.empty() ? stack_neighbours.data() : heap_neighbours.data();
  double* squared_distances = heap_distances.empty() ? stack_distances.data() : heap_distances.data();
  const std::size_t found = (own ? *s.index : *s.support_index)
                                .knnSearch(points_[index].data(), s.neighbours, neighbours, squared_distances);
  const Eigen::Matrix3d C = plane_covariance(own ? points_ : s.support, neighbours, found, s.epsilon);
  // Only the thread that claims the state writes; the others keep their equal copy.
  std::uint8_t expected = kNotComputed;
  if (state.compare_exchange_strong(expected, kWriting, std::memory_order_acq_rel)) {
    s.covariances[index] = C;
    state.store(kReady, std::memory_order_release);
  }
  return C;
}
#pragma GCC diagnostic pop

void GicpCloud::compute_covariances() const {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points_.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) covariance(i);
  });
}

bool GicpCloud::nearest(const Eigen::Vector3d& query_cloud, double max_squared_distance_m2, std::size_t* index,
                        double* squared_distance_m2) const {
  if (points_.empty() || !query_cloud.allFinite()) return false;
  NearestWithin result{max_squared_distance_m2};
  search_->index->findNeighbors(result, query_cloud.data(), nanoflann::SearchParams());
  if (!result.found) return false;
  *index = result.index;
  *squared_distance_m2 = result.worst;
  return true;
}

namespace {

// The normal equations of eq. (2) linearised at one pose, summed over the correspondences.
struct LinearSystem {
  Matrix6 H = Matrix6::Zero();
  Vector6 g = Vector6::Zero();
  double cost = 0.0;
  double squared_distance_sum = 0.0;
  std::size_t correspondences = 0;

  LinearSystem& operator+=(const LinearSystem& other) {
    H += other.H;
    g += other.g;
    cost += other.cost;
    squared_distance_sum += other.squared_distance_sum;
    correspondences += other.correspondences;
    return *this;
  }
};

// One correspondence's share. With d = b - T a and the right perturbation
// T exp(delta) a ~ T a + R (rho + phi x a), the Jacobian of d is J = [-R, R [a]x];
// W = (C^B + R C^A R^T)^{-1} is held fixed within the step (Segal et al. Sec. III-A; small_gicp's
// GICPFactor), so H += J^T W J, g += J^T W d and the Gauss-Newton step solves H delta = -g.
void add_correspondence(const Eigen::Matrix3d& R, const Eigen::Vector3d& a, const Eigen::Matrix3d& C_a,
                        const Eigen::Vector3d& d, const Eigen::Matrix3d& C_b, LinearSystem& system) {
  const Eigen::Matrix3d combined = C_b + R * C_a * R.transpose();
  const Eigen::Matrix3d W = combined.inverse();  // closed form for 3x3; combined is SPD
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>() = -R;
  J.rightCols<3>() = R * core::SO3::hat(a);
  const Eigen::Matrix<double, 3, 6> WJ = W * J;
  const Eigen::Vector3d Wd = W * d;
  system.H.noalias() += J.transpose() * WJ;
  system.g.noalias() += J.transpose() * Wd;
  system.cost += d.dot(Wd);
  system.squared_distance_sum += d.squaredNorm();
  ++system.correspondences;
}

// Pairs every `stride`-th source point, moved by T_target_source, with its nearest target point
// within the distance and sums the normal equations, in fixed chunks reduced in a fixed tree
// (parallel_deterministic_reduce with its simple_partitioner): the same sums on any number of
// threads, as register_scan.
LinearSystem linearise(const GicpCloud& target, const GicpCloud& source, const core::SE3& T_target_source,
                       double max_squared_distance, std::size_t stride) {
  constexpr std::size_t kGrain = 256;
  const Eigen::Matrix3d R = T_target_source.rotation_matrix();
  const Eigen::Vector3d t = T_target_source.translation();
  const std::vector<Eigen::Vector3d>& a = source.points();
  const std::size_t used = (a.size() + stride - 1) / stride;
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, used, std::max<std::size_t>(1, kGrain / stride)), LinearSystem{},
      [&](const tbb::blocked_range<std::size_t>& range, LinearSystem system) {
        for (std::size_t k = range.begin(); k != range.end(); ++k) {
          const std::size_t i = k * stride;
          const Eigen::Vector3d moved = R * a[i] + t;
          std::size_t j = 0;
          double squared_distance = 0.0;
          if (!target.nearest(moved, max_squared_distance, &j, &squared_distance)) continue;
          add_correspondence(R, a[i], source.covariance(i), target.points()[j] - moved, target.covariance(j),
                             system);
        }
        return system;
      },
      [](LinearSystem left, const LinearSystem& right) { return left += right; });
}

bool below(const Vector6& delta, const GicpOptions& options, double factor = 1.0) {
  return delta.head<3>().norm() < factor * options.translation_tolerance_m &&
         delta.tail<3>().norm() < factor * options.rotation_tolerance_rad;
}

// The last poses visited. Nearest-neighbour pairs that switch back and forth make the iteration
// cycle through a few poses a fraction of a millimetre apart (measured on the KITTI pairs:
// cycles of 3 and 6 steps of 0.1-0.7 mm), which never meets the step tolerances. A step that
// lands on a pose visited within the last kLength steps closes such a cycle; the result is then
// the mean of the cycle's poses (for a two-cycle: half-way, as register_scan).
class PoseHistory {
 public:
  static constexpr std::size_t kLength = 8;
  void push(const core::SE3& T) {
    poses_[next_ % kLength] = T;
    ++next_;
  }
  /// The mean of the poses since one within the tolerances of T_new, if there is one.
  bool closes_cycle(const core::SE3& T_new, const GicpOptions& options, core::SE3* mean) const {
    const std::size_t stored = std::min(next_, kLength);
    for (std::size_t back = 2; back <= stored; ++back) {
      if (!below((at(back).inverse() * T_new).log(), options)) continue;
      const core::SE3& T_last = at(1);
      Vector6 sum = Vector6::Zero();
      for (std::size_t j = 1; j <= back; ++j) sum += (T_last.inverse() * at(j)).log();
      *mean = T_last * core::SE3::exp(sum / static_cast<double>(back));
      return true;
    }
    return false;
  }

 private:
  const core::SE3& at(std::size_t back) const { return poses_[(next_ - back) % kLength]; }
  std::array<core::SE3, kLength> poses_{};
  std::size_t next_ = 0;
};

// `used`: the source points this linearisation paired (all of them but in the sparse phase).
void record(const LinearSystem& system, int iteration, std::size_t used, GicpResult& result) {
  result.iterations = iteration + 1;
  result.correspondences = system.correspondences;
  result.fitness = used > 0 ? static_cast<double>(system.correspondences) / static_cast<double>(used) : 0.0;
  result.inlier_rmse_m = system.correspondences > 0
                             ? std::sqrt(system.squared_distance_sum / static_cast<double>(system.correspondences))
                             : 0.0;
  result.cost = system.cost;
  result.hessian = system.H;
}

}  // namespace

GicpResult register_gicp(const GicpCloud& target, const GicpCloud& source, const core::SE3& T_target_source_guess,
                         const GicpOptions& options) {
  require_valid(options);
  if (!T_target_source_guess.matrix().allFinite()) {
    throw std::invalid_argument("register_gicp: the initial guess T_target_source is not finite");
  }
  GicpResult result;
  result.T_target_source = T_target_source_guess;
  result.source_points = source.size();
  const double max_squared = options.max_correspondence_m * options.max_correspondence_m;
  PoseHistory history;
  // The sparse phase (options.sparse_stride) ends at its first small step; its steps are not
  // recorded as the result's (record() runs again on all points).
  std::size_t stride = static_cast<std::size_t>(options.sparse_stride);
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const LinearSystem system = linearise(target, source, result.T_target_source, max_squared, stride);
    record(system, iteration, (source.size() + stride - 1) / stride, result);
    if (system.correspondences < 6) {  // six unknowns
      if (stride == 1) break;
      stride = 1;  // too few among the sparse points: all of them decide
      continue;
    }
    const Vector6 delta = system.H.ldlt().solve(-system.g);
    if (!delta.allFinite()) {
      if (stride == 1) break;
      stride = 1;  // singular over the sparse points: all of them decide
      continue;
    }
    history.push(result.T_target_source);
    const core::SE3 T_next = result.T_target_source * core::SE3::exp(delta);
    if (stride > 1) {
      core::SE3 T_cycle;
      if (below(delta, options, options.sparse_tolerance_factor) || history.closes_cycle(T_next, options, &T_cycle)) {
        stride = 1;
        history = PoseHistory{};
      }
      result.T_target_source = T_next;
      continue;
    }
    if (below(delta, options)) {
      result.T_target_source = T_next;
      result.converged = true;
      break;
    }
    if (history.closes_cycle(T_next, options, &result.T_target_source)) {
      result.converged = true;
      break;
    }
    result.T_target_source = T_next;
  }
  return result;
}

}  // namespace cairn::lidar3d
