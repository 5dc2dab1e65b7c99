#include "cairn/slam2d/slam.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cairn/backend/gnc.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

#include <tbb/parallel_for.h>

namespace cairn::slam2d {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

struct Keyframe {
  core::Timestamp time;
  core::SE2 T_local_laser;   ///< front-end pose (never corrected)
  core::SE2 T_world_laser;   ///< global estimate
  std::vector<Eigen::Vector2d> hits;
  std::vector<Eigen::Vector2d> misses;
  std::vector<Eigen::Vector2d> matching;
  double path_length_m = 0.0;  ///< travelled before this keyframe (front end)
  std::size_t scan = 0;
};

struct Submap {
  int anchor = 0;               ///< first keyframe
  std::vector<int> keyframes;
  bool finished = false;
  std::unique_ptr<PrecomputationGridStack> stack;
  std::unique_ptr<PointMap> points;  ///< in the anchor's frame
  Eigen::Vector2d centre_anchor = Eigen::Vector2d::Zero();
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
};

struct Edge {
  int from = 0;
  int to = 0;
  core::SE2 T_from_to;
  bool loop = false;
  int candidate = -1;  ///< index into summary.candidates
  /// Spans a scan whose match failed: odometry alone, possibly a slip or a kidnapping; kept only
  /// to connect the graph (sigma 10 m, 3 rad) so a relocalisation loop can move it freely.
  bool weak = false;
  /// Covariance of the keyframe's match in the `from` frame (x, y, theta); added to the
  /// odometry sigmas when edge_covariance_from_matcher is set.
  Eigen::Matrix3d match_covariance = Eigen::Matrix3d::Zero();
};

Eigen::Matrix3d information(double sigma_t, double sigma_r) {
  Eigen::Matrix3d info = Eigen::Matrix3d::Zero();
  info(0, 0) = info(1, 1) = 1.0 / (sigma_t * sigma_t);
  info(2, 2) = 1.0 / (sigma_r * sigma_r);
  return info;
}

}  // namespace

std::string_view to_string(Health health) {
  switch (health) {
    case Health::kOk: return "ok";
    case Health::kDegraded: return "degraded";
    case Health::kLost: return "lost";
  }
  return "?";
}

bool Slam2dOptions::is_valid(std::string* error) const {
  std::ostringstream problems;
  if (!(keyframe_distance_m > 0.0)) problems << "keyframe_distance_m must be > 0; ";
  if (!(keyframe_angle_rad > 0.0)) problems << "keyframe_angle_rad must be > 0; ";
  if (local_map_keyframes < 1) problems << "local_map_keyframes must be >= 1; ";
  if (submap_keyframes < 2) problems << "submap_keyframes must be >= 2; ";
  if (loop_search_every_n_keyframes < 1) problems << "loop_search_every_n_keyframes must be >= 1; ";
  if (!(loop_ambiguity_window_m >= 0.0)) problems << "loop_ambiguity_window_m must be >= 0; ";
  if (!(loop_min_score > 0.0 && loop_min_score < 1.0)) problems << "loop_min_score must be in (0, 1); ";
  if (!(relocalisation_min_score > 0.0 && relocalisation_min_score < 1.0)) problems << "relocalisation_min_score must be in (0, 1); ";
  if (!(odometry_translation_sigma_m > 0.0 && odometry_rotation_sigma_rad > 0.0 && loop_translation_sigma_m > 0.0 &&
        loop_rotation_sigma_rad > 0.0))
    problems << "edge sigmas must be > 0; ";
  if (optimize_every_n_keyframes < 1) problems << "optimize_every_n_keyframes must be >= 1; ";
  if (loop_max_submaps_per_search < 1) problems << "loop_max_submaps_per_search must be >= 1; ";
  if (min_matching_points < 3) problems << "min_matching_points must be >= 3; ";
  if (lost_after_scans < 1) problems << "lost_after_scans must be >= 1; ";
  if (!(icp.point_sigma_m > 0.0) || icp.max_iterations < 1) problems << "icp: point_sigma_m > 0, max_iterations >= 1; ";
  if (!(output_map_resolution_m > 0.0)) problems << "output map resolution must be > 0; ";
  if (!(grid.resolution_m > 0.0)) problems << "grid resolution must be > 0; ";
  if (!(map_points.cell_size_m >= icp.max_correspondence_m))
    problems << "map_points.cell_size_m must be >= icp.max_correspondence_m; ";
  const std::string text = problems.str();
  if (error != nullptr) *error = text;
  return text.empty();
}

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

  explicit Impl(const Slam2dOptions& o) : options(o), local_map(o.map_points) {}

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
    local_map.build(voxel_filter(points, options.filter.voxel_size_m));
  }

  void finish_submap(Submap& submap) {
    const core::SE2 T_anchor_local = keyframes[static_cast<std::size_t>(submap.anchor)].T_local_laser.inverse();
    ProbabilityGrid grid(options.grid);
    std::vector<Eigen::Vector2d> points;
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (const int k : submap.keyframes) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
      const core::SE2 T_anchor_laser = T_anchor_local * kf.T_local_laser;
      std::vector<Eigen::Vector2d> all = kf.hits;
      std::vector<bool> hit(all.size(), true);
      all.insert(all.end(), kf.misses.begin(), kf.misses.end());
      hit.resize(all.size(), false);
      grid.insert(T_anchor_laser, all, hit);
      for (const auto& p : kf.hits) points.push_back(T_anchor_laser * p);
      centre += T_anchor_laser.translation();
    }
    submap.centre_anchor = centre / static_cast<double>(submap.keyframes.size());
    submap.stack = std::make_unique<PrecomputationGridStack>(grid, options.loop_search);
    submap.points = std::make_unique<PointMap>(options.map_points);
    submap.points->build(voxel_filter(points, options.filter.voxel_size_m));
    submap.finished = true;
  }

  // Searches keyframe `k` against submap `s`; returns the verified (or rejected) candidate, or
  // nothing when the search finds no pose above the minimum score. Reads the state only, so the
  // searches of one keyframe run in parallel.
  std::optional<LoopCandidate> search_loop(int k, int s, bool relocalisation) const {
    const Submap& submap = submaps[static_cast<std::size_t>(s)];
    const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
    const Keyframe& anchor = keyframes[static_cast<std::size_t>(submap.anchor)];
    // The drift the estimate may have accumulated relative to the submap: the path travelled
    // since the submap, or since the last accepted loop closure when that is shorter.
    const double path = std::min(std::abs(kf.path_length_m - anchor.path_length_m),
                                 have_loop ? std::max(0.0, kf.path_length_m - last_loop_path_m) : 1e300);
    BranchAndBoundOptions window = options.loop_search;
    if (!relocalisation) {
      window.linear_search_window_m =
          std::min(options.loop_search.linear_search_window_m, options.loop_window_base_m + options.loop_window_drift_per_m * path);
      window.angular_search_window_rad = std::min(options.loop_search.angular_search_window_rad,
                                                  options.loop_angle_window_base_rad + options.loop_angle_window_drift_per_m * path);
    }
    const core::SE2 initial = anchor.T_world_laser.inverse() * kf.T_world_laser;
    LoopCandidate candidate;
    const double min_score = relocalisation ? options.relocalisation_min_score : options.loop_min_score;
    if (!search_and_verify(*submap.stack, *submap.points, kf.matching, initial, window, min_score, candidate)) return std::nullopt;
    candidate.keyframe = k;
    candidate.submap = s;
    candidate.anchor_keyframe = submap.anchor;
    candidate.time = kf.time;
    candidate.anchor_time = anchor.time;
    candidate.relocalisation = relocalisation;
    return candidate;
  }

  // Branch-and-bound search of `matching` in a map (grid stack + points, one frame) around
  // `initial`, then the loop-closure verification: ICP refinement without prior (inliers, RMS,
  // agreement with the search, degeneracy) and an ambiguity search. Fills the match fields of
  // `candidate`; returns false when the search finds nothing above `min_score`.
  bool search_and_verify(const PrecomputationGridStack& stack, const PointMap& map_points,
                         const std::vector<Eigen::Vector2d>& matching, const core::SE2& initial,
                         const BranchAndBoundOptions& window, double min_score, LoopCandidate& candidate) const {
    const BranchAndBoundResult best = match_branch_and_bound(stack, matching, initial, min_score, window);
    if (!best.found) return false;
    candidate.search_window_m = window.linear_search_window_m;
    candidate.score = best.score;
    // Verification 1: refine by ICP against the submap's points (no prior) and check the fit.
    IcpOptions refine = options.icp;
    refine.prior_translation_sigma_m = 0.0;
    const IcpResult icp = match_icp(map_points, matching, best.T_map_sensor, nullptr, refine);
    candidate.inlier_fraction = icp.inlier_fraction;
    candidate.rms_m = icp.rms_m;
    candidate.degeneracy = icp.degeneracy;
    candidate.T_anchor_keyframe = icp.T_map_sensor;
    const double moved = (icp.T_map_sensor.translation() - best.T_map_sensor.translation()).norm();
    if (icp.inlier_fraction < options.loop_min_inlier_fraction) {
      candidate.reason = "ICP inlier fraction below minimum";
    } else if (icp.rms_m > options.loop_max_rms_m) {
      candidate.reason = "ICP residual above maximum";
    } else if (moved > 2.0 * options.grid.resolution_m + 0.05) {
      candidate.reason = "ICP moved away from the branch-and-bound match";
    } else if (icp.degeneracy < options.loop_min_degeneracy) {
      candidate.reason = "degenerate: the match does not constrain every direction (corridor)";
    } else {
      // Verification 2: ambiguity. Is there a pose elsewhere in the window nearly as good?
      BranchAndBoundOptions wide = window;
      wide.linear_search_window_m = std::max(window.linear_search_window_m, options.loop_ambiguity_window_m);
      const BranchAndBoundResult other = match_branch_and_bound(
          stack, matching, initial, best.score - options.loop_ambiguity_margin, wide, &best.T_map_sensor,
          options.loop_ambiguity_distance_m, options.loop_ambiguity_angle_rad);
      candidate.second_score = other.found ? other.score : 0.0;
      if (other.found) {
        candidate.reason = "ambiguous: another pose scores within the margin";
      } else {
        candidate.accepted = true;
        candidate.reason = "accepted";
      }
    }
    return true;
  }

  // Tracking relocalisation: searches the scan in the map of the last keyframes that carry points
  // (front-end frame) over the loop-search window around `predicted`, with the loop verification.
  // Recovers a slip or jump of the odometry that the finished submaps do not cover yet (the
  // robot is usually still inside its active submap). Returns the verified pose or nothing.
  std::optional<core::SE2> relocalise_locally(const std::vector<Eigen::Vector2d>& matching, const core::SE2& predicted,
                                              LoopCandidate& candidate) const {
    ProbabilityGrid grid(options.grid);
    std::vector<Eigen::Vector2d> points;
    int used = 0;
    for (int k = static_cast<int>(keyframes.size()) - 1; k >= local_map_start && used < options.submap_keyframes; --k) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(k)];
      if (kf.hits.empty()) continue;
      ++used;
      std::vector<Eigen::Vector2d> all = kf.hits;
      std::vector<bool> hit(all.size(), true);
      all.insert(all.end(), kf.misses.begin(), kf.misses.end());
      hit.resize(all.size(), false);
      grid.insert(kf.T_local_laser, all, hit);
      for (const auto& p : kf.hits) points.push_back(kf.T_local_laser * p);
    }
    if (used == 0) return std::nullopt;
    const PrecomputationGridStack stack(grid, options.loop_search);
    PointMap map_points(options.map_points);
    map_points.build(voxel_filter(points, options.filter.voxel_size_m));
    const bool found =
        search_and_verify(stack, map_points, matching, predicted, options.loop_search, options.relocalisation_min_score, candidate);
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
        edge.information = information(10.0, 3.0);
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
    backend::OptimizerOptions solver;
    solver.max_iterations = 30;
    solver.function_tolerance = 1e-9;
    solver.threads = 1;
    solver.should_stop = options.should_stop;
    if (gnc) {
      backend::GncOptions gnc_options;
      gnc_options.inner = solver;
      const backend::GncSummary result = backend::optimize_gnc(problem, gnc_options);
      // Cut short, its weights are not a classification to act on: keep the graph as it was.
      if (result.interrupted) return;
      for (const std::size_t index : result.rejected_edges) {
        Edge& edge = edges[index];
        if (edge.candidate >= 0) summary.candidates[static_cast<std::size_t>(edge.candidate)].rejected_by_gnc = true;
      }
      summary.loops_rejected_by_gnc = result.rejected_edges.size();
      // Drop the rejected loops from the graph for good.
      std::vector<Edge> kept;
      for (std::size_t e = 0; e < edges.size(); ++e) {
        if (result.weights.empty() || result.weights[e] > 0.5 || !edges[e].loop) kept.push_back(edges[e]);
      }
      edges = std::move(kept);
    } else {
      backend::optimize(problem, solver);
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
}

Slam2d::~Slam2d() = default;

Health Slam2d::health() const { return impl_->health; }

ScanResult Slam2d::add_scan(const io::LaserScan& scan) {
  Impl& m = *impl_;
  const Slam2dOptions& o = m.options;
  const auto start = Clock::now();
  ScanPoints points = preprocess_scan(scan, o.filter);
  summary_.times.preprocess_s += seconds_since(start);
  const std::size_t scan_index = m.scans.size();
  ScanRecord record;
  record.time = scan.time;

  // 1. Local pose: odometry prediction, then ICP against the local map.
  core::SE2 T_local_laser = scan.T_odom_laser;
  const auto match_start = Clock::now();
  bool matched = false;
  core::SE2 predicted = T_local_laser;
  Eigen::Matrix3d match_hessian = Eigen::Matrix3d::Zero();  // scan term of the accepted match
  if (m.have_previous) {
    predicted = m.previous_local * (m.previous_odom.inverse() * scan.T_odom_laser);
    T_local_laser = predicted;
    if (!m.local_map.empty() && static_cast<int>(points.matching.size()) >= o.min_matching_points) {
      IcpResult icp = match_icp(m.local_map, points.matching, predicted, &predicted, o.icp);
      if (icp.inlier_fraction < o.degraded_min_inlier_fraction) {
        // The odometry prediction may be what is wrong (a stale or slipping odometry reading):
        // restart ICP from rotated guesses, without the prior, and keep a clearly better fit.
        for (const double offset : {-0.35, -0.2, -0.1, 0.1, 0.2, 0.35}) {
          const core::SE2 guess(predicted.so2() * core::SO2(offset), predicted.translation());
          const IcpResult alternative = match_icp(m.local_map, points.matching, guess, nullptr, o.icp);
          if (alternative.inlier_fraction > icp.inlier_fraction + 0.1) icp = alternative;
        }
      }
      record.inlier_fraction = icp.inlier_fraction;
      record.degeneracy = icp.degeneracy;
      const Eigen::LDLT<Eigen::Matrix3d> ldlt(icp.hessian);
      if (ldlt.info() == Eigen::Success && ldlt.isPositive() && icp.hessian.determinant() > 0.0)
        record.covariance = icp.hessian.inverse();
      if (icp.inlier_fraction >= o.lost_inlier_fraction) {
        T_local_laser = icp.T_map_sensor;
        match_hessian = icp.hessian;
        matched = true;
      }
    }
  } else {
    matched = true;
    record.inlier_fraction = 1.0;
    record.degeneracy = 0.5;
  }
  // A failed match may be a jump or slip of the odometry: search the recent map over the loop
  // window, verified like a loop closure (every failed scan until lost, then every 5th).
  std::string relocalised_reason;
  if (!matched && m.have_previous && static_cast<int>(points.matching.size()) >= o.min_matching_points &&
      (m.bad_matches_in_a_row < o.lost_after_scans || m.bad_matches_in_a_row % 5 == 0)) {
    LoopCandidate candidate;
    if (const auto T = m.relocalise_locally(points.matching, T_local_laser, candidate)) {
      T_local_laser = *T;
      matched = true;
      record.inlier_fraction = candidate.inlier_fraction;
      record.degeneracy = candidate.degeneracy;
      ++summary_.relocalisations;
      relocalised_reason = "relocalised in the recent map (score " + std::to_string(candidate.score) + ", inlier fraction " +
                           std::to_string(candidate.inlier_fraction) + ", moved " +
                           std::to_string((T->translation() - m.previous_local.translation()).norm()) + " m from the last pose)";
    }
  }
  if (m.have_previous && !matched && static_cast<int>(points.matching.size()) >= o.min_matching_points) {
    if (!m.failed_since_scan) {
      m.failed_since_scan = scan_index;
      m.failed_since_keyframe = m.keyframes.size();
    }
  } else if (matched && m.failed_since_scan) {
    m.replace_failed_stretch(T_local_laser * predicted.inverse());
  }
  summary_.times.local_match_s += seconds_since(match_start);

  // 2. Health. A scan with too few returns to match (open space beyond the sensor's range)
  // is no evidence of being lost: the pose follows odometry and the state says degraded.
  const bool too_few_returns = m.have_previous && static_cast<int>(points.matching.size()) < o.min_matching_points;
  if (too_few_returns) {
    // leave the failed-match counter as it is
  } else if (!matched) {
    ++m.bad_matches_in_a_row;
  } else {
    m.bad_matches_in_a_row = 0;
  }
  Health next = Health::kOk;
  std::string reason;
  if (m.bad_matches_in_a_row >= o.lost_after_scans) {
    next = Health::kLost;
    reason = "scan matching failed " + std::to_string(m.bad_matches_in_a_row) + " times in a row; following odometry";
  } else if (too_few_returns) {
    next = Health::kDegraded;
    reason = "too few returns to match (" + std::to_string(points.matching.size()) + "); following odometry";
  } else if (!matched || record.inlier_fraction < o.degraded_min_inlier_fraction) {
    next = Health::kDegraded;
    reason = "few scan points agree with the local map (inlier fraction " + std::to_string(record.inlier_fraction) + ")";
  } else if (record.degeneracy < o.degraded_min_degeneracy) {
    next = Health::kDegraded;
    reason = "degenerate geometry (degeneracy " + std::to_string(record.degeneracy) + "); odometry carries the unconstrained direction";
  }
  if (next == Health::kOk && m.health == Health::kLost) reason = "matching recovered";
  if (!relocalised_reason.empty()) {
    next = Health::kDegraded;  // one scan: the next one matching normally brings it back to ok
    reason = relocalised_reason;
  }
  m.set_health(next, scan_index, scan.time, reason, summary_);
  record.health = next;
  if (!matched && !too_few_returns && m.have_previous) m.lost_since_keyframe = true;
  if (next == Health::kOk) ++summary_.scans_ok;
  if (next == Health::kDegraded) ++summary_.scans_degraded;
  if (next == Health::kLost) ++summary_.scans_lost;

  if (m.have_previous) m.path_length_m += (T_local_laser.translation() - m.previous_local.translation()).norm();
  m.previous_local = T_local_laser;
  m.previous_odom = scan.T_odom_laser;
  m.have_previous = true;

  // 3. Keyframe?
  bool new_keyframe = m.keyframes.empty();
  if (!new_keyframe) {
    const Keyframe& last = m.keyframes.back();
    const core::SE2 delta = last.T_local_laser.inverse() * T_local_laser;
    new_keyframe = delta.translation().norm() >= o.keyframe_distance_m || std::abs(delta.angle()) >= o.keyframe_angle_rad;
  }
  if (new_keyframe) {
    Keyframe kf;
    kf.time = scan.time;
    kf.T_local_laser = T_local_laser;
    // A scan that failed to match keeps its points out of the maps (it may be garbage, or
    // placed wrong); the keyframe still carries the pose chain.
    // Its matching points are kept: relocalisation searches them against the submaps.
    const bool placed = matched || too_few_returns;
    if (placed) {
      kf.hits = std::move(points.hits);
      kf.misses = std::move(points.misses);
    }
    kf.matching = std::move(points.matching);
    kf.path_length_m = m.path_length_m;
    kf.scan = scan_index;
    const int k = static_cast<int>(m.keyframes.size());
    if (k == 0) {
      kf.T_world_laser = T_local_laser;
    } else {
      const Keyframe& previous = m.keyframes.back();
      const core::SE2 T_prev_kf = previous.T_local_laser.inverse() * T_local_laser;
      kf.T_world_laser = previous.T_world_laser * T_prev_kf;
      Edge edge{k - 1, k, T_prev_kf, false, -1, m.lost_since_keyframe};
      if (!edge.weak) {
        // (H_scan + H_prior)^-1 in the local frame, rotated into the previous keyframe's frame.
        Eigen::Matrix3d H = match_hessian;
        if (o.icp.prior_translation_sigma_m > 0.0) {
          H(0, 0) += 1.0 / (o.icp.prior_translation_sigma_m * o.icp.prior_translation_sigma_m);
          H(1, 1) += 1.0 / (o.icp.prior_translation_sigma_m * o.icp.prior_translation_sigma_m);
          H(2, 2) += 1.0 / (o.icp.prior_rotation_sigma_rad * o.icp.prior_rotation_sigma_rad);
        }
        const Eigen::LDLT<Eigen::Matrix3d> ldlt(H);
        if (ldlt.info() == Eigen::Success && ldlt.isPositive() && H.determinant() > 0.0) {
          Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
          J.topLeftCorner<2, 2>() = previous.T_local_laser.so2().matrix().transpose();
          edge.match_covariance = J * H.inverse() * J.transpose();
        }
      }
      m.edges.push_back(edge);
      m.lost_since_keyframe = false;
    }
    m.keyframes.push_back(std::move(kf));
    ++summary_.keyframes;
    ++m.keyframes_since_optimization;
    const auto map_start = Clock::now();
    m.rebuild_local_map();
    summary_.times.local_map_s += seconds_since(map_start);

    // Submaps: start one every half submap; add the keyframe to the active ones.
    const auto submap_start = Clock::now();
    const int half = std::max(1, o.submap_keyframes / 2);
    if (k % half == 0) {
      Submap submap;
      submap.anchor = k;
      m.submaps.push_back(std::move(submap));
      ++summary_.submaps;
    }
    for (auto& submap : m.submaps) {
      if (submap.finished || k < submap.anchor) continue;
      submap.keyframes.push_back(k);
      if (static_cast<int>(submap.keyframes.size()) >= o.submap_keyframes) m.finish_submap(submap);
    }
    summary_.times.submap_s += seconds_since(submap_start);

    // Loop closure (or relocalisation when lost).
    const auto loop_start = Clock::now();
    const bool lost = m.health == Health::kLost;
    if (lost || k % o.loop_search_every_n_keyframes == 0) {
      const Keyframe& current = m.keyframes.back();
      // Finished submaps not containing the keyframe, nearest first (by the current estimate).
      std::vector<std::pair<double, int>> nearby;
      for (int s = 0; s < static_cast<int>(m.submaps.size()); ++s) {
        const Submap& submap = m.submaps[static_cast<std::size_t>(s)];
        if (!submap.finished) continue;
        if (std::find(submap.keyframes.begin(), submap.keyframes.end(), k) != submap.keyframes.end()) continue;
        const Keyframe& anchor = m.keyframes[static_cast<std::size_t>(submap.anchor)];
        const double distance = ((anchor.T_world_laser * submap.centre_anchor) - current.T_world_laser.translation()).norm();
        if (!lost && distance > o.loop_max_distance_m) continue;
        nearby.emplace_back(distance, s);
      }
      std::sort(nearby.begin(), nearby.end());
      if (!lost) {
        // The nearest submaps are usually the ones just built on the way here; keep the nearest
        // of those and fill the rest of the budget with submaps from earlier visits.
        std::vector<std::pair<double, int>> chosen;
        int recent = 0;
        for (const auto& entry : nearby) {
          if (static_cast<int>(chosen.size()) >= o.loop_max_submaps_per_search) break;
          const Keyframe& anchor = m.keyframes[static_cast<std::size_t>(m.submaps[static_cast<std::size_t>(entry.second)].anchor)];
          const bool is_recent = current.path_length_m - anchor.path_length_m < 2.0 * o.loop_max_distance_m;
          if (is_recent && recent++ >= 1) continue;
          chosen.push_back(entry);
        }
        nearby = std::move(chosen);
      }
      // The searches are independent: run them in parallel, then take their results in order.
      // All searches of one keyframe size their window from the state before any of them (a loop
      // accepted by one does not narrow the windows of the others), so the run is deterministic.
      std::vector<std::optional<LoopCandidate>> found(nearby.size());
      tbb::parallel_for(std::size_t{0}, nearby.size(), [&](std::size_t i) { found[i] = m.search_loop(k, nearby[i].second, lost); });
      for (std::size_t i = 0; i < nearby.size(); ++i) {
        const int s = nearby[i].second;
        const Submap& submap = m.submaps[static_cast<std::size_t>(s)];
        const Keyframe& anchor = m.keyframes[static_cast<std::size_t>(submap.anchor)];
        ++summary_.loop_searches;
        if (!found[i]) continue;
        summary_.candidates.push_back(*found[i]);
        const int c = static_cast<int>(summary_.candidates.size()) - 1;
        LoopCandidate& candidate = summary_.candidates.back();
        if (!candidate.accepted) continue;
        m.edges.push_back({submap.anchor, k, candidate.T_anchor_keyframe, true, c});
        ++summary_.loops_accepted;
        ++m.loops_since_optimization;
        // A loop to an earlier visit bounds the drift relative to the old map; a loop to a
        // submap built on the way here does not.
        if (m.keyframes.back().path_length_m - anchor.path_length_m >= 2.0 * o.loop_max_distance_m) {
          m.have_loop = true;
          m.last_loop_path_m = m.keyframes.back().path_length_m;
        }
        if (lost) {
          // Relocalised: place the keyframe where the submap says, restart the local map there.
          ++summary_.relocalisations;
          Keyframe& relocalised = m.keyframes.back();
          relocalised.T_world_laser = anchor.T_world_laser * candidate.T_anchor_keyframe;
          if (!placed) {
            // Verified against the map: its points are trustworthy now.
            relocalised.hits = std::move(points.hits);
            relocalised.misses = std::move(points.misses);
          }
          m.local_map_start = k;
          m.rebuild_local_map();
          m.failed_since_scan.reset();  // placed by the submap; the stretch keeps its odometry
          m.bad_matches_in_a_row = 0;
          m.set_health(Health::kDegraded, scan_index, scan.time, "relocalised against submap " + std::to_string(s), summary_);
          break;
        }
      }
    }
    summary_.times.loop_search_s += seconds_since(loop_start);
    if (m.loops_since_optimization > 0 && m.keyframes_since_optimization >= o.optimize_every_n_keyframes) m.optimize(false, summary_);
  }

  record.keyframe = static_cast<int>(m.keyframes.size()) - 1;
  record.keyframe_itself = new_keyframe;
  record.T_keyframe_laser = m.keyframes.back().T_local_laser.inverse() * T_local_laser;
  m.scans.push_back(record);
  ++summary_.scans;
  summary_.total_s += seconds_since(start);

  ScanResult result;
  result.time = record.time;
  result.T_world_laser = m.keyframes.back().T_world_laser * record.T_keyframe_laser;
  result.health = record.health;
  result.inlier_fraction = record.inlier_fraction;
  result.degeneracy = record.degeneracy;
  result.covariance = record.covariance;
  result.keyframe = new_keyframe;
  return result;
}

void Slam2d::finish() {
  const auto start = Clock::now();
  impl_->optimize(impl_->options.final_gnc, summary_);
  if (impl_->options.final_gnc) impl_->optimize(false, summary_);
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
  for (const Keyframe& kf : impl_->keyframes) {
    std::vector<Eigen::Vector2d> all = kf.hits;
    std::vector<bool> hit(all.size(), true);
    all.insert(all.end(), kf.misses.begin(), kf.misses.end());
    hit.resize(all.size(), false);
    grid.insert(kf.T_world_laser, all, hit);
  }
  return grid;
}

}  // namespace cairn::slam2d
