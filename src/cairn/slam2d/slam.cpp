#include "cairn/slam2d/slam.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <mutex>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cairn/backend/keyframe_graph.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/slam2d/place_search.hpp"

#include <Eigen/Eigenvalues>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

namespace cairn::slam2d {
namespace {

using core::Clock;
using core::seconds_since;

struct Keyframe {
  core::Timestamp time;
  core::SE2 T_local_laser;   ///< front-end pose (never corrected)
  core::SE2 T_world_laser;   ///< global estimate
  std::vector<Eigen::Vector2d> hits;
  std::vector<Eigen::Vector2d> misses;
  std::vector<Eigen::Vector2d> matching;
  double path_length_m = 0.0;  ///< travelled before this keyframe (front end)
  std::size_t scan = 0;
  int segment = 0;
};

struct Submap {
  int anchor = 0;               ///< first keyframe
  std::vector<int> keyframes;
  bool finished = false;
  bool building = false;        ///< full, its build queued or running (installed at BuildJob::install_at)
  /// While active: the grid of its first `grid_keyframes` keyframes' rays, filled in the
  /// background as keyframes come (Slam2d::Impl::start_ray_insertions; complete once they are
  /// waited for), so a build only adds the last keyframes. Null after the front end moved or
  /// emptied keyframes: the build then starts over from the keyframes.
  std::unique_ptr<ProbabilityGrid> grid;
  int grid_keyframes = 0;
  std::unique_ptr<PrecomputationGridStack> stack;
  std::unique_ptr<PointMap> points;  ///< in the anchor's frame
  Eigen::Vector2d centre_anchor = Eigen::Vector2d::Zero();
  Eigen::Vector2d lower_anchor = Eigen::Vector2d::Zero();  ///< observed extent of its grid
  Eigen::Vector2d upper_anchor = Eigen::Vector2d::Zero();
  int segment = 0;
  /// Finished without a single point (a segment closed before its submap saw anything):
  /// never searched.
  bool empty = false;
};

/// A verified match across two groups of segments, waiting for confirmation. `delta` moves
/// group b's world estimates into group a's frame: delta = T_world_anchor T_anchor_keyframe
/// T_world_keyframe^-1.
struct PendingMerge {
  int id = 0;
  int group_a = 0;
  int group_b = 0;
  core::SE2 delta;
  std::vector<int> candidates;  ///< the agreeing verified matches (support)
  std::vector<int> keyframes;
  int misses = 0;  ///< searches where it placed a keyframe that found nothing agreeing there
  int misses_in_a_row = 0;
};

/// One search planned for a keyframe.
struct PlannedSearch {
  int submap = 0;
  bool merge = false;
  bool global = false;
  core::SE2 T_world_guess;  ///< where the keyframe is believed to be (windowed searches)
  int hypothesis = -1;      ///< the pending merge (id) whose placement this search tests
};

struct ScanRecord {
  core::Timestamp time;
  int keyframe = 0;          ///< the keyframe at or before the scan
  core::SE2 T_keyframe_laser;
  Health health = Health::kOk;
  double inlier_fraction = 0.0;
  double degeneracy = 0.0;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  bool keyframe_itself = false;
  int segment = 0;
};

/// What the stages of one Slam2d::add_scan share: the scan, its points, its front-end pose as it
/// is worked out, the verdict on its health, and its record.
struct ScanWork {
  ScanWork(const io::LaserScan& laser_scan, ScanPoints scan_points, std::size_t scan_index)
      : scan(laser_scan), points(std::move(scan_points)), index(scan_index), T_local_laser(laser_scan.T_odom_laser),
        predicted(laser_scan.T_odom_laser) {
    record.time = laser_scan.time;
  }

  const io::LaserScan& scan;
  ScanPoints points;
  std::size_t index = 0;  ///< of the scan (into Impl::scans)
  ScanRecord record;
  core::SE2 T_local_laser;  ///< front-end pose: the prediction, then the match
  core::SE2 predicted;      ///< odometry prediction
  Eigen::Matrix3d match_hessian = Eigen::Matrix3d::Zero();  ///< scan term of the accepted match
  bool matched = false;
  bool restarted = false;  ///< the accepted match came from an ICP restart away from the prediction
  std::string relocalised_reason;  ///< set when the scan was relocalised in the recent map
  bool too_few_returns = false;
  /// A failed match that contradicts nothing the local map holds (judge_failed_match).
  bool new_space = false;
  double rays_through_map = 0.0;  ///< of the failed match at the prediction (rays_through_map)
  Eigen::Vector2d degenerate_direction = Eigen::Vector2d::Zero();  ///< of the match (IcpResult), local frame
  Health next = Health::kOk;
  std::string reason;
  /// Neither matched nor failed: too few returns to match, or only new structure. The pose follows
  /// the odometry, the points enter the map, and the scan neither counts towards nor judges being
  /// lost. (too_few_returns is set by assess_health.)
  bool odometry_only() const { return too_few_returns || new_space; }
  bool start_segment = false;  ///< this scan (re)seeds the current segment's map
  SegmentInfo* segment_info = nullptr;  ///< the current segment's (after the health stages)
  bool new_keyframe = false;
};

struct Edge {
  int from = 0;
  int to = 0;
  core::SE2 T_from_to;
  bool loop = false;
  int candidate = -1;  ///< index into summary.candidates
  /// Spans a scan whose match failed: odometry alone, possibly a slip or a kidnapping; kept only
  /// to connect the graph (segment_link_*_sigma) so a loop closure or merge can move it freely.
  bool weak = false;
  /// Covariance of the keyframe's match in the `from` frame (x, y, theta); added to the
  /// odometry sigmas when edge_covariance_from_matcher is set.
  Eigen::Matrix3d match_covariance = Eigen::Matrix3d::Zero();
};

/// Inserts the rays of scans taken at T_grid_laser[i] (hits[i] ending in a hit, misses[i] without
/// a return) into `grid`, after reserving the box that holds every ray: the grid is allocated once
/// instead of doubling as rays leave it (each doubling copies the grid and, on this project's
/// VM, faults its new pages in: the map of MIT CSAIL's 1,683 keyframes spent 0.2 s there). Cell
/// values do not depend on the grid's extent (probability_grid.hpp). `margin_m` widens the box on
/// every side.
void insert_rays(ProbabilityGrid& grid, const std::vector<core::SE2>& T_grid_laser,
                 const std::vector<const std::vector<Eigen::Vector2d>*>& hits,
                 const std::vector<const std::vector<Eigen::Vector2d>*>& misses, double margin_m) {
  Eigen::Vector2d lower = Eigen::Vector2d::Constant(1e300), upper = Eigen::Vector2d::Constant(-1e300);
  for (std::size_t i = 0; i < T_grid_laser.size(); ++i) {
    lower = lower.cwiseMin(T_grid_laser[i].translation());
    upper = upper.cwiseMax(T_grid_laser[i].translation());
    for (const auto* list : {hits[i], misses[i]}) {
      for (const auto& p : *list) {
        const Eigen::Vector2d q = T_grid_laser[i] * p;
        lower = lower.cwiseMin(q);
        upper = upper.cwiseMax(q);
      }
    }
  }
  if (lower.allFinite() && upper.allFinite()) {
    grid.reserve(lower - Eigen::Vector2d::Constant(margin_m), upper + Eigen::Vector2d::Constant(margin_m));
  }
  std::vector<Eigen::Vector2d> all;
  std::vector<bool> hit;
  for (std::size_t i = 0; i < T_grid_laser.size(); ++i) {
    all.assign(hits[i]->begin(), hits[i]->end());
    hit.assign(all.size(), true);
    all.insert(all.end(), misses[i]->begin(), misses[i]->end());
    hit.resize(all.size(), false);
    grid.insert(T_grid_laser[i], all, hit);
  }
}

Eigen::Matrix3d information(double sigma_t, double sigma_r) {
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  info(0, 0) = info(1, 1) = 1.0 / (sigma_t * sigma_t);
  info(2, 2) = 1.0 / (sigma_r * sigma_r);
  return info;
}

}  // namespace

bool Slam2dOptions::is_valid(std::string* error) const {
  std::ostringstream problems;
  if (!(keyframe_distance_m > 0.0)) problems << "keyframe_distance_m must be > 0; ";
  if (!(keyframe_angle_rad > 0.0)) problems << "keyframe_angle_rad must be > 0; ";
  if (local_map_keyframes < 1) problems << "local_map_keyframes must be >= 1; ";
  if (submap_keyframes < 2) problems << "submap_keyframes must be >= 2; ";
  if (loop_search_every_n_keyframes < 1) problems << "loop_search_every_n_keyframes must be >= 1; ";
  if (!(loop_ambiguity_window_m >= 0.0)) problems << "loop_ambiguity_window_m must be >= 0; ";
  if (!(loop_search.angular_step_range_quantile > 0.0 && loop_search.angular_step_range_quantile <= 1.0))
    problems << "loop_closure.angular_step_range_quantile must be in (0, 1]; ";
  if (loop_search.depth < 1 || loop_search.depth > 12) problems << "loop_closure.branch_and_bound_depth must be in [1, 12]; ";
  if (!(loop_min_score > 0.0 && loop_min_score < 1.0)) problems << "loop_min_score must be in (0, 1); ";
  if (!(relocalisation_min_score > 0.0 && relocalisation_min_score < 1.0)) problems << "relocalisation_min_score must be in (0, 1); ";
  if (!(odometry_translation_sigma_m > 0.0 && odometry_rotation_sigma_rad > 0.0 && loop_translation_sigma_m > 0.0 &&
        loop_rotation_sigma_rad > 0.0))
    problems << "edge sigmas must be > 0; ";
  if (optimize_every_n_keyframes < 1) problems << "optimize_every_n_keyframes must be >= 1; ";
  if (loop_max_submaps_per_search < 1) problems << "loop_max_submaps_per_search must be >= 1; ";
  if (submap_install_delay_keyframes < 1) problems << "submap_install_delay_keyframes must be >= 1; ";
  if (min_matching_points < 3) problems << "min_matching_points must be >= 3; ";
  if (lost_after_scans < 1) problems << "lost_after_scans must be >= 1; ";
  if (!(segment_link_translation_sigma_m > 0.0 && segment_link_rotation_sigma_rad > 0.0)) problems << "segment link sigmas must be > 0; ";
  if (min_segment_keyframes < 1 || segment_confirm_scans < 1) problems << "segments: min_keyframes and confirm_scans must be >= 1; ";
  if (!(segment_trusted_link_min_inlier_fraction >= 0.0 && segment_trusted_link_min_inlier_fraction <= 1.0))
    problems << "segments: trusted_link_min_inlier_fraction must be in [0, 1]; ";
  if (merge_searches_per_keyframe < 0 || merge_confirmations < 1 || merge_max_misses_in_a_row < 1)
    problems << "segments: merge_searches_per_keyframe >= 0, merge_confirmations >= 1, merge_max_misses_in_a_row >= 1; ";
  if (!(merge_max_distance_m >= 0.0 && merge_min_spread_m >= 0.0 && merge_min_spread_corroborated_m >= 0.0 &&
        merge_odometry_radius_m >= 0.0 && merge_odometry_angle_rad >= 0.0 && merge_agreement_m > 0.0 && merge_agreement_rad > 0.0 &&
        merge_support_gap_m > 0.0 && merge_miss_coverage_m >= 0.0))
    problems << "segments: merge distances and angles must be >= 0 (agreement and support gap > 0); ";
  if (!(search_budget_per_keyframe > 0.0 && search_budget_burst >= 1.0 && global_search_max_range_m > 0.0) ||
      global_search_every_n_keyframes < 1)
    problems << "search_budget: per_keyframe > 0, burst >= 1, global_search_max_range_m > 0, global_search_every_n_keyframes >= 1; ";
  if (!(icp.point_sigma_m > 0.0) || icp.max_iterations < 1) problems << "icp: point_sigma_m > 0, max_iterations >= 1; ";
  // The bounds a saved map's reader checks too (map_file.cpp): finer than 1 mm, a building's
  // grid outgrows memory and the grid's 1e8-cell reach.
  if (!(output_map_resolution_m >= 1e-3 && output_map_resolution_m <= 10.0)) problems << "output.map_resolution_m must be in [0.001, 10]; ";
  if (!(grid.resolution_m >= 1e-3 && grid.resolution_m <= 10.0)) problems << "grid.resolution_m must be in [0.001, 10]; ";
  if (!(map_points.cell_size_m >= icp.max_correspondence_m))
    problems << "map_points.cell_size_m must be >= icp.max_correspondence_m; ";
  // The scan filter (the bounds a saved map's reader checks too, map_file.cpp).
  if (!(filter.min_range_m >= 0.0)) problems << "scan.min_range_m must be >= 0; ";
  if (!(filter.max_range_m > filter.min_range_m)) problems << "scan.max_range_m must be > scan.min_range_m; ";
  if (!(filter.missing_ray_length_m >= 0.0)) problems << "scan.missing_ray_length_m must be >= 0 (0 = none); ";
  if (!(filter.voxel_size_m >= 0.0 && filter.voxel_size_m <= 100.0)) problems << "scan.voxel_size_m must be in [0, 100]; ";
  if (!(filter.adaptive_max_voxel_size_m >= 0.0 && filter.adaptive_max_voxel_size_m <= 100.0))
    problems << "scan.adaptive_max_voxel_size_m must be in [0, 100]; ";
  if (filter.adaptive_min_points < 0) problems << "scan.adaptive_min_points must be >= 0; ";
  if (!(map_points.normal_radius_m > 0.0)) problems << "front_end.normal_radius_m must be > 0; ";
  if (!(icp.max_correspondence_m > 0.0 && icp.final_correspondence_m > 0.0 && icp.huber_threshold_m > 0.0 &&
        icp.inlier_distance_m > 0.0))
    problems << "icp: max_correspondence_m, final_correspondence_m, huber_threshold_m and inlier_distance_m must be > 0; ";
  if (!(icp.point_to_point_weight >= 0.0 && icp.degenerate_threshold >= 0.0))
    problems << "icp: point_to_point_weight and degenerate_threshold must be >= 0; ";
  if (!(grid.hit_probability > 0.5 && grid.hit_probability < 1.0 && grid.miss_probability > 0.0 && grid.miss_probability < 0.5))
    problems << "grid.hit_probability must be in (0.5, 1) and grid.miss_probability in (0, 0.5); ";
  if (!(loop_search.unknown_probability >= 0.0 && loop_search.unknown_probability <= 1.0))
    problems << "loop_closure.unknown_probability must be in [0, 1]; ";
  if (!(loop_max_distance_m >= 0.0 && loop_search.linear_search_window_m >= 0.0 && loop_search.angular_search_window_rad >= 0.0 &&
        loop_window_base_m >= 0.0 && loop_window_drift_per_m >= 0.0 && loop_angle_window_base_rad >= 0.0 &&
        loop_angle_window_drift_per_m >= 0.0))
    problems << "loop_closure: distances and search windows must be >= 0; ";
  if (!(loop_min_inlier_fraction >= 0.0 && loop_min_inlier_fraction <= 1.0 && degraded_min_inlier_fraction >= 0.0 &&
        degraded_min_inlier_fraction <= 1.0 && lost_inlier_fraction >= 0.0 && lost_inlier_fraction <= 1.0))
    problems << "inlier fractions (loop_closure.min_inlier_fraction, health.*_inlier_fraction) must be in [0, 1]; ";
  if (!(loop_max_rms_m > 0.0)) problems << "loop_closure.max_rms_m must be > 0; ";
  if (loop_min_inliers < 0) problems << "loop_closure.min_inliers must be >= 0; ";
  if (!(new_space_max_rays_through <= 1.0)) problems << "health.new_space_max_rays_through must be <= 1 (negative: off); ";
  const std::string text = problems.str();
  if (error != nullptr) *error = text;
  return text.empty();
}

namespace {
/// The share of a scan's rays, cast from `T_map_laser`, that pass within `radius_m` of a point of
/// `map` more than `end_margin_m` before their end: returns (`points.hits`) and no-returns
/// (`points.misses`, free rays of the filter's missing_ray_length_m). A ray through a mapped point
/// says the scan, placed there, sees through what the map holds (Slam2dOptions::
/// new_space_max_rays_through); a ray shorter than the margin says nothing and is not counted.
/// The rays are sampled every `radius_m` (> 0, <= the map's cell size), at most 4,096 times each
/// (a ray longer than that many steps is checked over its first part only).
double rays_through_map(const PointMap& map, const ScanPoints& points, const core::SE2& T_map_laser, double radius_m,
                        double end_margin_m) {
  std::size_t rays = 0, through = 0;
  const Eigen::Vector2d origin = T_map_laser.translation();
  const auto cast = [&](const Eigen::Vector2d& end_laser) {
    const Eigen::Vector2d end = T_map_laser * end_laser;
    const double length = (end - origin).norm();
    if (!(length > end_margin_m) || !std::isfinite(length)) return;
    ++rays;
    const Eigen::Vector2d direction = (end - origin) / length;
    const double steps = std::min(std::floor((length - end_margin_m) / radius_m), 4096.0);
    for (int k = 1; k <= static_cast<int>(steps); ++k) {
      if (map.nearest(origin + k * radius_m * direction, radius_m) != nullptr) {
        ++through;
        return;
      }
    }
  };
  for (const Eigen::Vector2d& p : points.hits) cast(p);
  for (const Eigen::Vector2d& p : points.misses) cast(p);
  return rays == 0 ? 0.0 : static_cast<double>(through) / static_cast<double>(rays);
}

// Whether a match's scan term (Hessian in (x, y, theta), 1/sigma^2 units) holds the position to
// within `sigma_m` in every direction: the largest eigenvalue of the position block of its inverse.
bool pins_position(const Eigen::Matrix3d& hessian, double sigma_m) {
  const Eigen::LDLT<Eigen::Matrix3d> ldlt(hessian);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive() || !(hessian.determinant() > 0.0)) return false;
  const Eigen::Matrix2d position = hessian.inverse().topLeftCorner<2, 2>();
  const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(position, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff();
  return std::isfinite(largest) && largest <= sigma_m * sigma_m;
}
}  // namespace

struct Slam2d::Impl {
  Slam2dOptions options;
  std::vector<Keyframe> keyframes;
  std::vector<Submap> submaps;
  std::vector<ScanRecord> scans;
  std::vector<Edge> edges;
  PointMap local_map;
  bool have_previous = false;
  core::SE2 previous_odom;
  core::SE2 previous_local;
  double path_length_m = 0.0;
  int bad_matches_in_a_row = 0;
  double failed_inlier_sum = 0.0;  ///< inlier fractions of those failed matches, summed
  Health health = Health::kOk;
  std::size_t loops_since_optimization = 0;
  int keyframes_since_optimization = 0;
  int local_map_start = 0;  ///< first keyframe allowed in the local map (reset on relocalisation)
  bool have_loop = false;
  bool lost_since_keyframe = false;  ///< a scan since the last keyframe failed to match
  /// The current stretch of failed matches: its first scan and the first keyframe made in it.
  std::optional<std::size_t> failed_since_scan;
  std::size_t failed_since_keyframe = 0;
  double last_loop_path_m = 0.0;  ///< path length at the last accepted loop closure
  int segment = 0;                 ///< the current map segment
  int probation = 0;               ///< matching scans the current segment's seed still needs
  int segment_first_keyframe = 0;  ///< where the current segment's submaps count from
  std::vector<int> segment_parent{0};  ///< union-find over segments (root = lowest id)
  std::vector<PendingMerge> pending_merges;
  int next_hypothesis = 0;
  std::map<int, double> uniqueness_blocked_until_m;  ///< per group: path before the next test
  double search_tokens = 0.0;
  std::size_t global_search_turn = 0;  ///< round-robin position over other groups' submaps
  int keyframes_since_global = 0;

  explicit Impl(const Slam2dOptions& o) : options(o), local_map(o.map_points), search_tokens(o.search_budget_burst) {}

  int group_of(int segment_id) const {
    while (segment_parent[static_cast<std::size_t>(segment_id)] != segment_id)
      segment_id = segment_parent[static_cast<std::size_t>(segment_id)];
    return segment_id;
  }
  void join_groups(int a, int b) {
    a = group_of(a);
    b = group_of(b);
    if (a == b) return;
    segment_parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  }

  void rebuild_local_map() {
    std::vector<Eigen::Vector2d> points;
    // The newest `local_map_keyframes` keyframes that carry points: keyframes of failed matches
    // carry none, so after a stretch of garbage scans the map of the last good stretch is kept.
    int first = static_cast<int>(keyframes.size());
    for (int used = 0; first > local_map_start && used < options.local_map_keyframes;) {
      if (!keyframes[static_cast<std::size_t>(--first)].hits.empty()) ++used;
    }
    for (int k = first; k < static_cast<int>(keyframes.size()); ++k) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
      for (const auto& p : kf.hits) points.push_back(kf.T_local_laser * p);
    }
    const std::vector<Eigen::Vector2d> filtered = voxel_filter(points, options.filter.voxel_size_m);
    // Isolated: while its parallel normals wait, this thread must not pick up a task of the
    // background job (a whole submap build), which would hold the front end back for its length.
    tbb::this_task_arena::isolate([&] { local_map.build(filtered); });
  }

  // What a submap is made of, copied out of the keyframes so it can be built in the background.
  struct SubmapSource {
    int submap = 0;
    std::vector<core::SE2> T_anchor_laser;
    std::vector<std::vector<Eigen::Vector2d>> hits, misses;
    std::unique_ptr<ProbabilityGrid> grid;  ///< the rays of the first grid_keyframes keyframes, or null
    int grid_keyframes = 0;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();  ///< mean keyframe position (anchor frame)
  };
  struct BuiltSubmap {
    std::unique_ptr<PrecomputationGridStack> stack;
    std::unique_ptr<PointMap> points;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero(), lower = Eigen::Vector2d::Zero(), upper = Eigen::Vector2d::Zero();
    bool empty = false;
  };
  // One search with everything it reads copied or pinned (grid stacks and point maps of finished
  // submaps never change and live behind unique_ptrs), so it can run in the background.
  struct SearchTask {
    const PrecomputationGridStack* stack = nullptr;
    const PointMap* points = nullptr;
    std::shared_ptr<const std::vector<Eigen::Vector2d>> matching;
    std::shared_ptr<const std::vector<Eigen::Vector2d>> search_points;  ///< range-limited (global searches)
    int hypothesis = -1;
    double ambiguity_m = 0.0;  ///< the ambiguity search spans at least this (the estimate's drift)
    double ambiguity_rad = 0.0;
    core::SE2 initial;
    BranchAndBoundOptions window;
    LoopCandidate header;  ///< keyframe, submap, anchor, times, merge/global filled in
  };
  // The keyframe's background job (Cartographer's constraint builder, Hess et al. 2016 sec. IV,
  // made deterministic): the submaps the keyframe finished and its searches run on the other core
  // while the front end goes on; the job is joined, and its results taken in a fixed order, when
  // the next keyframe is made (or at finish()), so results never depend on timing.
  struct BackgroundJob {
    tbb::task_group group;
    bool running = false;
    std::size_t scan = 0;
    core::Timestamp time;
    std::vector<SearchTask> searches;
    std::vector<std::optional<LoopCandidate>> found;
    double search_s = 0.0, global_s = 0.0;
  };
  BackgroundJob job;
  // task(0) .. task(n - 1) in parallel, one task per TBB chunk (a submap build or a search is
  // long), each writing its own slot: deterministic. Returns every task's duration.
  template <typename Task>
  static std::vector<double> timed_parallel_for(std::size_t n, const Task& task) {
    std::vector<double> seconds(n, 0.0);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, n, 1),
        [&](const tbb::blocked_range<std::size_t>& range) {
          for (std::size_t t = range.begin(); t != range.end(); ++t) {
            const auto one = Clock::now();
            task(t);
            seconds[t] = seconds_since(one);
          }
        },
        tbb::simple_partitioner());
    return seconds;
  }

  // Submap builds, apart from the searches: queued when a keyframe fills a submap and installed
  // (searchable) submap_install_delay_keyframes keyframes later (default 1: at the next keyframe,
  // as when builds and searches were one job). A longer delay lets a build run beside the front
  // end of the keyframes in between instead of holding the next one at its join, but let false
  // loops through in simulation (slam.hpp). Installed at a fixed keyframe (or when a segment
  // closes, or at finish()): deterministic.
  struct BuildJob {
    tbb::task_group group;
    bool running = false;
    int install_at = 0;
    std::vector<SubmapSource> sources;
    std::vector<BuiltSubmap> built;
    double cpu_s = 0.0;
  };
  BuildJob builds;
  // The finished submaps' precomputation grids, kept for the whole run and read at random by
  // every search: on huge pages (core::PageArena).
  mutable core::PageArena stack_memory;  // thread-safe; build_submap is const

  void start_builds(int install_at) {
    builds.running = true;
    builds.install_at = install_at;
    builds.built.clear();
    builds.built.resize(builds.sources.size());
    builds.group.run([this] {
      const std::vector<double> seconds =
          timed_parallel_for(builds.sources.size(), [this](std::size_t t) { builds.built[t] = build_submap(builds.sources[t]); });
      builds.cpu_s = 0.0;
      for (const double t : seconds) builds.cpu_s += t;
    });
  }

  // Waits for the queued builds and installs them in order.
  void join_builds(Slam2dSummary& summary) {
    if (!builds.running) return;
    builds.group.wait();
    builds.running = false;
    summary.times.submap_s += builds.cpu_s;
    for (std::size_t i = 0; i < builds.sources.size(); ++i) {
      Submap& submap = submaps[static_cast<std::size_t>(builds.sources[i].submap)];
      submap.building = false;
      install_submap(submap, std::move(builds.built[i]));
    }
    builds.sources.clear();
    builds.built.clear();
  }

  // The keyframes' rays go into the growing grid of every active submap in the background (one
  // task per submap, each its own grid, keyframes in order) while the front end matches the
  // next scans. Cartographer likewise inserts every range data into its active submaps as it
  // comes (Hess et al. 2016, sec. III-B). Nobody waits for them at every keyframe: keyframes
  // that arrive while insertions run are handed over at the next keyframe that finds them
  // done, and a build (or a change to the keyframes) waits for what is in flight, then inserts
  // what was not handed over itself.
  // They run in an arena of their own at low priority: the other core takes the searches and
  // builds first, and a thread waiting for those never picks up an insertion instead.
  // An insertion that throws (a point beyond the grid's reach) marks its grid failed instead:
  // the grid is dropped when the insertions are waited for, and the submap's build inserts
  // every keyframe itself, where the error surfaces as it did before (and no wait, not even in
  // the destructor, throws).
  struct RayInsertions {
    tbb::task_arena arena{1, 0, tbb::task_arena::priority::low};
    tbb::task_group group;
    std::atomic<int> in_flight{0};
    bool started = false;
    std::mutex failed_mutex;
    std::vector<const ProbabilityGrid*> failed;
  };
  RayInsertions ray_insertions;

  void wait_for_ray_insertions() {
    if (!ray_insertions.started) return;
    ray_insertions.arena.execute([this] { ray_insertions.group.wait(); });
    ray_insertions.started = false;
    for (const ProbabilityGrid* grid : ray_insertions.failed) {
      for (Submap& submap : submaps) {
        if (submap.grid.get() != grid) continue;
        submap.grid.reset();
        submap.grid_keyframes = 0;
      }
    }
    ray_insertions.failed.clear();
  }

  // Hands the keyframes the active submaps' grids do not hold yet to background insertions,
  // unless insertions are still running. A submap's grid is made with the submap and stays null
  // once dropped.
  void start_ray_insertions() {
    if (ray_insertions.in_flight.load(std::memory_order_acquire) > 0) return;
    wait_for_ray_insertions();  // all done: returns at once
    for (Submap& submap : submaps) {
      if (submap.finished || submap.building || submap.keyframes.empty()) continue;
      if (!submap.grid || submap.grid_keyframes == static_cast<int>(submap.keyframes.size())) continue;
      auto batch = std::make_shared<SubmapSource>();
      copy_keyframes(submap, static_cast<std::size_t>(submap.grid_keyframes), *batch);
      submap.grid_keyframes = static_cast<int>(submap.keyframes.size());
      ProbabilityGrid* grid = submap.grid.get();
      ray_insertions.started = true;
      ray_insertions.in_flight.fetch_add(1, std::memory_order_relaxed);
      // The first keyframe reserves room for the submap's path (submap_keyframes keyframes
      // keyframe_distance_m apart at least), so a grid seldom grows: each growth is a copy, and
      // on fresh memory (page faults were 44 % of a run's on MIT CSAIL with 4 m, perf).
      const double first_margin_m = grid->width() == 0 ? options.submap_keyframes * options.keyframe_distance_m : 0.0;
      ray_insertions.arena.execute([&] {
        ray_insertions.group.run([grid, batch, first_margin_m, this] {
          try {
            for (std::size_t i = 0; i < batch->T_anchor_laser.size(); ++i)
              insert_rays(*grid, {batch->T_anchor_laser[i]}, {&batch->hits[i]}, {&batch->misses[i]}, i == 0 ? first_margin_m : 0.0);
          } catch (...) {
            const std::lock_guard<std::mutex> lock(ray_insertions.failed_mutex);
            ray_insertions.failed.push_back(grid);
          }
          ray_insertions.in_flight.fetch_sub(1, std::memory_order_release);
        });
      });
    }
  }

  // After the front end moved keyframes or dropped their points: the active submaps' grids no
  // longer hold what their keyframes say; their builds start over from the keyframes.
  void drop_growing_grids() {
    wait_for_ray_insertions();
    for (Submap& submap : submaps) {
      submap.grid.reset();
      submap.grid_keyframes = 0;
    }
  }

  // The submap's keyframes from `first` on, copied into `source` in its anchor's frame.
  void copy_keyframes(const Submap& submap, std::size_t first, SubmapSource& source) const {
    const core::SE2 T_anchor_local = keyframes[static_cast<std::size_t>(submap.anchor)].T_local_laser.inverse();
    for (std::size_t i = first; i < submap.keyframes.size(); ++i) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(submap.keyframes[i])];
      source.T_anchor_laser.push_back(T_anchor_local * kf.T_local_laser);
      source.hits.push_back(kf.hits);
      source.misses.push_back(kf.misses);
    }
  }

  // Takes the submap's growing grid (the ray insertions must be idle: wait_for_ray_insertions).
  SubmapSource submap_source(Submap& submap, int index) const {
    SubmapSource source;
    source.submap = index;
    source.grid = std::move(submap.grid);
    source.grid_keyframes = source.grid ? submap.grid_keyframes : 0;
    submap.grid_keyframes = 0;
    copy_keyframes(submap, 0, source);
    for (const core::SE2& T_anchor_laser : source.T_anchor_laser) source.centre += T_anchor_laser.translation();
    source.centre /= static_cast<double>(std::max<std::size_t>(1, source.T_anchor_laser.size()));
    return source;
  }

  BuiltSubmap build_submap(SubmapSource& source) const {
    BuiltSubmap built;
    built.centre = source.centre;
    std::vector<Eigen::Vector2d> points;
    for (std::size_t i = 0; i < source.T_anchor_laser.size(); ++i) {
      const core::SE2& T_anchor_laser = source.T_anchor_laser[i];
      for (const auto& p : source.hits[i]) points.push_back(T_anchor_laser * p);
    }
    if (points.empty()) {
      built.empty = true;
      return built;
    }
    // The grid and its precomputation stack beside the point map: the front end waits for a
    // build at the next keyframe (update_submaps), and a waiting thread takes one of the two.
    bool observed = false;
    tbb::parallel_invoke(
        [&] {
          // The rays in keyframe order on the growing grid, or on a new one: the same updates in
          // the same order, so the same cells (the layout differs; nothing below depends on it).
          ProbabilityGrid grid = source.grid ? std::move(*source.grid) : ProbabilityGrid(options.grid);
          const auto first = static_cast<std::size_t>(source.grid_keyframes);
          std::vector<core::SE2> T_grid_laser(source.T_anchor_laser.begin() + static_cast<std::ptrdiff_t>(first), source.T_anchor_laser.end());
          std::vector<const std::vector<Eigen::Vector2d>*> hits, misses;
          for (std::size_t i = first; i < source.T_anchor_laser.size(); ++i) {
            hits.push_back(&source.hits[i]);
            misses.push_back(&source.misses[i]);
          }
          insert_rays(grid, T_grid_laser, hits, misses, 0.0);
          observed = observed_extent(grid, built.lower, built.upper);
          if (observed) built.stack = std::make_unique<PrecomputationGridStack>(grid, options.loop_search, &stack_memory);
        },
        [&] {
          built.points = std::make_unique<PointMap>(options.map_points);
          built.points->build(voxel_filter(points, options.filter.voxel_size_m));
        });
    if (!observed) {
      built.empty = true;
      built.points.reset();
    }
    return built;
  }

  void install_submap(Submap& submap, BuiltSubmap&& built) {
    submap.stack = std::move(built.stack);
    submap.points = std::move(built.points);
    submap.centre_anchor = built.centre;
    submap.lower_anchor = built.lower;
    submap.upper_anchor = built.upper;
    submap.empty = built.empty;
    submap.finished = true;
  }

  // Finishes a submap now, on this thread (a segment closing).
  void finish_submap(Submap& submap) {
    const int index = static_cast<int>(&submap - submaps.data());
    wait_for_ray_insertions();
    SubmapSource source = submap_source(submap, index);
    install_submap(submap, build_submap(source));
  }

  // The search task of keyframe `k` for one planned search: window and initial pose from the
  // current state (file comment of slam.hpp).
  SearchTask make_search(int k, const PlannedSearch& plan, const std::shared_ptr<const std::vector<Eigen::Vector2d>>& matching) const {
    const Submap& submap = submaps[static_cast<std::size_t>(plan.submap)];
    const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
    const Keyframe& anchor = keyframes[static_cast<std::size_t>(submap.anchor)];
    SearchTask task;
    task.stack = submap.stack.get();
    task.points = submap.points.get();
    task.matching = matching;
    task.window = options.loop_search;
    task.initial = anchor.T_world_laser.inverse() * plan.T_world_guess;
    if (plan.global) {
      global_window(submap.lower_anchor, submap.upper_anchor, 1.0, options.loop_search, task.window, task.initial);
      task.search_points =
          std::make_shared<const std::vector<Eigen::Vector2d>>(within_range(*matching, options.global_search_max_range_m));
    } else {
      // The drift the estimate may have accumulated relative to the submap: the path travelled
      // since the submap, or since the last accepted loop closure when that is shorter. A loop's
      // window is that drift, capped; the ambiguity search of every windowed search spans the
      // whole drift, uncapped (the true place may lie beyond the cap, a look-alike within it).
      const double path = std::min(std::abs(kf.path_length_m - anchor.path_length_m),
                                   have_loop ? std::max(0.0, kf.path_length_m - last_loop_path_m) : 1e300);
      const double drift_m = options.loop_window_base_m + options.loop_window_drift_per_m * path;
      const double drift_rad = options.loop_angle_window_base_rad + options.loop_angle_window_drift_per_m * path;
      if (!plan.merge) {
        task.window.linear_search_window_m = std::min(options.loop_search.linear_search_window_m, drift_m);
        task.window.angular_search_window_rad = std::min(options.loop_search.angular_search_window_rad, drift_rad);
      }
      task.ambiguity_m = std::min(drift_m, options.loop_ambiguity_max_window_m);
      task.ambiguity_rad = drift_rad;
    }
    task.header.keyframe = k;
    task.header.submap = plan.submap;
    task.header.anchor_keyframe = submap.anchor;
    task.header.time = kf.time;
    task.header.anchor_time = anchor.time;
    task.header.merge = plan.merge || plan.global;
    task.header.global = plan.global;
    task.hypothesis = plan.hypothesis;
    return task;
  }

  std::optional<LoopCandidate> run_search(const SearchTask& task) const {
    LoopCandidate candidate = task.header;
    if (!search_and_verify(*task.stack, *task.points, *task.matching, task.initial, task.window, options.loop_min_score, options,
                           candidate, task.search_points.get(), task.ambiguity_m, task.ambiguity_rad))
      return std::nullopt;
    return candidate;
  }

  void start_job() {
    job.running = true;
    job.found.assign(job.searches.size(), std::nullopt);
    job.group.run([this] {
      // The searches are independent of each other: one parallel loop, each task writing its own
      // slot (deterministic). The job's wall time is the search stage's.
      const auto job_start = Clock::now();
      const std::vector<double> seconds =
          timed_parallel_for(job.searches.size(), [this](std::size_t t) { job.found[t] = run_search(job.searches[t]); });
      job.search_s = seconds_since(job_start);
      job.global_s = 0.0;
      for (std::size_t t = 0; t < seconds.size(); ++t) {
        if (job.searches[t].header.global) job.global_s += seconds[t];
      }
    });
  }

  // Joins the background job and takes its results in order: finished submaps, then candidates
  // (loop closures, merges).
  void join_job(Slam2dSummary& summary) {
    if (!job.running) return;
    job.group.wait();
    job.running = false;
    const auto start = Clock::now();
    summary.times.loop_search_s += job.search_s;
    summary.times.global_search_s += job.global_s;
    for (std::size_t i = 0; i < job.found.size(); ++i) {
      if (!job.found[i]) continue;
      summary.candidates.push_back(*job.found[i]);
      const int c = static_cast<int>(summary.candidates.size()) - 1;
      LoopCandidate& candidate = summary.candidates.back();
      const Submap& submap = submaps[static_cast<std::size_t>(candidate.submap)];
      const int keyframe_segment = keyframes[static_cast<std::size_t>(candidate.keyframe)].segment;
      const bool across = group_of(submap.segment) != group_of(keyframe_segment);
      if (!candidate.accepted) {
        if (across) candidate.merge_decision = "failed verification";
        continue;
      }
      if (across) {
        consider_merge(c, job.scan, job.time, summary);
        continue;
      }
      // A merge search whose groups a merge earlier in this list has joined: a loop closure if
      // it agrees with the merged placement.
      if (candidate.merge && !agree(implied_pose(candidate), keyframes[static_cast<std::size_t>(candidate.keyframe)].T_world_laser)) {
        candidate.accepted = false;
        candidate.reason = "disagrees with the merge just made";
        candidate.merge_decision = "superseded";
        continue;
      }
      // The search's own ambiguity test covers its submap; when the estimate may have drifted
      // farther than the usual ambiguity window, the place must also be unique in every submap
      // of the group within that drift (the true place may sit in a neighbouring submap).
      const SearchTask& task = job.searches[i];
      if (task.ambiguity_m > options.loop_ambiguity_window_m && !unique_within_drift(candidate, task, summary)) {
        candidate.accepted = false;
        candidate.reason = "ambiguous within the estimate's possible drift: another submap scores within the margin elsewhere";
        continue;
      }
      add_loop(c, summary);
    }
    count_misses(summary);
    job.searches.clear();
    job.found.clear();
    summary.times.loop_search_s += seconds_since(start);
  }

  ~Impl() {
    wait_for_ray_insertions();
    if (job.running) job.group.wait();
    if (builds.running) builds.group.wait();
  }

  // Tracking relocalisation: searches the scan in the map of the last keyframes that carry points
  // (front-end frame) over the loop-search window around `predicted`, with the loop verification.
  // Recovers a slip or jump of the odometry that the finished submaps do not cover yet (the
  // robot is usually still inside its active submap). Returns the verified pose or nothing.
  std::optional<core::SE2> relocalise_locally(const std::vector<Eigen::Vector2d>& matching, const core::SE2& predicted,
                                              LoopCandidate& candidate) const {
    // The newest keyframes first, into a grid reserved once (not doubled ray by ray).
    std::vector<core::SE2> T_local_laser;
    std::vector<const std::vector<Eigen::Vector2d>*> hits, misses;
    std::vector<Eigen::Vector2d> points;
    for (int k = static_cast<int>(keyframes.size()) - 1; k >= local_map_start && static_cast<int>(hits.size()) < options.submap_keyframes; --k) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
      if (kf.hits.empty()) continue;
      T_local_laser.push_back(kf.T_local_laser);
      hits.push_back(&kf.hits);
      misses.push_back(&kf.misses);
      for (const auto& p : kf.hits) points.push_back(kf.T_local_laser * p);
    }
    if (hits.empty()) return std::nullopt;
    ProbabilityGrid grid(options.grid);
    insert_rays(grid, T_local_laser, hits, misses, 0.0);
    const PrecomputationGridStack stack(grid, options.loop_search);
    PointMap map_points(options.map_points);
    map_points.build(voxel_filter(points, options.filter.voxel_size_m));
    const bool found = search_and_verify(stack, map_points, matching, predicted, options.loop_search,
                                         options.relocalisation_min_score, options, candidate);
    if (!found || !candidate.accepted)
      return std::nullopt;
    return candidate.T_anchor_keyframe;
  }

  backend::Problem2D make_graph_problem(io::PoseGraph2D* graph_out = nullptr) const {
    io::PoseGraph2D graph;
    for (std::size_t k = 0; k < keyframes.size(); ++k) graph.vertices.push_back({static_cast<std::int64_t>(k), keyframes[k].T_world_laser});
    for (const Edge& e : edges) {
      io::GraphEdge<core::SE2> edge;
      edge.from = e.from;
      edge.to = e.to;
      edge.T_from_to = e.T_from_to;
      if (e.loop) {
        edge.information = information(options.loop_translation_sigma_m, options.loop_rotation_sigma_rad);
      } else if (e.weak) {
        edge.information = information(options.segment_link_translation_sigma_m, options.segment_link_rotation_sigma_rad);
      } else {
        edge.information = information(options.odometry_translation_sigma_m, options.odometry_rotation_sigma_rad);
        if (options.edge_covariance_from_matcher) {
          const Eigen::Matrix3d covariance = edge.information.inverse() + e.match_covariance;
          edge.information = covariance.inverse();
          edge.information = 0.5 * (edge.information + edge.information.transpose()).eval();
        }
      }
      graph.edges.push_back(edge);
    }
    graph.fixed.push_back(0);
    if (graph_out != nullptr) *graph_out = graph;
    return backend::make_problem(graph, "slam2d pose graph");
  }

  void optimize(bool gnc, Slam2dSummary& summary) {
    if (keyframes.size() < 2) return;
    if (options.should_stop && options.should_stop()) return;
    const auto start = Clock::now();
    backend::Problem2D problem = make_graph_problem();
    std::vector<bool> is_loop;
    for (const Edge& edge : edges) is_loop.push_back(edge.loop);
    backend::KeyframeGraphSolveOptions solve_options;
    solve_options.should_stop = options.should_stop;
    const backend::KeyframeGraphSolve solve = backend::solve_keyframe_graph(problem, gnc, is_loop, solve_options);
    // A GNC cut short is no classification to act on: keep the graph as it was.
    if (!solve.applied) return;
    if (gnc) {
      for (const std::size_t index : solve.rejected_loops) {
        const Edge& edge = edges[index];
        if (edge.candidate >= 0) summary.candidates[static_cast<std::size_t>(edge.candidate)].rejected_by_gnc = true;
      }
      summary.loops_rejected_by_gnc = solve.rejected_loops.size();
      // Drop the rejected loops from the graph for good.
      std::vector<Edge> kept;
      for (std::size_t e = 0; e < edges.size(); ++e) {
        if (solve.keep[e]) kept.push_back(edges[e]);
      }
      edges = std::move(kept);
    }
    for (std::size_t k = 0; k < keyframes.size(); ++k) keyframes[k].T_world_laser = problem.T_world_pose[k];
    ++summary.optimizations;
    loops_since_optimization = 0;
    keyframes_since_optimization = 0;
    summary.times.optimize_s += seconds_since(start);
  }

  // Matching resumed after a stretch of failed matches: the stretch followed odometry from the
  // last good pose, but the failure most likely began with what made it fail (a jump or slip of
  // the odometry, a kidnapping), so its poses are re-placed by odometry backwards from the first
  // good match instead: every front-end pose of the stretch is moved by the correction
  // `C_local` (matched pose times predicted pose inverse) and the keyframe chain is rebuilt.
  void replace_failed_stretch(const core::SE2& C_local) {
    drop_growing_grids();
    const std::size_t first_scan = *failed_since_scan;
    std::vector<core::SE2> T_local_scans;
    for (std::size_t i = first_scan; i < scans.size(); ++i) {
      const ScanRecord& record = scans[i];
      T_local_scans.push_back(C_local * (keyframes[static_cast<std::size_t>(record.keyframe)].T_local_laser * record.T_keyframe_laser));
    }
    for (std::size_t k = std::max<std::size_t>(failed_since_keyframe, 1); k < keyframes.size(); ++k) {
      Keyframe& kf = keyframes[k];
      const Keyframe& previous = keyframes[k - 1];
      kf.T_local_laser = C_local * kf.T_local_laser;
      kf.T_world_laser = previous.T_world_laser * (previous.T_local_laser.inverse() * kf.T_local_laser);
    }
    for (Edge& e : edges) {
      if (e.loop || e.to < static_cast<int>(failed_since_keyframe)) continue;
      e.T_from_to = keyframes[static_cast<std::size_t>(e.from)].T_local_laser.inverse() * keyframes[static_cast<std::size_t>(e.to)].T_local_laser;
    }
    for (std::size_t i = first_scan; i < scans.size(); ++i) {
      ScanRecord& record = scans[i];
      record.T_keyframe_laser = keyframes[static_cast<std::size_t>(record.keyframe)].T_local_laser.inverse() * T_local_scans[i - first_scan];
    }
    previous_local = C_local * previous_local;
    failed_since_scan.reset();
  }

  // Whether the budget allows a search of `cost` tokens; spends them if so.
  bool spend(double cost, Slam2dSummary& summary) {
    if (search_tokens < cost) {
      ++summary.searches_skipped_by_budget;
      return false;
    }
    search_tokens -= cost;
    return true;
  }

  bool searchable(const Submap& submap, int k) const {
    return submap.finished && !submap.empty && std::find(submap.keyframes.begin(), submap.keyframes.end(), k) == submap.keyframes.end();
  }

  Eigen::Vector2d submap_centre_world(const Submap& submap) const {
    return keyframes[static_cast<std::size_t>(submap.anchor)].T_world_laser * submap.centre_anchor;
  }

  // The searches of keyframe `k` in priority order, within the budget (file comment of slam.hpp).
  std::vector<PlannedSearch> plan_searches(int k, Slam2dSummary& summary) {
    std::vector<PlannedSearch> plan;
    const Keyframe& current = keyframes[static_cast<std::size_t>(k)];
    const int group = group_of(current.segment);
    std::vector<int> others;  // searchable submaps of other groups, in index order
    for (int s = 0; s < static_cast<int>(submaps.size()); ++s) {
      const Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (searchable(submap, k) && group_of(submap.segment) != group) others.push_back(s);
    }
    // Priorities when other groups exist: (1) test the pending merges of this group where they
    // place the keyframe, (2) windowed merge searches around the estimate (the odometry link),
    // (3) loop searches within the group, all from the token budget; (4) the round-robin
    // whole-submap search (finds the place when the odometry link is wrong) at a fixed cadence.
    // Each windowed merge search goes to the nearest submap of the other group(s).
    if (!others.empty()) plan_merge_searches(current, group, others, plan, summary);
    if (k % options.loop_search_every_n_keyframes == 0) plan_loop_searches(k, group, plan, summary);
    plan_global_search(current, others, plan, summary);
    return plan;
  }

  // The submap of `others` (of `target_group`; -1: any) not `chosen` yet whose centre lies
  // nearest `guess`, within merge_max_distance_m; -1 if none.
  int nearest_submap(const core::SE2& guess, int target_group, const std::vector<int>& others,
                     const std::vector<int>& chosen) const {
    int best = -1;
    double best_distance = options.merge_max_distance_m;
    for (const int s : others) {
      const Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (target_group >= 0 && group_of(submap.segment) != target_group) continue;
      if (std::find(chosen.begin(), chosen.end(), s) != chosen.end()) continue;
      const double distance = (submap_centre_world(submap) - guess.translation()).norm();
      if (distance <= best_distance) {
        best = s;
        best_distance = distance;
      }
    }
    return best;
  }

  // Priorities (1) and (2) of plan_searches: the windowed merge searches of keyframe `current`
  // (of `group`) in the submaps of other groups (`others`).
  void plan_merge_searches(const Keyframe& current, int group, const std::vector<int>& others, std::vector<PlannedSearch>& plan,
                           Slam2dSummary& summary) {
    std::vector<int> chosen;
    // (1) The pending merges of this group, best supported first, at most
    // merge_searches_per_keyframe of them.
    std::vector<const PendingMerge*> mine;
    for (const PendingMerge& pending : pending_merges)
      if (group_of(pending.group_b) == group && group_of(pending.group_a) != group) mine.push_back(&pending);
    std::stable_sort(mine.begin(), mine.end(), [](const PendingMerge* a, const PendingMerge* b) {
      return a->candidates.size() - static_cast<std::size_t>(a->misses) > b->candidates.size() - static_cast<std::size_t>(b->misses);
    });
    if (mine.size() > static_cast<std::size_t>(options.merge_searches_per_keyframe))
      mine.resize(static_cast<std::size_t>(options.merge_searches_per_keyframe));
    // Each in the two nearest submaps where it puts the keyframe (submaps overlap by half: the
    // place may lie at the edge of the nearest).
    for (const PendingMerge* hypothesis : mine) {
      const PendingMerge& pending = *hypothesis;
      const core::SE2 guess = pending.delta * current.T_world_laser;
      for (int test = 0; test < 2; ++test) {
        const int s = nearest_submap(guess, group_of(pending.group_a), others, chosen);
        if (s < 0 || !spend(1.0, summary)) break;
        chosen.push_back(s);
        plan.push_back({s, true, false, guess, pending.id});
        ++summary.merge_searches;
        ++summary.segments[static_cast<std::size_t>(current.segment)].merge_searches;
      }
    }
    // (2) Around the estimate (the odometry link), merge_searches_per_keyframe searches.
    for (int estimate = 0; estimate < options.merge_searches_per_keyframe; ++estimate) {
      const int s = nearest_submap(current.T_world_laser, -1, others, chosen);
      if (s < 0 || !spend(1.0, summary)) break;
      chosen.push_back(s);
      plan.push_back({s, true, false, current.T_world_laser, -1});
      ++summary.merge_searches;
      ++summary.segments[static_cast<std::size_t>(current.segment)].merge_searches;
    }
  }

  // (3) Loop searches within the group, every n-th keyframe: the nearest finished submaps by
  // the estimate. The nearest are usually the ones just built on the way here; keep the
  // nearest of those and fill the rest with submaps from earlier visits.
  void plan_loop_searches(int k, int group, std::vector<PlannedSearch>& plan, Slam2dSummary& summary) {
    const Keyframe& current = keyframes[static_cast<std::size_t>(k)];
    std::vector<std::pair<double, int>> nearby;
    for (int s = 0; s < static_cast<int>(submaps.size()); ++s) {
      const Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (!searchable(submap, k) || group_of(submap.segment) != group) continue;
      const double distance = (submap_centre_world(submap) - current.T_world_laser.translation()).norm();
      if (distance <= options.loop_max_distance_m) nearby.emplace_back(distance, s);
    }
    std::sort(nearby.begin(), nearby.end());
    int taken = 0;
    int recent = 0;
    for (const auto& [distance, s] : nearby) {
      if (taken >= options.loop_max_submaps_per_search) break;
      const Keyframe& anchor = keyframes[static_cast<std::size_t>(submaps[static_cast<std::size_t>(s)].anchor)];
      const bool is_recent = current.path_length_m - anchor.path_length_m < 2.0 * options.loop_max_distance_m;
      if (is_recent && recent++ >= 1) continue;
      if (!spend(1.0, summary)) break;
      ++taken;
      plan.push_back({s, false, false, current.T_world_laser, -1});
      ++summary.loop_searches;
    }
  }

  // (4) One search over a whole submap of another group every global_search_every_n_keyframes
  // keyframes, round-robin over them, outside the token budget (a fixed cadence bounds it).
  void plan_global_search(const Keyframe& current, const std::vector<int>& others, std::vector<PlannedSearch>& plan,
                          Slam2dSummary& summary) {
    ++keyframes_since_global;
    if (!others.empty() && keyframes_since_global >= options.global_search_every_n_keyframes) {
      keyframes_since_global = 0;
      const int s = others[global_search_turn++ % others.size()];
      plan.push_back({s, true, true, current.T_world_laser, -1});
      ++summary.global_searches;
      ++summary.segments[static_cast<std::size_t>(current.segment)].merge_searches;
    }
  }

  void add_loop(int c, Slam2dSummary& summary) {
    const LoopCandidate& candidate = summary.candidates[static_cast<std::size_t>(c)];
    edges.push_back({candidate.anchor_keyframe, candidate.keyframe, candidate.T_anchor_keyframe, true, c});
    ++summary.loops_accepted;
    ++loops_since_optimization;
    // A loop to an earlier visit bounds the drift relative to the old map; a loop to a submap
    // built on the way here does not.
    const Keyframe& kf = keyframes[static_cast<std::size_t>(candidate.keyframe)];
    if (kf.path_length_m - keyframes[static_cast<std::size_t>(candidate.anchor_keyframe)].path_length_m >= 2.0 * options.loop_max_distance_m) {
      have_loop = true;
      last_loop_path_m = kf.path_length_m;
    }
  }

  // Where candidate `c` says its keyframe is, in the world frame of its submap's group.
  core::SE2 implied_pose(const LoopCandidate& candidate) const {
    return keyframes[static_cast<std::size_t>(candidate.anchor_keyframe)].T_world_laser * candidate.T_anchor_keyframe;
  }

  bool agree(const core::SE2& a, const core::SE2& b) const {
    return (a.translation() - b.translation()).norm() <= options.merge_agreement_m &&
           std::abs((a.so2().inverse() * b.so2()).angle()) <= options.merge_agreement_rad;
  }

  // A verified match across groups: confirm a pending merge, or start one.
  void consider_merge(int c, std::size_t scan, core::Timestamp time, Slam2dSummary& summary) {
    LoopCandidate& candidate = summary.candidates[static_cast<std::size_t>(c)];
    const int group_a = group_of(submaps[static_cast<std::size_t>(candidate.submap)].segment);
    const int group_b = group_of(keyframes[static_cast<std::size_t>(candidate.keyframe)].segment);
    const core::SE2& T_world_keyframe = keyframes[static_cast<std::size_t>(candidate.keyframe)].T_world_laser;
    const core::SE2 delta = implied_pose(candidate) * T_world_keyframe.inverse();
    candidate.accepted = false;
    const std::size_t p = add_merge_support(c, candidate.keyframe, group_a, group_b, delta, T_world_keyframe);
    PendingMerge& pending = pending_merges[p];
    // Support: agreeing matches from distinct keyframes along a stretch of path long enough to
    // leave a room and see its surroundings (one room may have a twin the map holds and the true
    // one it does not). The path between consecutive supporting keyframes counts, each gap up to
    // merge_support_gap_m: a placement kept through a stretch the other map never covered (no
    // test there counts against it, count_misses) gains nothing from that stretch.
    const double spread_m = supported_path_m(pending);
    const int support = static_cast<int>(pending.candidates.size());
    // Odometry is independent evidence: a placement close to where the segment link (odometry)
    // puts the keyframe needs a short stretch of support; one far from it (a kidnapping, a
    // symmetric floor plan seen from an unmapped twin) needs a long one. Only when the links are
    // trusted: after a loss on consistent scans the robot may have been carried, and a wrong
    // placement may lie near the stale odometry by chance (measured: a kidnapping 7 m off).
    const bool corroborated = odometry_chain_trusted(submaps[static_cast<std::size_t>(candidate.submap)].segment,
                                                     keyframes[static_cast<std::size_t>(candidate.keyframe)].segment, summary) &&
                              near_odometry(delta, T_world_keyframe);
    const double needed_m = corroborated ? options.merge_min_spread_corroborated_m : options.merge_min_spread_m;
    if (support < options.merge_confirmations || spread_m < needed_m) {
      candidate.reason = "verified across segments; " + std::to_string(support) + " agreeing matches over " + std::to_string(spread_m) +
                         " m of path (a merge " + (corroborated ? "near" : "away from") + " the odometry link needs " +
                         std::to_string(options.merge_confirmations) + " over " + std::to_string(needed_m) + " m)";
      candidate.merge_decision = "awaiting support";
      return;
    }
    if (const PendingMerge* other = competing_placement(pending, group_a, group_b, corroborated, T_world_keyframe)) {
      candidate.reason = "verified across segments and confirmed, but another placement of the same segments is also "
                         "supported (hypothesis " + std::to_string(other->id) + "); waiting until one is refuted";
      candidate.merge_decision = "competing placement";
      return;
    }
    // The uniqueness test costs a search of every submap: after a refusal, the group waits for
    // kUniquenessRetryM more path before the next one (linear in the path, never quadratic).
    const double path_m = keyframes[static_cast<std::size_t>(candidate.keyframe)].path_length_m;
    double& blocked_until_m = uniqueness_blocked_until_m[group_b];
    if (path_m < blocked_until_m) {
      candidate.reason = "verified across segments; confirmed, waiting to repeat the map-wide uniqueness test";
      candidate.merge_decision = "awaiting the uniqueness test";
      return;
    }
    // Odometry corroborates a placement near the link: a twin of the place elsewhere (farther
    // than the odometry could be wrong) is excluded by it, the windowed verification covers the
    // rest. Far from the link, only a place unique over the whole map is merged.
    if (corroborated || unique_over_map(c, summary)) {
      const PendingMerge confirmed = pending;
      pending_merges.erase(pending_merges.begin() + static_cast<std::ptrdiff_t>(p));
      candidate.merge_decision = "merged";
      merge(confirmed, scan, time, summary);
      return;
    }
    constexpr double kUniquenessRetryM = 5.0;
    blocked_until_m = path_m + kUniquenessRetryM;
    candidate.reason = "verified across segments, but the place is ambiguous over the whole map: another submap scores "
                       "within the margin elsewhere (symmetric or repeated structure); not merged";
    candidate.merge_decision = "ambiguous";
    ++summary.merges_refused_as_ambiguous;
  }

  // The pending merge of groups `group_a` and `group_b` whose placement agrees with `delta` at
  // `T_world_keyframe` (a new one if none does) gains candidate `c` of `keyframe` as support,
  // once per keyframe. Returns its index in pending_merges.
  std::size_t add_merge_support(int c, int keyframe, int group_a, int group_b, const core::SE2& delta,
                                const core::SE2& T_world_keyframe) {
    std::size_t p = 0;
    for (; p < pending_merges.size(); ++p) {
      const PendingMerge& pending = pending_merges[p];
      if (group_of(pending.group_a) == group_a && group_of(pending.group_b) == group_b &&
          agree(pending.delta * T_world_keyframe, delta * T_world_keyframe))
        break;
    }
    if (p == pending_merges.size()) pending_merges.push_back({next_hypothesis++, group_a, group_b, delta, {}, {}, 0, 0});
    PendingMerge& pending = pending_merges[p];
    if (std::find(pending.keyframes.begin(), pending.keyframes.end(), keyframe) == pending.keyframes.end()) {
      pending.candidates.push_back(c);
      pending.keyframes.push_back(keyframe);
      pending.misses_in_a_row = 0;
    }
    return p;
  }

  // Competing placements: another live hypothesis of the same groups with support of its own.
  // Odometry is evidence scans cannot give: a placement near the odometry link is not held up
  // by one far from it (on a floor plan symmetric under a half turn the twin placement is
  // supported by the scans as long as the true one), only by another near it. Returns the first
  // such rival of `pending`, or nullptr.
  const PendingMerge* competing_placement(const PendingMerge& pending, int group_a, int group_b, bool corroborated,
                                          const core::SE2& T_world_keyframe) const {
    for (const PendingMerge& other : pending_merges) {
      if (&other == &pending || other.candidates.size() < 2) continue;
      if (group_of(other.group_a) != group_a || group_of(other.group_b) != group_b) continue;
      if (corroborated && !near_odometry(other.delta, T_world_keyframe)) continue;
      return &other;
    }
    return nullptr;
  }

  // Whether every segment link on the odometry chain between segments `a` and `b` (the starts of
  // the segments after the older one, up to the younger) is trusted (SegmentInfo).
  static bool odometry_chain_trusted(int a, int b, const Slam2dSummary& summary) {
    for (int s = std::min(a, b) + 1; s <= std::max(a, b); ++s)
      if (!summary.segments[static_cast<std::size_t>(s)].odometry_link_trusted) return false;
    return true;
  }

  // Whether the placement `delta` moves a keyframe at `T_world_keyframe` (its group's estimate,
  // placed by the odometry link) by less than merge_odometry_radius_m / merge_odometry_angle_rad.
  bool near_odometry(const core::SE2& delta, const core::SE2& T_world_keyframe) const {
    const core::SE2 placed = delta * T_world_keyframe;
    return (placed.translation() - T_world_keyframe.translation()).norm() <= options.merge_odometry_radius_m &&
           std::abs(core::wrap_angle(placed.angle() - T_world_keyframe.angle())) <= options.merge_odometry_angle_rad;
  }

  // The path a placement's support covers: between consecutive supporting keyframes (in path
  // order), each gap counted up to merge_support_gap_m.
  double supported_path_m(const PendingMerge& pending) const {
    std::vector<double> along;
    for (const int k : pending.keyframes) along.push_back(keyframes[static_cast<std::size_t>(k)].path_length_m);
    std::sort(along.begin(), along.end());
    double path_m = 0.0;
    for (std::size_t i = 1; i < along.size(); ++i) path_m += std::min(along[i] - along[i - 1], options.merge_support_gap_m);
    return path_m;
  }

  // Whether a keyframe of `group` lies within merge_miss_coverage_m of `T_world_pose`.
  bool covered_by_group(int group, const core::SE2& T_world_pose) const {
    for (const Keyframe& kf : keyframes) {
      if (group_of(kf.segment) == group &&
          (kf.T_world_laser.translation() - T_world_pose.translation()).norm() <= options.merge_miss_coverage_m)
        return true;
    }
    return false;
  }

  // A search that tested a pending merge's placement and found nothing agreeing there counts
  // against it; a hypothesis missed at least twice and more often than supported is dropped.
  // Nothing found where the other group's robot never passed (no keyframe of it within
  // merge_miss_coverage_m of the pose the placement gives) does not count: a right placement is
  // tested there whenever the robot drives where the other map never was, or saw only from afar
  // (a kidnapped robot's ring beyond the part mapped before), and the map need not hold what
  // the scan sees. A verified match elsewhere always counts, and so does every test of a
  // placement near the odometry link (it puts the robot where its own segment's path suggests,
  // which is no kidnapping; exempting those kept near-duplicate placements alive that blocked a
  // merge on ACES with scans below 50 % inliers kept out of the map).
  void count_misses(Slam2dSummary& summary) {
    // Per hypothesis tested by this job: contradicted when every one of its tests contradicts it.
    std::map<int, bool> contradicted;
    for (std::size_t i = 0; i < job.searches.size(); ++i) {
      const int id = job.searches[i].hypothesis;
      if (id < 0) continue;
      const auto it = std::find_if(pending_merges.begin(), pending_merges.end(), [&](const PendingMerge& p) { return p.id == id; });
      if (it == pending_merges.end()) continue;
      // A contradiction is nothing above the minimum score where the placement says the keyframe
      // is, or a verified match elsewhere. A match rejected for degeneracy, ambiguity or a poor
      // fit says nothing either way (a corridor seen along its axis).
      const std::optional<LoopCandidate>& found = job.found[i];
      const core::SE2& T_world_tested = keyframes[static_cast<std::size_t>(job.searches[i].header.keyframe)].T_world_laser;
      if (!found && !near_odometry(it->delta, T_world_tested) &&
          !covered_by_group(group_of(it->group_a), it->delta * T_world_tested))
        continue;
      const bool against =
          !found || (found->accepted &&
                     !agree(it->delta * keyframes[static_cast<std::size_t>(found->keyframe)].T_world_laser, implied_pose(*found)));
      const auto [entry, fresh] = contradicted.emplace(id, against);
      if (!fresh) entry->second = entry->second && against;
    }
    for (const auto& [merge_id, against] : contradicted) {
      if (!against) continue;
      const auto id = merge_id;  // clang 14 cannot capture a structured binding in a lambda (C++20, P1381)
      const auto it = std::find_if(pending_merges.begin(), pending_merges.end(), [&](const PendingMerge& p) { return p.id == id; });
      if (it == pending_merges.end()) continue;
      ++it->misses;
      ++it->misses_in_a_row;
      if ((it->misses >= 2 && it->misses > static_cast<int>(it->candidates.size())) ||
          it->misses_in_a_row >= options.merge_max_misses_in_a_row) {
        for (const int c : it->candidates)
          summary.candidates[static_cast<std::size_t>(c)].reason =
              "verified across segments, but later keyframes did not find the place where this match put them; not merged";
        pending_merges.erase(it);
      }
    }
  }

  // A merge is as bad as a loop closure when wrong, and a place seen once may have a twin anywhere
  // in the old map (a floor plan symmetric under a half turn, identical rooms): before a merge the
  // confirming keyframe's scan is searched in every finished submap not of its own group, over
  // the whole submap and every heading, for a pose scoring within `loop_ambiguity_margin` of the
  // match elsewhere than where the merge would put it. Any such pose refuses the merge. Points
  // beyond `global_search_max_range_m` are left out of these searches (a coarser angle step,
  // Hess et al. 2016 eq. (7)), never of the verification.
  bool unique_over_map(int c, Slam2dSummary& summary) const {
    const LoopCandidate& candidate = summary.candidates[static_cast<std::size_t>(c)];
    const Keyframe& kf = keyframes[static_cast<std::size_t>(candidate.keyframe)];
    return unique_in_map(kf.matching, candidate.score, implied_pose(candidate),
                         group_of(submaps[static_cast<std::size_t>(candidate.submap)].segment), group_of(kf.segment), summary);
  }

  // The search of unique_over_map: `matching` placed at `T_world_match` with `score`; submaps of
  // `placed_group` exclude that place, submaps of `skipped_group` are not searched (-1: none).
  bool unique_in_map(const std::vector<Eigen::Vector2d>& matching, double score, const core::SE2& T_world_match, int placed_group,
                     int skipped_group, Slam2dSummary& summary) const {
    const std::vector<Eigen::Vector2d> near = within_range(matching, options.global_search_max_range_m);
    std::vector<int> others;
    for (int s = 0; s < static_cast<int>(submaps.size()); ++s) {
      const Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (submap.finished && !submap.empty && group_of(submap.segment) != skipped_group) others.push_back(s);
    }
    std::vector<char> competitor(others.size(), 0);
    const double threshold = std::max(options.loop_min_score, score) - options.loop_ambiguity_margin;
    tbb::parallel_for(std::size_t{0}, others.size(), [&](std::size_t i) {
      const Submap& submap = submaps[static_cast<std::size_t>(others[i])];
      BranchAndBoundOptions window;
      core::SE2 initial;
      global_window(submap.lower_anchor, submap.upper_anchor, 1.0, options.loop_search, window, initial);
      const core::SE2 T_anchor_world = keyframes[static_cast<std::size_t>(submap.anchor)].T_world_laser.inverse();
      // The place itself is excluded only in the placed group (other groups are not placed).
      const core::SE2 excluded = T_anchor_world * T_world_match;
      const bool same_group = group_of(submap.segment) == placed_group;
      const BranchAndBoundResult other =
          match_branch_and_bound(*submap.stack, near, initial, threshold, window, same_group ? &excluded : nullptr,
                                 options.loop_ambiguity_distance_m, options.loop_ambiguity_angle_rad);
      competitor[i] = other.found ? 1 : 0;
    });
    summary.uniqueness_searches += others.size();
    return std::find(competitor.begin(), competitor.end(), 1) == competitor.end();
  }

  bool unique_within_drift(const LoopCandidate& candidate, const SearchTask& task, Slam2dSummary& summary) const {
    const Keyframe& kf = keyframes[static_cast<std::size_t>(candidate.keyframe)];
    const int group = group_of(kf.segment);
    const core::SE2 T_world_match = implied_pose(candidate);
    std::vector<int> nearby;
    for (int s = 0; s < static_cast<int>(submaps.size()); ++s) {
      const Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (!submap.finished || submap.empty || group_of(submap.segment) != group) continue;
      const double radius = 0.5 * (submap.upper_anchor - submap.lower_anchor).norm();
      if ((submap_centre_world(submap) - kf.T_world_laser.translation()).norm() <= task.ambiguity_m + radius) nearby.push_back(s);
    }
    std::vector<char> competitor(nearby.size(), 0);
    const double threshold = std::max(options.loop_min_score, candidate.score) - options.loop_ambiguity_margin;
    tbb::parallel_for(std::size_t{0}, nearby.size(), [&](std::size_t i) {
      const Submap& submap = submaps[static_cast<std::size_t>(nearby[i])];
      const core::SE2 T_anchor_world = keyframes[static_cast<std::size_t>(submap.anchor)].T_world_laser.inverse();
      BranchAndBoundOptions window = options.loop_search;
      window.linear_search_window_m = task.ambiguity_m;
      window.angular_search_window_rad = std::min(task.ambiguity_rad, std::numbers::pi);
      const core::SE2 excluded = T_anchor_world * T_world_match;
      const BranchAndBoundResult other =
          match_branch_and_bound(*submap.stack, kf.matching, T_anchor_world * kf.T_world_laser, threshold, window, &excluded,
                                 options.loop_ambiguity_distance_m, options.loop_ambiguity_angle_rad);
      competitor[i] = other.found ? 1 : 0;
    });
    summary.uniqueness_searches += nearby.size();
    return std::find(competitor.begin(), competitor.end(), 1) == competitor.end();
  }

  static std::vector<Eigen::Vector2d> within_range(const std::vector<Eigen::Vector2d>& points, double range_m) {
    std::vector<Eigen::Vector2d> near;
    for (const auto& p : points)
      if (p.norm() <= range_m) near.push_back(p);
    return near.size() >= 10 ? near : points;
  }

  // Joins two groups: the one without segment 0 (whose first keyframe is fixed) is moved rigidly
  // by the confirmed placement, the matches become loop-closure edges and the graph is solved.
  void merge(const PendingMerge& confirmed, std::size_t scan, core::Timestamp time, Slam2dSummary& summary) {
    const int group_a = group_of(confirmed.group_a);
    const int group_b = group_of(confirmed.group_b);
    const bool move_b = group_of(0) != group_b;
    const core::SE2 D = move_b ? confirmed.delta : confirmed.delta.inverse();
    const int moved = move_b ? group_b : group_a;
    double moved_m = 0.0;
    for (Keyframe& kf : keyframes) {
      if (group_of(kf.segment) != moved) continue;
      const core::SE2 before = kf.T_world_laser;
      kf.T_world_laser = D * kf.T_world_laser;
      moved_m = (kf.T_world_laser.translation() - before.translation()).norm();
    }
    const std::string text = "accepted: merged segment group " + std::to_string(group_b) + " into " + std::to_string(group_a) +
                             " (" + std::to_string(confirmed.candidates.size()) + " agreeing matches)";
    for (const int c : confirmed.candidates) {
      LoopCandidate& candidate = summary.candidates[static_cast<std::size_t>(c)];
      candidate.accepted = true;
      candidate.reason = text;
      add_loop(c, summary);
    }
    join_groups(group_a, group_b);
    std::erase_if(pending_merges, [&](const PendingMerge& p) { return group_of(p.group_a) == group_of(p.group_b); });
    summary.merges.push_back({time, scan, group_a, group_b, confirmed.candidates, moved_m});
    optimize(false, summary);
    refresh_segments(summary);
  }

  // Why each segment not joined with segment 0 stayed apart (SegmentInfo::why_not_merged), from
  // the merge decisions of the matches its own keyframes found across segments.
  void explain_unmerged_segments(Slam2dSummary& summary) const {
    for (SegmentInfo& info : summary.segments) {
      info.why_not_merged.clear();
      if (info.merged_with == 0) continue;
      std::map<std::string, std::size_t> decisions;
      std::map<std::string, std::string> last_reason;
      for (const LoopCandidate& c : summary.candidates) {
        if (c.merge_decision.empty() || keyframes[static_cast<std::size_t>(c.keyframe)].segment != info.id) continue;
        ++decisions[c.merge_decision];
        last_reason[c.merge_decision] = c.reason;
      }
      const auto count = [&](const char* decision) { return decisions.count(decision) ? decisions.at(decision) : std::size_t{0}; };
      const std::size_t waiting = count("awaiting support") + count("competing placement") + count("awaiting the uniqueness test");
      if (info.merge_searches == 0 && decisions.empty()) {
        info.why_not_merged = "no merge search: no other segment's finished submap lay within merge_max_distance_m of its keyframes, "
                              "or the search budget was spent";
      } else if (decisions.empty()) {
        info.why_not_merged = "no candidate: " + std::to_string(info.merge_searches) +
                              " merge searches from its keyframes found no match above the minimum score";
      } else if (count("ambiguous") > 0) {
        info.why_not_merged = "ambiguous: a placement was confirmed " + std::to_string(count("ambiguous")) +
                              " times but another place scored within the margin elsewhere";
      } else if (waiting > 0) {
        const std::string last = count("awaiting support") > 0 ? last_reason.at("awaiting support")
                                 : count("competing placement") > 0 ? last_reason.at("competing placement")
                                                                     : last_reason.at("awaiting the uniqueness test");
        info.why_not_merged = "not enough support: " + std::to_string(waiting) + " verified matches; the last: " + last;
      } else {
        info.why_not_merged = "failed verification: " + std::to_string(count("failed verification") + count("superseded")) +
                              " candidates above the minimum score, none verified; the last: " +
                              (count("failed verification") > 0 ? last_reason.at("failed verification") : last_reason.at("superseded"));
      }
    }
  }

  void refresh_segments(Slam2dSummary& summary) const {
    for (SegmentInfo& info : summary.segments) {
      info.merged_with = group_of(info.id);
      bool first = true;
      for (const Keyframe& kf : keyframes) {
        if (kf.segment != info.id) continue;
        const Eigen::Vector2d t = kf.T_world_laser.translation();
        info.min_world = first ? t : info.min_world.cwiseMin(t);
        info.max_world = first ? t : info.max_world.cwiseMax(t);
        first = false;
      }
    }
  }

  // ---- The stages of Slam2d::add_scan, in order.

  /// Whether the scan has enough matching points to be matched.
  bool enough_points(const ScanWork& w) const {
    return static_cast<int>(w.points.matching.size()) >= options.min_matching_points;
  }

  /// 1. Local pose: odometry prediction, then ICP against the local map. The first scan is the
  /// map's origin.
  void predict_and_match(ScanWork& w) {
    if (have_previous) {
      w.predicted = previous_local * (previous_odom.inverse() * w.scan.T_odom_laser);
      w.T_local_laser = w.predicted;
      if (!local_map.empty() && enough_points(w)) match_local_map(w);
    } else {
      w.matched = true;
      w.record.inlier_fraction = 1.0;
      w.record.degeneracy = 0.5;
    }
  }

  /// ICP against the local map with the prediction as prior (restarted when it fits poorly); the
  /// match is accepted above lost_inlier_fraction.
  void match_local_map(ScanWork& w) {
    IcpResult icp = match_icp(local_map, w.points.matching, w.predicted, &w.predicted, options.icp);
    if (icp.inlier_fraction < options.degraded_min_inlier_fraction) restart_icp(w, icp);
    w.record.inlier_fraction = icp.inlier_fraction;
    w.record.degeneracy = icp.degeneracy;
    w.degenerate_direction = icp.degenerate_direction;
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(icp.hessian);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && icp.hessian.determinant() > 0.0)
      w.record.covariance = icp.hessian.inverse();
    if (icp.inlier_fraction >= options.lost_inlier_fraction) {
      w.T_local_laser = icp.T_map_sensor;
      w.match_hessian = icp.hessian;
      w.matched = true;
    }
  }

  /// ICP restarts from rotated guesses without the prior; a clearly better fit replaces `icp`.
  void restart_icp(ScanWork& w, IcpResult& icp) const {
    // The odometry prediction may be what is wrong (a stale, slipping or jumping odometry
    // reading): restart ICP from rotated guesses, without the prior, and keep a clearly
    // better fit. Without the prior nothing holds the pose along a direction the scan does
    // not constrain: a fit that ended farther than ICP's first search radius from the
    // prediction must pin the position (standard deviation from its Hessian within that
    // radius) to be a place rather than a slide. Kidnapping seed 4 of
    // bench/slam2d_recovery.py: a restart slid 6.2 m along the corridor (position sigma
    // 0.71 m), into a look-alike room where the next scans matched at 98 %, and 9 false loop
    // closures followed; MIT CSAIL's odometry jump at scan 1584 is a restart of 2.7 m pinned
    // to 0.025 m, and is kept.
    for (const double offset : {-0.35, -0.2, -0.1, 0.1, 0.2, 0.35}) {
      const core::SE2 guess(w.predicted.so2() * core::SO2(offset), w.predicted.translation());
      const IcpResult alternative = match_icp(local_map, w.points.matching, guess, nullptr, options.icp);
      const bool near = (alternative.T_map_sensor.translation() - w.predicted.translation()).norm() <= options.icp.max_correspondence_m;
      if (alternative.inlier_fraction > icp.inlier_fraction + 0.1 &&
          (near || pins_position(alternative.hessian, options.icp.max_correspondence_m))) {
        icp = alternative;
        w.restarted = true;
      }
    }
  }

  /// A failed match may be a jump or slip of the odometry: search the recent map over the loop
  /// window, verified like a loop closure (every failed scan until lost, then every 5th).
  void relocalise_after_failure(ScanWork& w, Slam2dSummary& summary) const {
    if (!(!w.matched && have_previous && enough_points(w) &&
          (bad_matches_in_a_row < options.lost_after_scans || bad_matches_in_a_row % 5 == 0)))
      return;
    LoopCandidate candidate;
    // A twin of the place farther than the window is excluded by the odometry (a slip of more
    // than the window is not one); within it the verification's ambiguity search covers it.
    const std::optional<core::SE2> T = relocalise_locally(w.points.matching, w.T_local_laser, candidate);
    if (T) {
      w.T_local_laser = *T;
      w.matched = true;
      w.record.inlier_fraction = candidate.inlier_fraction;
      w.record.degeneracy = candidate.degeneracy;
      ++summary.relocalisations;
      w.relocalised_reason = "relocalised in the recent map (score " + std::to_string(candidate.score) + ", inlier fraction " +
                             std::to_string(candidate.inlier_fraction) + ", moved " +
                             std::to_string((T->translation() - previous_local.translation()).norm()) + " m from the last pose)";
    }
  }

  /// A failed match whose rays, cast from the odometry prediction, cross none of the local map
  /// (Slam2dOptions::new_space_max_rays_through) sees only structure the map does not hold yet:
  /// in the sparse open stretch of issue 41 (outdoor-stretch with 10 features), 10-20 returns of
  /// a post or bench just come into range. A kidnapped robot's scan, cast from where the robot
  /// was, crosses the walls mapped around it. Points within 2 inlier distances of a ray (at least
  /// 2 cm, at most the point map's cell) count as on it; the last max_correspondence_m of a return's ray may be the same surface, misplaced by
  /// the odometry's error, and is not checked.
  void judge_failed_match(ScanWork& w) const {
    if (w.matched || !have_previous || local_map.empty() || !enough_points(w) || options.new_space_max_rays_through < 0.0) return;
    const double radius_m = std::clamp(2.0 * options.icp.inlier_distance_m, 0.02, options.map_points.cell_size_m);
    w.rays_through_map = rays_through_map(local_map, w.points, w.T_local_laser, radius_m, options.icp.max_correspondence_m);
    w.new_space = w.rays_through_map <= options.new_space_max_rays_through;
  }

  /// Notes where a stretch of failed matches begins; when matching resumes after one, the
  /// stretch is re-placed (replace_failed_stretch).
  void track_failed_stretch(const ScanWork& w) {
    if (have_previous && !w.matched && !w.new_space && enough_points(w)) {
      if (!failed_since_scan) {
        failed_since_scan = w.index;
        failed_since_keyframe = keyframes.size();
      }
    } else if (w.matched && failed_since_scan) {
      replace_failed_stretch(w.T_local_laser * w.predicted.inverse());
    }
  }

  /// 2. Health. A scan with too few returns to match (open space beyond the sensor's range)
  /// is no evidence of being lost: the pose follows odometry and the state says degraded.
  void assess_health(ScanWork& w) {
    w.too_few_returns = have_previous && static_cast<int>(w.points.matching.size()) < options.min_matching_points;
    if (w.odometry_only()) {
      // leave the failed-match counter as it is
    } else if (!w.matched) {
      ++bad_matches_in_a_row;
      failed_inlier_sum += w.record.inlier_fraction;
    } else {
      bad_matches_in_a_row = 0;
      failed_inlier_sum = 0.0;
    }
    if (w.too_few_returns) {
      w.next = Health::kDegraded;
      w.reason = "too few returns to match (" + std::to_string(w.points.matching.size()) + "); following odometry";
    } else if (w.new_space) {
      w.next = Health::kDegraded;
      w.reason = "the scan sees structure the local map does not hold (inlier fraction " + std::to_string(w.record.inlier_fraction) +
                 ") and contradicts none of it (" + std::to_string(w.rays_through_map) +
                 " of its rays pass through mapped points); following odometry";
    } else if (!w.matched || w.record.inlier_fraction < options.degraded_min_inlier_fraction) {
      w.next = Health::kDegraded;
      w.reason = "few scan points agree with the local map (inlier fraction " + std::to_string(w.record.inlier_fraction) + ")";
    } else if (w.record.degeneracy < options.degraded_min_degeneracy) {
      w.next = Health::kDegraded;
      w.reason = "degenerate geometry (degeneracy " + std::to_string(w.record.degeneracy) + "): the scan barely constrains " +
                 name_direction(w.degenerate_direction, w.T_local_laser) + "; odometry carries it";
    }
    if (w.next == Health::kOk && health == Health::kLost) w.reason = "matching recovered in segment " + std::to_string(segment);
    if (!w.relocalised_reason.empty()) {
      w.next = Health::kDegraded;  // one scan: the next one matching normally brings it back to ok
      w.reason = w.relocalised_reason;
    }
  }

  /// Lost: map on from this scan, in a new segment (or the current one restarted when it holds
  /// too little to keep). The segment is on probation until `segment_confirm_scans` scans in a
  /// row match its map well: a seed that does not match its successors (a burst of garbage, a
  /// scan of people crowding the sensor) is dropped from the map and the next scan seeds again.
  void supervise_segment(ScanWork& w, Slam2dSummary& summary) {
    const bool judged = have_previous && !w.odometry_only();
    const std::string segment_name = "map segment " + std::to_string(segment);
    if (probation > 0 && judged) {
      judge_probation(w, segment_name, summary);
    } else if (bad_matches_in_a_row >= options.lost_after_scans) {
      restart_after_loss(w, segment_name, summary);
    }
    if (w.start_segment) {
      local_map_start = static_cast<int>(keyframes.size());
      failed_since_scan.reset();  // the failed stretch keeps its odometry
    }
  }

  /// A scan judged while the segment is on probation: a good match counts towards establishing
  /// it; a poor one drops the seed, and this scan seeds the segment again.
  void judge_probation(ScanWork& w, const std::string& segment_name, Slam2dSummary& summary) {
    const bool good = w.matched && w.record.inlier_fraction >= options.degraded_min_inlier_fraction;
    bad_matches_in_a_row = 0;
    if (good && --probation == 0) {
      if (w.next == Health::kOk)
        w.reason = segment_name + " established: " + std::to_string(options.segment_confirm_scans) + " scans matched its map";
    } else if (good) {
      w.next = Health::kLost;
      w.reason = segment_name + " on probation: " + std::to_string(probation) + " more matching scans needed";
    } else {
      drop_growing_grids();
      for (std::size_t k = static_cast<std::size_t>(local_map_start); k < keyframes.size(); ++k) {
        keyframes[k].hits.clear();
        keyframes[k].misses.clear();
      }
      w.next = Health::kLost;
      w.start_segment = true;
      probation = options.segment_confirm_scans;
      summary.segments[static_cast<std::size_t>(segment)].odometry_link_trusted = true;
      w.reason = segment_name + " on probation: this scan does not match its seed; the seed is dropped and this scan seeds it";
    }
  }

  /// Matching failed lost_after_scans times in a row: a new segment when the current one holds
  /// enough to keep (start_new_segment), else the current one restarted; on probation either way.
  void restart_after_loss(ScanWork& w, const std::string& segment_name, Slam2dSummary& summary) {
    w.next = Health::kLost;
    w.start_segment = true;
    probation = options.segment_confirm_scans;
    w.reason = "scan matching failed " + std::to_string(bad_matches_in_a_row) + " times in a row; ";
    // The keyframes of the current segment that carry points since it (re)started.
    int mapped = 0;
    for (std::size_t k = static_cast<std::size_t>(local_map_start); k < keyframes.size(); ++k)
      if (!keyframes[k].hits.empty()) ++mapped;
    if (mapped >= options.min_segment_keyframes) {
      start_new_segment(w, summary);
    } else {
      w.reason += segment_name + " restarted from this scan (it had " + std::to_string(mapped) + " mapped keyframes)";
    }
    bad_matches_in_a_row = 0;
    failed_inlier_sum = 0.0;
  }

  /// Closes the current segment (its submaps are finished as they are, searchable from now) and
  /// starts a new one from this scan.
  void start_new_segment(ScanWork& w, Slam2dSummary& summary) {
    const int k = static_cast<int>(keyframes.size());
    join_builds(summary);
    join_job(summary);
    wait_for_ray_insertions();
    for (auto& submap : submaps)
      if (!submap.finished) finish_submap(submap);
    segment = static_cast<int>(summary.segments.size());
    segment_parent.push_back(segment);
    segment_first_keyframe = k;
    SegmentInfo info;
    info.id = segment;
    info.first_scan = w.index;
    info.first_keyframe = k;
    info.merged_with = segment;
    info.started_because = w.reason + "lost at scan " + std::to_string(w.index);
    // The failed matches still explained part of each scan at the odometry's prediction: the
    // robot is about where odometry says and the map fits poorly there. Otherwise trusted only
    // once a seed is dropped on probation (below).
    info.odometry_link_trusted =
        failed_inlier_sum / static_cast<double>(std::max(1, bad_matches_in_a_row)) >= options.segment_trusted_link_min_inlier_fraction;
    summary.segments.push_back(info);
    w.reason += "new map segment " + std::to_string(segment) + " started from this scan";
  }

  /// Records the scan's health (a health event when it changed) and counts the scan.
  void record_health(ScanWork& w, Slam2dSummary& summary) {
    set_health(w.next, w.index, w.scan.time, w.reason, summary);
    w.record.health = w.next;
    w.record.segment = segment;
    if (!w.matched && !w.odometry_only() && have_previous) lost_since_keyframe = true;
    if (w.new_space) ++summary.scans_new_space;
    if (w.next == Health::kOk) ++summary.scans_ok;
    if (w.next == Health::kDegraded) ++summary.scans_degraded;
    if (w.next == Health::kLost) ++summary.scans_lost;
    w.segment_info = &summary.segments[static_cast<std::size_t>(segment)];
    ++w.segment_info->scans;
  }

  /// Moves the front end on to this scan: the path travelled, the previous pose and odometry.
  void advance(const ScanWork& w) {
    if (have_previous) {
      const double step = (w.T_local_laser.translation() - previous_local.translation()).norm();
      path_length_m += step;
      w.segment_info->path_length_m += step;
    }
    previous_local = w.T_local_laser;
    previous_odom = w.scan.T_odom_laser;
    have_previous = true;
  }

  /// 3. Keyframe? The first scan, a (re)seeded segment, or far enough from the last keyframe.
  bool keyframe_due(const ScanWork& w) const {
    bool new_keyframe = keyframes.empty() || w.start_segment;
    if (!new_keyframe) {
      const Keyframe& last = keyframes.back();
      const core::SE2 delta = last.T_local_laser.inverse() * w.T_local_laser;
      new_keyframe = delta.translation().norm() >= options.keyframe_distance_m || std::abs(delta.angle()) >= options.keyframe_angle_rad;
    }
    return new_keyframe;
  }

  /// A new keyframe: the local map, the submaps, the optimisation and the searches follow it.
  void add_keyframe(ScanWork& w, Slam2dSummary& summary) {
    const int k = make_keyframe(w, summary);
    // The local map (front-end frame) is rebuilt first, while the previous keyframe's background
    // job still runs on the other core: it reads only front-end poses and points, which the job's
    // results (loop closures, merges: global poses) never change, so the order does not matter
    // to the result. On MIT CSAIL (a keyframe per scan) the front end used to wait for the job
    // first and rebuild the map afterwards, while the other core had nothing to do.
    const auto map_start = Clock::now();
    rebuild_local_map();
    summary.times.local_map_s += seconds_since(map_start);
    update_submaps(k, summary);
    if (loops_since_optimization > 0 && keyframes_since_optimization >= options.optimize_every_n_keyframes) optimize(false, summary);
    start_searches(k, w, summary);
    start_ray_insertions();  // after the searches, which the other core should take first
  }

  /// Makes the scan a keyframe, chained to the previous one by an odometry edge. Returns its index.
  int make_keyframe(ScanWork& w, Slam2dSummary& summary) {
    Keyframe kf;
    kf.time = w.scan.time;
    kf.T_local_laser = w.T_local_laser;
    // A scan that failed to match keeps its points out of the maps (it may be garbage, or
    // placed wrong); the keyframe still carries the pose chain. The first scan of a (re)started
    // segment is the segment's map. Its matching points are kept: relocalisation searches them.
    // A poor match found only by restarting ICP away from the odometry prediction places the pose
    // but not the points: half the scan disagreeing with the map after a jump is what a kidnapping
    // into a look-alike room looks like.
    const bool doubtful = w.restarted && w.record.inlier_fraction < options.degraded_min_inlier_fraction;
    const bool placed = (w.matched && !doubtful) || w.odometry_only() || w.start_segment;
    if (placed) {
      kf.hits = std::move(w.points.hits);
      kf.misses = std::move(w.points.misses);
    }
    kf.matching = std::move(w.points.matching);
    kf.path_length_m = path_length_m;
    kf.scan = w.index;
    kf.segment = segment;
    const int k = static_cast<int>(keyframes.size());
    if (k == 0) {
      kf.T_world_laser = w.T_local_laser;
    } else {
      chain_keyframe(kf, k, w.T_local_laser, w.match_hessian);
    }
    keyframes.push_back(std::move(kf));
    ++summary.keyframes;
    ++w.segment_info->keyframes;
    ++keyframes_since_optimization;
    return k;
  }

  /// Places keyframe `k` (not yet added) after the previous one by the front end's relative pose
  /// and adds the odometry edge between them, with the match's covariance unless the edge is weak.
  void chain_keyframe(Keyframe& kf, int k, const core::SE2& T_local_laser, const Eigen::Matrix3d& match_hessian) {
    const Keyframe& previous = keyframes.back();
    const core::SE2 T_prev_kf = previous.T_local_laser.inverse() * T_local_laser;
    kf.T_world_laser = previous.T_world_laser * T_prev_kf;
    Edge edge{k - 1, k, T_prev_kf, false, -1, lost_since_keyframe};
    if (!edge.weak) {
      // (H_scan + H_prior)^-1 in the local frame, rotated into the previous keyframe's frame.
      Eigen::Matrix3d H = match_hessian;
      if (options.icp.prior_translation_sigma_m > 0.0) {
        H(0, 0) += 1.0 / (options.icp.prior_translation_sigma_m * options.icp.prior_translation_sigma_m);
        H(1, 1) += 1.0 / (options.icp.prior_translation_sigma_m * options.icp.prior_translation_sigma_m);
        H(2, 2) += 1.0 / (options.icp.prior_rotation_sigma_rad * options.icp.prior_rotation_sigma_rad);
      }
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
      if (ldlt.info() == Eigen::Success && ldlt.isPositive() && H.determinant() > 0.0) {
        Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
        J.topLeftCorner<2, 2>() = previous.T_local_laser.so2().matrix().transpose();
        edge.match_covariance = J * H.inverse() * J.transpose();
      }
    }
    edges.push_back(edge);
    lost_since_keyframe = false;
  }

  /// Submaps: start one every half submap (counted from the segment's start); take the previous
  /// keyframe's background job; add keyframe `k` to the active submaps, queueing the full ones to
  /// be built.
  void update_submaps(int k, Slam2dSummary& summary) {
    const int half = std::max(1, options.submap_keyframes / 2);
    if ((k - segment_first_keyframe) % half == 0) {
      Submap submap;
      submap.anchor = k;
      submap.segment = segment;
      submap.grid = std::make_unique<ProbabilityGrid>(options.grid);
      submaps.push_back(std::move(submap));
      ++summary.submaps;
    }
    // Submaps whose install is due become searchable; then the previous keyframe's searches:
    // their loop closures and merges are taken now, before this keyframe plans its own.
    if (builds.running && k >= builds.install_at) join_builds(summary);
    join_job(summary);
    std::vector<SubmapSource> full;
    for (int s = 0; s < static_cast<int>(submaps.size()); ++s) {
      Submap& submap = submaps[static_cast<std::size_t>(s)];
      if (submap.finished || submap.building || k < submap.anchor) continue;
      submap.keyframes.push_back(k);
      if (static_cast<int>(submap.keyframes.size()) >= options.submap_keyframes) {
        wait_for_ray_insertions();
        full.push_back(submap_source(submap, s));
        submap.building = true;
      }
    }
    if (!full.empty()) {
      join_builds(summary);  // one batch at a time (a submap fills every submap_keyframes / 2 keyframes)
      builds.sources = std::move(full);
      start_builds(k + options.submap_install_delay_keyframes);
    }
  }

  /// Loop closure and merge searches, within the budget, planned for keyframe `k` and started in
  /// the background with the queued submap builds. A submap this keyframe finishes holds it, so
  /// it is not searched now anyway.
  void start_searches(int k, const ScanWork& w, Slam2dSummary& summary) {
    const auto plan_start = Clock::now();
    search_tokens = std::min(options.search_budget_burst, search_tokens + options.search_budget_per_keyframe);
    const std::vector<PlannedSearch> plan = plan_searches(k, summary);
    const auto matching = std::make_shared<const std::vector<Eigen::Vector2d>>(keyframes.back().matching);
    for (const PlannedSearch& search : plan) job.searches.push_back(make_search(k, search, matching));
    job.scan = w.index;
    job.time = w.scan.time;
    summary.times.loop_search_s += seconds_since(plan_start);
    start_job();
  }

  /// Records the scan relative to its keyframe (trajectory() and export read these records).
  void record_scan(ScanWork& w, Slam2dSummary& summary) {
    w.record.keyframe = static_cast<int>(keyframes.size()) - 1;
    w.record.keyframe_itself = w.new_keyframe;
    w.record.T_keyframe_laser = keyframes.back().T_local_laser.inverse() * w.T_local_laser;
    scans.push_back(w.record);
    ++summary.scans;
  }

  /// The scan's result, from its record.
  ScanResult scan_result(const ScanWork& w) const {
    const ScanRecord& record = w.record;
    ScanResult result;
    result.time = record.time;
    result.T_world_laser = keyframes.back().T_world_laser * record.T_keyframe_laser;
    result.health = record.health;
    result.inlier_fraction = record.inlier_fraction;
    result.degeneracy = record.degeneracy;
    result.covariance = record.covariance;
    result.keyframe = w.new_keyframe;
    result.segment = record.segment;
    return result;
  }

  void set_health(Health next, std::size_t scan, core::Timestamp time, const std::string& reason, Slam2dSummary& summary) {
    if (next == health) return;
    summary.health_events.push_back({time, scan, health, next, reason});
    health = next;
  }
};

Slam2d::Slam2d(const Slam2dOptions& options) {
  std::string error;
  if (!options.is_valid(&error)) throw std::invalid_argument("invalid slam2d options: " + error);
  impl_ = std::make_unique<Impl>(options);
  summary_.segments.push_back(SegmentInfo{});
}

Slam2d::~Slam2d() = default;

Health Slam2d::health() const { return impl_->health; }

ScanResult Slam2d::add_scan(const io::LaserScan& scan) {
  Impl& m = *impl_;
  const auto start = Clock::now();
  ScanWork w(scan, preprocess_scan(scan, m.options.filter), m.scans.size());
  summary_.times.preprocess_s += seconds_since(start);
  // 1. Local pose: predict from odometry, match against the local map, recover a failed match.
  const auto match_start = Clock::now();
  m.predict_and_match(w);
  m.relocalise_after_failure(w, summary_);
  m.judge_failed_match(w);
  m.track_failed_stretch(w);
  summary_.times.local_match_s += seconds_since(match_start);
  // 2. Health: of the match, then of the map segment.
  m.assess_health(w);
  m.supervise_segment(w, summary_);
  m.record_health(w, summary_);
  m.advance(w);
  // 3. Keyframe: local map, submaps, optimisation, loop and merge searches.
  w.new_keyframe = m.keyframe_due(w);
  if (w.new_keyframe) m.add_keyframe(w, summary_);
  m.record_scan(w, summary_);
  summary_.total_s += seconds_since(start);
  return m.scan_result(w);
}

void Slam2d::finish() {
  const auto start = Clock::now();
  impl_->join_builds(summary_);
  impl_->join_job(summary_);
  impl_->optimize(impl_->options.final_gnc, summary_);
  if (impl_->options.final_gnc) impl_->optimize(false, summary_);
  impl_->refresh_segments(summary_);
  impl_->explain_unmerged_segments(summary_);
  summary_.total_s += seconds_since(start);
}

std::vector<ScanResult> Slam2d::trajectory() const {
  std::vector<ScanResult> out;
  out.reserve(impl_->scans.size());
  for (const ScanRecord& r : impl_->scans) {
    ScanResult s;
    s.time = r.time;
    s.T_world_laser = impl_->keyframes[static_cast<std::size_t>(r.keyframe)].T_world_laser * r.T_keyframe_laser;
    s.health = r.health;
    s.inlier_fraction = r.inlier_fraction;
    s.degeneracy = r.degeneracy;
    s.covariance = r.covariance;
    s.keyframe = r.keyframe_itself;
    s.segment = r.segment;
    out.push_back(s);
  }
  return out;
}

io::PoseGraph2D Slam2d::pose_graph() const {
  io::PoseGraph2D graph;
  impl_->make_graph_problem(&graph);
  return graph;
}

ProbabilityGrid Slam2d::render_map(const ProbabilityGridOptions& options) const {
  ProbabilityGrid grid(options);
  std::vector<core::SE2> T_world_laser;
  std::vector<const std::vector<Eigen::Vector2d>*> hits, misses;
  for (const Keyframe& kf : impl_->keyframes) {
    T_world_laser.push_back(kf.T_world_laser);
    hits.push_back(&kf.hits);
    misses.push_back(&kf.misses);
  }
  // The pictures' crops keep a margin of unknown cells around the known ones (outputs.cpp: 10
  // cells in map.pgm); the grid a doubling made always held it, a reserved one must too.
  insert_rays(grid, T_world_laser, hits, misses, 64.0 * options.resolution_m);
  return grid;
}

SavedMap2D Slam2d::export_map() const {
  const Impl& m = *impl_;
  SavedMap2D map;
  map.grid = m.options.grid;
  map.map_points = m.options.map_points;
  map.filter = m.options.filter;
  for (const Keyframe& kf : m.keyframes) map.keyframes.push_back({kf.time, kf.T_world_laser, kf.segment});
  for (const Submap& submap : m.submaps) {
    const Keyframe& anchor = m.keyframes[static_cast<std::size_t>(submap.anchor)];
    SavedSubmap saved{anchor.T_world_laser, ProbabilityGrid(m.options.grid), {}, submap.segment, submap.anchor,
                      static_cast<int>(submap.keyframes.size())};
    std::vector<Eigen::Vector2d> points;
    for (const int k : submap.keyframes) {
      const Keyframe& kf = m.keyframes[static_cast<std::size_t>(k)];
      if (kf.hits.empty()) continue;
      const core::SE2 T_submap_laser = anchor.T_world_laser.inverse() * kf.T_world_laser;
      std::vector<Eigen::Vector2d> all = kf.hits;
      std::vector<bool> hit(all.size(), true);
      all.insert(all.end(), kf.misses.begin(), kf.misses.end());
      hit.resize(all.size(), false);
      saved.grid.insert(T_submap_laser, all, hit);
      for (const auto& p : kf.hits) points.push_back(T_submap_laser * p);
    }
    if (points.empty()) continue;
    saved.points_submap = voxel_filter(points, m.options.filter.voxel_size_m);
    map.submaps.push_back(std::move(saved));
  }
  return map;
}

}  // namespace cairn::slam2d
