#include "cairn/slam2d/localization.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "cairn/core/so2.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/slam2d/branch_and_bound.hpp"
#include "cairn/slam2d/icp.hpp"
#include "cairn/slam2d/place_search.hpp"
#include "cairn/slam2d/point_map.hpp"
#include "cairn/slam2d/range_scan.hpp"

namespace cairn::slam2d {
namespace {

using core::Clock;
using core::seconds_since;

std::string fixed(double value, int decimals) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(decimals);
  s << value;
  return s.str();
}

// A max-pooled copy of `fine`: cells `factor` times larger, each holding the largest probability
// of its known fine cells (unknown when none is known). Scores against it bound those against
// the fine grid from above, up to the coarser angular step (the multi-resolution idea of Olson,
// ICRA 2009, applied across submaps).
ProbabilityGrid max_pooled(const ProbabilityGrid& fine, int factor) {
  ProbabilityGridOptions options = fine.options();
  options.resolution_m *= factor;
  int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
  if (!fine.known_bounds(i0, j0, i1, j1)) return ProbabilityGrid(options);
  const auto floor_div = [factor](long a) { return a >= 0 ? a / factor : -((-a + factor - 1) / factor); };
  const long ci0 = floor_div(fine.offset_i() + i0), cj0 = floor_div(fine.offset_j() + j0);
  const int width = static_cast<int>(floor_div(fine.offset_i() + i1) - ci0 + 1);
  const int height = static_cast<int>(floor_div(fine.offset_j() + j1) - cj0 + 1);
  std::vector<double> largest(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), -1.0);
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      if (!fine.cell_known(i, j)) continue;
      const long ci = floor_div(fine.offset_i() + i) - ci0, cj = floor_div(fine.offset_j() + j) - cj0;
      double& p = largest[static_cast<std::size_t>(cj * width + ci)];
      p = std::max(p, fine.cell_probability(i, j));
    }
  }
  std::vector<float> log_odds(largest.size(), 0.0f);
  std::vector<std::uint8_t> known(largest.size(), 0);
  for (std::size_t k = 0; k < largest.size(); ++k) {
    if (largest[k] < 0.0) continue;
    const double l = std::log(largest[k] / (1.0 - largest[k]));
    log_odds[k] = static_cast<float>(std::clamp(l, fine.min_log_odds(), fine.max_log_odds()));
    known[k] = 1;
  }
  return ProbabilityGrid::from_cells(options, ci0, cj0, width, height, std::move(log_odds), std::move(known));
}

// Below this occupancy probability an observed cell counts as empty: with the default grid (a hit
// raises the log-odds by 0.20, a miss lowers them by 0.04) a cell below 0.4 was crossed by at
// least 5 times as many rays as ended in it, plus 10.
constexpr double kFreeProbability = 0.4;

// Whether `p_grid` (grid frame) lies in a cell of `grid` whose 3 x 3 neighbourhood is all observed
// and empty (kFreeProbability): where the map saw through. The neighbourhood keeps a point on a
// wall, a cell or so off after noise and voxel filtering, from counting; unobserved cells never
// count (the map may lack a place; it does not contradict it).
bool in_observed_empty_space(const ProbabilityGrid& grid, const Eigen::Vector2d& p_grid) {
  const double r = grid.resolution();
  const double gi = std::floor(p_grid.x() / r) - static_cast<double>(grid.offset_i());
  const double gj = std::floor(p_grid.y() / r) - static_cast<double>(grid.offset_j());
  if (!(gi >= 1.0 && gj >= 1.0 && gi < grid.width() - 1 && gj < grid.height() - 1)) return false;
  const int i = static_cast<int>(gi), j = static_cast<int>(gj);
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di)
      if (!grid.cell_known(i + di, j + dj) || grid.cell_probability(i + di, j + dj) >= kFreeProbability) return false;
  return true;
}

// The fraction of `points_sensor` that, placed at `T_grid_sensor`, land in observed empty space
// of `grid` (in_observed_empty_space): the scan sees something where the map saw through.
double free_space_fraction(const ProbabilityGrid& grid, const std::vector<Eigen::Vector2d>& points_sensor,
                           const core::SE2& T_grid_sensor) {
  if (points_sensor.empty()) return 0.0;
  std::size_t in_free = 0;
  for (const Eigen::Vector2d& p_sensor : points_sensor)
    if (in_observed_empty_space(grid, T_grid_sensor * p_sensor)) ++in_free;
  return static_cast<double>(in_free) / static_cast<double>(points_sensor.size());
}

}  // namespace

bool Localizer2dOptions::is_valid(std::string* error) const {
  std::ostringstream problems;
  std::string matching_error;
  if (!matching.is_valid(&matching_error)) problems << matching_error;
  if (!(tracking_min_inlier_fraction >= 0.0 && tracking_min_inlier_fraction <= ok_min_inlier_fraction &&
        ok_min_inlier_fraction <= 1.0))
    problems << "need 0 <= tracking_min_inlier_fraction <= ok_min_inlier_fraction <= 1; ";
  if (!(verification_min_inlier_fraction >= 0.0 && verification_min_inlier_fraction <= 1.0))
    problems << "verification_min_inlier_fraction must be in [0, 1]; ";
  if (!(verification_min_degeneracy >= 0.0 && verification_min_degeneracy <= 0.5))
    problems << "verification_min_degeneracy must be in [0, 0.5]; ";
  if (!(verification_max_free_fraction >= 0.0 && verification_max_free_fraction <= 1.0))
    problems << "verification_max_free_fraction must be in [0, 1]; ";
  if (global_searches_per_scan < 1) problems << "global_searches_per_scan must be >= 1; ";
  if (round_robin_searches_per_scan < 0 || round_robin_searches_per_scan > global_searches_per_scan)
    problems << "round_robin_searches_per_scan must be in [0, global_searches_per_scan]; ";
  if (coarse_cell_factor < 1 || coarse_cell_factor > 64) problems << "coarse_cell_factor must be in [1, 64]; ";
  if (coarse_depth < 1 || coarse_depth > 12) problems << "coarse_depth must be in [1, 12]; ";
  if (check_every_n_scans < 1) problems << "check_every_n_scans must be >= 1; ";
  if (!(global_search_margin_m >= 0.0)) problems << "global_search_margin_m must be >= 0; ";
  if (confirmations < 1) problems << "confirmations must be >= 1; ";
  if (!(agreement_m > 0.0)) problems << "agreement_m must be > 0; ";
  if (!(agreement_rad > 0.0)) problems << "agreement_rad must be > 0; ";
  if (!(confirmation_window_m >= 0.0)) problems << "confirmation_window_m must be >= 0; ";
  if (!(confirmation_window_rad >= 0.0)) problems << "confirmation_window_rad must be >= 0; ";
  if (max_hypotheses < 1) problems << "max_hypotheses must be >= 1; ";
  if (!(look_alike_min_observed_fraction > 0.0 && look_alike_min_observed_fraction <= 1.0))
    problems << "look_alike_min_observed_fraction must be in (0, 1]; ";
  if (look_alike_places < 0) problems << "look_alike_places must be >= 0; ";
  if (!(hypothesis_drop_deficit > 0.0)) problems << "hypothesis_drop_deficit must be > 0; ";
  if (hypothesis_drop_window_scans < 1) problems << "hypothesis_drop_window_scans must be >= 1; ";
  const std::string text = problems.str();
  if (error != nullptr) *error = text;
  return text.empty();
}

std::string_view to_string(LocalizationState state) {
  switch (state) {
    case LocalizationState::kSearching: return "searching";
    case LocalizationState::kTracking: return "tracking";
  }
  return "unknown";
}

struct Localizer2d::Impl {
  core::PageArena stack_memory;  ///< the submaps' precomputation grids, on huge pages
  struct Submap {
    core::SE2 T_world_submap;
    std::unique_ptr<PrecomputationGridStack> stack;
    std::unique_ptr<PrecomputationGridStack> coarse_stack;  ///< of the max-pooled grid (ranking)
    std::unique_ptr<PointMap> points;  ///< submap frame
    Eigen::Vector2d lower_submap = Eigen::Vector2d::Zero();  ///< observed extent, submap frame
    Eigen::Vector2d upper_submap = Eigen::Vector2d::Zero();
    Eigen::Vector2d path_lower_submap = Eigen::Vector2d::Zero();  ///< keyframe positions' box, submap frame
    Eigen::Vector2d path_upper_submap = Eigen::Vector2d::Zero();
    Eigen::Vector2d centre_world = Eigen::Vector2d::Zero();  ///< of the path box
  };
  /// A place the coarse ranking found: its coarse score, submap and pose.
  struct Ranked {
    double score = 0.0;
    int submap = 0;
    core::SE2 T_map_laser;
  };
  /// Poses closer than this are one place (overlapping submaps see the same place).
  static constexpr double kPlaceSeparation_m = 2.0;

  /// A place the robot may be: where the odometry frame lies in the map.
  struct Hypothesis {
    core::SE2 T_map_odom;
    int support = 0;                 ///< distinct scans with a verified match that agrees
    std::size_t last_support_scan = 0;
    std::size_t created_scan = 0;
    int failures = 0;                ///< scans in a row that did not fit (ICP) here
    double inlier_fraction = 0.0;    ///< of this scan's ICP match here
    std::deque<double> deficits;     ///< best place's inlier fraction minus this one's, last scans
    int last_submap = -1;            ///< searchable-submap index of the last supporting match
    std::vector<LocalizationMatch> evidence;
    /// A partly mapped place that explained what the map observed of the scans when this
    /// hypothesis was last up for acceptance (partly_mapped_look_alike), as T_map_odom.
    std::optional<core::SE2> look_alike_T_map_odom;
  };

  SavedMap2D map;
  Localizer2dOptions options;
  Slam2dOptions matching;  ///< options.matching with the map's filter, point-map and grid settings
  std::vector<Submap> submaps;    ///< searchable submaps (with points and an observed grid)
  std::vector<int> submap_index;  ///< index into map.submaps of each searchable submap
  PointMap tracking_map;          ///< every submap's points, map frame
  struct CoarseOptions {
    BranchAndBoundOptions search;     ///< matching.loop_search with the coarse depth
    double cell_m = 0.4;  ///< cell of the max-pooled grids
  } coarse_options;

  LocalizationState state = LocalizationState::kSearching;
  Health health = Health::kLost;
  std::size_t scan_index = 0;
  core::SE2 T_map_laser;       ///< last pose (tracking)
  core::SE2 previous_odom;
  int failures_in_a_row = 0;
  /// Tracking: a match put scan points where the map saw empty space, and no scan has verified
  /// the tracked pose since (see add_scan); the pose is at most `degraded` meanwhile.
  bool contradicted = false;
  /// The prior for the search order: the map-from-odometry transform before being lost.
  std::optional<core::SE2> prior_T_map_odom;
  bool order_stale = true;
  std::vector<int> spread_order;  ///< into `submaps`, farthest-point order
  std::vector<int> search_order;  ///< into `submaps`, the current search's order
  std::size_t next_search = 0;
  std::size_t next_check = 0;     ///< position in spread_order of the tracking check
  std::size_t searching_since = 0;
  std::vector<Hypothesis> hypotheses;  ///< while searching: candidates; while tracking: rivals
  std::vector<core::SE2> refuted;      ///< T_map_odom of rivals refuted while tracking (the last 4)
  std::vector<Ranked> ranking;         ///< the current scan's coarse ranking (places, best first)
  static constexpr int kAlternatives = 4;  ///< places ranked per searching scan (searched or tested)
  std::size_t hypotheses_died = 0;     ///< since the current search started

  Impl(SavedMap2D saved, const Localizer2dOptions& o)
      : map(std::move(saved)), options(o), matching(o.matching), tracking_map(map.map_points) {
    matching.filter = map.filter;
    matching.map_points = map.map_points;
    matching.grid = map.grid;
    matching.loop_min_degeneracy = o.verification_min_degeneracy;
    matching.loop_min_inlier_fraction = o.verification_min_inlier_fraction;
    coarse_options.search = matching.loop_search;
    coarse_options.search.depth = o.coarse_depth;
    coarse_options.cell_m = map.grid.resolution_m * o.coarse_cell_factor;
  }

  bool agrees(const core::SE2& a, const core::SE2& b) const {
    return (a.translation() - b.translation()).norm() <= options.agreement_m &&
           std::abs(core::wrap_angle(a.angle() - b.angle())) <= options.agreement_rad;
  }

  // Farthest-point order over the submaps' path centres (each next submap the one farthest from
  // those already in the order), so that the first searches sample the whole map coarsely
  // instead of one corridor's overlapping submaps. Built once.
  void make_spread_order() {
    const std::size_t n = submaps.size();
    spread_order.clear();
    std::vector<double> distance(n, std::numeric_limits<double>::infinity());
    std::vector<bool> taken(n, false);
    std::size_t next = 0;
    for (std::size_t k = 0; k < n; ++k) {
      spread_order.push_back(static_cast<int>(next));
      taken[next] = true;
      std::size_t farthest = next;
      double farthest_distance = -1.0;
      for (std::size_t s = 0; s < n; ++s) {
        if (taken[s]) continue;
        distance[s] = std::min(distance[s], (submaps[s].centre_world - submaps[next].centre_world).norm());
        if (distance[s] > farthest_distance) {
          farthest_distance = distance[s];
          farthest = s;
        }
      }
      next = farthest;
    }
  }

  // The order of the global search: with a prior, nearest path centre first; else the spread order.
  void make_search_order(const core::SE2& odom) {
    search_order = spread_order;
    if (prior_T_map_odom) {
      const Eigen::Vector2d at = (*prior_T_map_odom * odom).translation();
      std::stable_sort(search_order.begin(), search_order.end(), [&](int a, int b) {
        return (submaps[static_cast<std::size_t>(a)].centre_world - at).squaredNorm() <
               (submaps[static_cast<std::size_t>(b)].centre_world - at).squaredNorm();
      });
    }
    next_search = 0;
    order_stale = false;
  }

  // Whether submap `s`'s observed extent holds `p_world`.
  bool holds(int s, const Eigen::Vector2d& p_world) const {
    const Submap& submap = submaps[static_cast<std::size_t>(s)];
    const Eigen::Vector2d p = submap.T_world_submap.inverse() * p_world;
    return (p.array() >= submap.lower_submap.array()).all() && (p.array() <= submap.upper_submap.array()).all();
  }

  // The searchable submap whose observed extent holds `p_world`, nearest path centre first; -1
  // if none.
  int submap_holding(const Eigen::Vector2d& p_world) const {
    int best = -1;
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t s = 0; s < submaps.size(); ++s) {
      if (!holds(static_cast<int>(s), p_world)) continue;
      const double d = (submaps[s].centre_world - p_world).squaredNorm();
      if (d < best_distance) {
        best_distance = d;
        best = static_cast<int>(s);
      }
    }
    return best;
  }

  // The whole-submap window of submap `s` (its path box plus margin, clamped to its observed
  // extent; every heading) with `base`'s depth and unknown probability.
  void whole_submap_window(int s, const BranchAndBoundOptions& base, BranchAndBoundOptions& window, core::SE2& initial) const {
    const Submap& submap = submaps[static_cast<std::size_t>(s)];
    const Eigen::Vector2d lower =
        (submap.path_lower_submap.array() - options.global_search_margin_m).max(submap.lower_submap.array());
    const Eigen::Vector2d upper =
        (submap.path_upper_submap.array() + options.global_search_margin_m).min(submap.upper_submap.array());
    global_window(lower, upper, 0.0, base, window, initial);
  }

  // The `count` submaps whose max-pooled grids score the scan best over their whole window
  // (branch and bound on the coarse grids; each search prunes below the `count`-th best score
  // so far, and below matching.loop_min_score), best first, at most one per place: a result
  // whose pose lies within 2 m of a better one is dropped (overlapping submaps see the same
  // place), so that the searches go to different places, a look-alike place among them
  // (which then becomes a rival hypothesis instead of being missed).
  std::vector<Ranked> rank_submaps(const std::vector<Eigen::Vector2d>& points, int count, Localizer2dSummary& summary) const {
    const auto start = Clock::now();
    const std::vector<Eigen::Vector2d> coarse_points = voxel_filter(points, 0.5 * coarse_options.cell_m);
    std::vector<Ranked> best;  // best first, at most `count`, pairwise farther apart than the separation
    for (std::size_t s = 0; s < submaps.size(); ++s) {
      BranchAndBoundOptions window;
      core::SE2 initial;
      whole_submap_window(static_cast<int>(s), coarse_options.search, window, initial);
      // A result below the weakest kept one could only enter by replacing a weaker neighbour.
      const double threshold = static_cast<int>(best.size()) >= count ? std::max(matching.loop_min_score, best.back().score)
                                                                       : matching.loop_min_score;
      const BranchAndBoundResult result =
          match_branch_and_bound(*submaps[s].coarse_stack, coarse_points, initial, threshold, window);
      if (!result.found) continue;
      const Ranked entry{result.score, static_cast<int>(s), submaps[s].T_world_submap * result.T_map_sensor};
      const auto near = [&](const Ranked& other) {
        return (other.T_map_laser.translation() - entry.T_map_laser.translation()).norm() < kPlaceSeparation_m;
      };
      if (std::any_of(best.begin(), best.end(), [&](const Ranked& other) { return near(other) && other.score >= entry.score; }))
        continue;
      std::erase_if(best, near);
      best.push_back(entry);
      std::stable_sort(best.begin(), best.end(), [](const Ranked& a, const Ranked& b) { return a.score > b.score; });
      if (static_cast<int>(best.size()) > count) best.pop_back();
    }
    ++summary.rankings;
    summary.times.ranking_s += seconds_since(start);
    return best;
  }

  // One search of `points` in submap `s`: global (the submap's path box plus margin, every
  // heading) or windowed around `T_map_guess`; the verified pose in the map frame, or nothing.
  std::optional<LocalizationMatch> search(int s, const std::vector<Eigen::Vector2d>& points, const core::SE2& T_map_guess,
                                          bool global, core::Timestamp time, Localizer2dSummary& summary) {
    const Submap& submap = submaps[static_cast<std::size_t>(s)];
    BranchAndBoundOptions window = matching.loop_search;
    core::SE2 initial = submap.T_world_submap.inverse() * T_map_guess;
    if (global) {
      whole_submap_window(s, matching.loop_search, window, initial);
    } else {
      window.linear_search_window_m = options.confirmation_window_m;
      window.angular_search_window_rad = options.confirmation_window_rad;
    }
    LoopCandidate candidate;
    const bool found =
        search_and_verify(*submap.stack, *submap.points, points, initial, window, matching.loop_min_score, matching, candidate);
    if (!found) return std::nullopt;
    if (!candidate.accepted) {
      ++summary.rejected_matches;
      ++summary.rejected_by_reason[candidate.reason];
      return std::nullopt;
    }
    const double free_fraction =
        free_space_fraction(map.submaps[static_cast<std::size_t>(submap_index[static_cast<std::size_t>(s)])].grid, points,
                            candidate.T_anchor_keyframe);
    if (free_fraction > options.verification_max_free_fraction) {
      ++summary.rejected_matches;
      ++summary.rejected_by_reason["scan points where the map saw empty space"];
      return std::nullopt;
    }
    ++summary.verified_matches;
    LocalizationMatch match;
    match.free_space_fraction = free_fraction;
    match.scan = scan_index;
    match.time = time;
    match.submap = submap_index[static_cast<std::size_t>(s)];
    match.global = global;
    match.score = candidate.score;
    match.second_score = candidate.second_score;
    match.inlier_fraction = candidate.inlier_fraction;
    match.rms_m = candidate.rms_m;
    match.degeneracy = candidate.degeneracy;
    match.T_map_laser = submap.T_world_submap * candidate.T_anchor_keyframe;
    return match;
  }

  // A windowed search around `T_map_guess` in `preferred` (a searchable submap index, the one
  // that matched before) if it holds the guess, else in the submap holding it with the nearest
  // path centre; a match that does not agree with the guess does not count.
  std::optional<LocalizationMatch> search_near(const std::vector<Eigen::Vector2d>& points, const core::SE2& T_map_guess,
                                               core::Timestamp time, Localizer2dSummary& summary, int preferred = -1) {
    const auto start = Clock::now();
    const int s = preferred >= 0 && holds(preferred, T_map_guess.translation()) ? preferred
                                                                               : submap_holding(T_map_guess.translation());
    std::optional<LocalizationMatch> match;
    if (s >= 0) {
      ++summary.confirmation_searches;
      match = search(s, points, T_map_guess, false, time, summary);
      if (match && !agrees(match->T_map_laser, T_map_guess)) match.reset();
    }
    summary.times.confirmation_search_s += seconds_since(start);
    return match;
  }

  void add_support(Hypothesis& h, const LocalizationMatch& match, const core::SE2& odom) {
    if (h.support == 0 || h.last_support_scan != match.scan) ++h.support;
    h.last_support_scan = match.scan;
    const auto it = std::find(submap_index.begin(), submap_index.end(), match.submap);
    h.last_submap = it == submap_index.end() ? -1 : static_cast<int>(it - submap_index.begin());
    h.T_map_odom = match.T_map_laser * odom.inverse();
    h.evidence.push_back(match);
  }

  // A verified match of a global search: support for the hypothesis it agrees with, or a new one
  // (while tracking: unless it agrees with the tracked pose).
  void add_match(const LocalizationMatch& match, const core::SE2& odom, Localizer2dSummary& summary) {
    if (state == LocalizationState::kTracking) {
      if (agrees(match.T_map_laser, T_map_laser)) {
        ++summary.tracking_checks_agreeing;
        contradicted = false;  // a verified match (free space included) at the tracked pose
        return;
      }
      for (const core::SE2& T_map_odom : refuted)
        if (agrees(match.T_map_laser, T_map_odom * odom)) return;  // refuted before
    }
    for (Hypothesis& h : hypotheses) {
      if (agrees(match.T_map_laser, h.T_map_odom * odom)) {
        add_support(h, match, odom);
        return;
      }
    }
    if (static_cast<int>(hypotheses.size()) >= options.max_hypotheses) {
      ++summary.hypotheses_ignored;
      return;
    }
    Hypothesis h;
    h.created_scan = scan_index;
    add_support(h, match, odom);
    hypotheses.push_back(std::move(h));
    ++summary.hypotheses;
  }

  // Every hypothesis followed one scan: ICP against the map from its odometry prediction (the
  // tracking state's match; failures in a row drop it), then a windowed, verified search around
  // its pose for support. Hypotheses that have come to agree are merged.
  void follow_hypotheses(const std::vector<Eigen::Vector2d>& points, const core::SE2& odom, core::Timestamp time,
                         Localizer2dSummary& summary) {
    const auto start = Clock::now();
    std::vector<Hypothesis> kept;
    for (Hypothesis& h : hypotheses) {
      const core::SE2 predicted = h.T_map_odom * odom;
      const IcpResult icp = match_icp(tracking_map, points, predicted, &predicted, matching.icp);
      h.inlier_fraction = icp.inlier_fraction;
      if (icp.inlier_fraction >= options.tracking_min_inlier_fraction) {
        h.T_map_odom = icp.T_map_sensor * odom.inverse();
        h.failures = 0;
      } else if (++h.failures >= matching.lost_after_scans) {
        ++summary.hypotheses_dropped;
        ++hypotheses_died;
        continue;
      }
      bool duplicate = false;
      for (Hypothesis& other : kept) {
        if (!agrees(other.T_map_odom * odom, h.T_map_odom * odom)) continue;
        if (h.support > other.support) std::swap(h, other);
        duplicate = true;
        break;
      }
      if (duplicate) {
        ++summary.hypotheses_dropped;
        continue;
      }
      kept.push_back(std::move(h));
    }
    hypotheses = std::move(kept);
    // Among several places, one that explains clearly less of the scans than the best over the
    // last scans is dropped (an accumulated likelihood-ratio test in its simplest form: a small
    // asymmetry of a symmetric building, seen for a while, decides).
    if (hypotheses.size() > 1) {
      double best = 0.0;
      for (const Hypothesis& h : hypotheses) best = std::max(best, h.inlier_fraction);
      std::vector<Hypothesis> better;
      for (Hypothesis& h : hypotheses) {
        h.deficits.push_back(best - h.inlier_fraction);
        if (static_cast<int>(h.deficits.size()) > options.hypothesis_drop_window_scans) h.deficits.pop_front();
        double deficit = 0.0;
        for (const double d : h.deficits) deficit += d;
        if (deficit >= options.hypothesis_drop_deficit) {
          ++summary.hypotheses_dropped;
          ++hypotheses_died;
          continue;
        }
        better.push_back(std::move(h));
      }
      hypotheses = std::move(better);
    }
    summary.times.confirmation_search_s += seconds_since(start);
    for (Hypothesis& h : hypotheses) {
      if (const auto match = search_near(points, h.T_map_odom * odom, time, summary, h.last_submap)) add_support(h, *match, odom);
    }
  }

  // Whole-submap searches of the submaps in `chosen`.
  void global_searches(const std::vector<int>& chosen, const std::vector<Eigen::Vector2d>& points, const core::SE2& odom,
                       core::Timestamp time, Localizer2dSummary& summary) {
    const auto start = Clock::now();
    for (const int s : chosen) {
      const auto one_start = Clock::now();
      ++summary.global_searches;
      const std::optional<LocalizationMatch> match = search(s, points, core::SE2(), true, time, summary);
      summary.max_global_search_s = std::max(summary.max_global_search_s, seconds_since(one_start));
      if (match) add_match(*match, odom, summary);
    }
    summary.times.global_search_s += seconds_since(start);
  }

  // The submaps to search on this scan: the `ranked` best by coarse score, then `round_robin`
  // more, the next ones of `order` from `position` that are not chosen yet.
  std::vector<int> choose_submaps(const std::vector<Eigen::Vector2d>& points, int ranked, int round_robin,
                                  const std::vector<int>& order, std::size_t& position, Localizer2dSummary& summary) {
    std::vector<int> chosen;
    if (ranked > 0) {
      // Rank a few more places than are searched: the others are the look-alikes the
      // acceptance test checks (unique_fit).
      ranking = rank_submaps(points, std::max(ranked, kAlternatives), summary);
      for (std::size_t k = 0; k < ranking.size() && static_cast<int>(k) < ranked; ++k) chosen.push_back(ranking[k].submap);
    }
    for (int k = 0; k < round_robin && !order.empty(); ++k) {
      for (std::size_t tries = 0; tries < order.size(); ++tries) {
        const int s = order[position++ % order.size()];
        if (std::find(chosen.begin(), chosen.end(), s) == chosen.end()) {
          chosen.push_back(s);
          break;
        }
      }
    }
    return chosen;
  }

  // One scan of the search. Returns the accepted relocalisation, if any.
  std::optional<Relocalisation> search_scan(const std::vector<Eigen::Vector2d>& points, const core::SE2& odom,
                                            core::Timestamp time, Localizer2dSummary& summary) {
    if (order_stale) make_search_order(odom);
    ranking.clear();
    follow_hypotheses(points, odom, time, summary);
    global_searches(choose_submaps(points, options.global_searches_per_scan - options.round_robin_searches_per_scan,
                                   options.round_robin_searches_per_scan, search_order, next_search, summary),
                    points, odom, time, summary);
    for (Hypothesis& h : hypotheses) {
      if (h.support < options.confirmations || h.last_support_scan != scan_index) continue;
      if (hypotheses.size() > 1) {
        ++summary.scans_ambiguous;
        return std::nullopt;
      }
      if (const auto look_alike = other_fitting_place(points, h.evidence.back().T_map_laser, summary)) {
        // The whole map explains the scan as well elsewhere (a symmetric building): follow that
        // place too, accept nothing until the scans stop fitting one of them.
        ++summary.scans_ambiguous;
        ++summary.look_alikes;
        LocalizationMatch match = h.evidence.back();
        match.global = true;
        match.T_map_laser = *look_alike;
        Hypothesis rival;
        rival.created_scan = scan_index;
        rival.T_map_odom = *look_alike * odom.inverse();
        hypotheses.push_back(std::move(rival));
        ++summary.hypotheses;
        return std::nullopt;
      }
      // Scan points where another submap of the matched one's segment saw through (the matched
      // one never looked there). Other segments are left out: an unmerged segment is placed by
      // odometry alone, and its empty space may lie over the true place.
      const int segment = map.submaps[static_cast<std::size_t>(h.evidence.back().submap)].segment;
      if (observed_fit(points, h.evidence.back().T_map_laser, segment).empty_fraction > options.verification_max_free_fraction) {
        ++summary.refused_empty_space_elsewhere;
        return std::nullopt;
      }
      if (partly_mapped_look_alike(points, h, odom, summary)) {  // another place fits too
        ++summary.scans_ambiguous;
        ++summary.partly_mapped_look_alikes;
        return std::nullopt;
      }
      Relocalisation relocalisation;
      relocalisation.scan = scan_index;
      relocalisation.time = time;
      relocalisation.T_map_laser = h.evidence.back().T_map_laser;
      relocalisation.searching_since_scan = searching_since;
      relocalisation.had_prior = prior_T_map_odom.has_value();
      relocalisation.evidence = h.evidence;
      relocalisation.rival_hypotheses = hypotheses_died;
      return relocalisation;
    }
    return std::nullopt;
  }

  // Branch and bound in searchable submap `s` within the coarse cell around `T_map_guess` and the
  // confirmation angle window: the full-resolution pose of a place the coarse ranking found (a
  // uniqueness test). The result's pose is in the map frame.
  BranchAndBoundResult refine_place(int s, const std::vector<Eigen::Vector2d>& points, const core::SE2& T_map_guess,
                                    double min_score, Localizer2dSummary& summary) const {
    const Submap& submap = submaps[static_cast<std::size_t>(s)];
    BranchAndBoundOptions window = matching.loop_search;
    window.linear_search_window_m = coarse_options.cell_m;
    window.angular_search_window_rad = options.confirmation_window_rad;
    BranchAndBoundResult fine =
        match_branch_and_bound(*submap.stack, points, submap.T_world_submap.inverse() * T_map_guess, min_score, window);
    ++summary.uniqueness_tests;
    if (fine.found) fine.T_map_sensor = submap.T_world_submap * fine.T_map_sensor;
    return fine;
  }

  // The uniqueness test before a pose is accepted: each other place of this scan's coarse
  // ranking (farther than kPlaceSeparation_m from `T_map_accepted`) is refined by branch and
  // bound in a small window of its submap and then by ICP against the whole map without a prior;
  // a place where the map explains the scan as well as a verified match must (inlier fraction,
  // residual, degeneracy) is returned. Per-submap verification cannot see such a look-alike:
  // its ambiguity test spans one submap.
  std::optional<core::SE2> other_fitting_place(const std::vector<Eigen::Vector2d>& points, const core::SE2& T_map_accepted,
                                               Localizer2dSummary& summary) {
    const auto start = Clock::now();
    std::optional<core::SE2> found;
    IcpOptions icp_options = matching.icp;
    icp_options.prior_translation_sigma_m = 0.0;  // no prior: the fit decides
    for (const Ranked& place : ranking) {
      if ((place.T_map_laser.translation() - T_map_accepted.translation()).norm() < kPlaceSeparation_m) continue;
      const BranchAndBoundResult fine = refine_place(place.submap, points, place.T_map_laser, matching.loop_min_score, summary);
      if (!fine.found) continue;
      const IcpResult fit = match_icp(tracking_map, points, fine.T_map_sensor, nullptr, icp_options);
      if (fit.inlier_fraction >= options.verification_min_inlier_fraction && fit.rms_m <= matching.loop_max_rms_m &&
          fit.degeneracy >= options.verification_min_degeneracy &&
          (fit.T_map_sensor.translation() - T_map_accepted.translation()).norm() >= kPlaceSeparation_m) {
        found = fit.T_map_sensor;
        break;
      }
    }
    // The accepted place itself turned by a quarter or half turn: a room symmetric but for what
    // lies behind the robot looks the same both ways round. The ranking keeps one pose per
    // place, so such a rival never enters it (simulated office, put down in the middle room
    // facing away from its post: relocalised 180 degrees off, the match verified at 0.94-0.96).
    const int holding = found ? -1 : submap_holding(T_map_accepted.translation());
    for (const double turn : {std::numbers::pi, 0.5 * std::numbers::pi, -0.5 * std::numbers::pi}) {
      if (holding < 0) break;
      const core::SE2 guess(T_map_accepted.x(), T_map_accepted.y(), T_map_accepted.angle() + turn);
      const BranchAndBoundResult fine = refine_place(holding, points, guess, matching.loop_min_score, summary);
      // The submap's grid may hold the turned view too poorly for its score: then ICP against
      // the whole map from the turned pose itself decides.
      const IcpResult fit = match_icp(tracking_map, points, fine.found ? fine.T_map_sensor : guess, nullptr, icp_options);
      if (fit.inlier_fraction >= options.verification_min_inlier_fraction && fit.rms_m <= matching.loop_max_rms_m &&
          fit.degeneracy >= options.verification_min_degeneracy &&
          std::abs(core::wrap_angle(fit.T_map_sensor.angle() - T_map_accepted.angle())) > 0.25 * std::numbers::pi) {
        found = fit.T_map_sensor;
        break;
      }
    }
    summary.times.confirmation_search_s += seconds_since(start);
    return found;
  }

  /// How a scan placed at a pose fits what the map observed there.
  struct ObservedFit {
    double observed_fraction = 0.0;     ///< points near a map point or in a cell some submap observed
    double explained_of_observed = 0.0; ///< of those, within the ICP inlier distance of a map point
    double empty_fraction = 0.0;        ///< points in some submap's observed empty space, not near a map point
  };
  // The observed cells and empty space are those of every submap, or of map segment `segment`'s
  // when it is >= 0; the map points are the whole map's.
  ObservedFit observed_fit(const std::vector<Eigen::Vector2d>& points, const core::SE2& T_map_scan, int segment = -1) const {
    ObservedFit fit;
    if (points.empty()) return fit;
    const double inlier_m = matching.icp.inlier_distance_m;
    std::size_t observed = 0, explained = 0, empty = 0;
    for (const Eigen::Vector2d& p_scan : points) {
      const Eigen::Vector2d p = T_map_scan * p_scan;
      const MapPoint* near = tracking_map.nearest(p, inlier_m);
      if (near != nullptr && (near->position - p).norm() <= inlier_m) {
        ++observed;
        ++explained;
        continue;
      }
      bool seen = false, seen_empty = false;
      for (std::size_t s = 0; s < submaps.size() && !seen_empty; ++s) {
        const Submap& submap = submaps[s];
        const SavedSubmap& saved = map.submaps[static_cast<std::size_t>(submap_index[s])];
        if (segment >= 0 && saved.segment != segment) continue;
        const Eigen::Vector2d q = submap.T_world_submap.inverse() * p;
        if (!(q.array() >= submap.lower_submap.array()).all() || !(q.array() <= submap.upper_submap.array()).all()) continue;
        const ProbabilityGrid& grid = saved.grid;
        if (!grid.known(q)) continue;
        seen = true;
        seen_empty = in_observed_empty_space(grid, q);
      }
      observed += seen ? 1 : 0;
      empty += seen_empty ? 1 : 0;
    }
    const double n = static_cast<double>(points.size());
    fit.observed_fraction = static_cast<double>(observed) / n;
    fit.explained_of_observed = observed > 0 ? static_cast<double>(explained) / static_cast<double>(observed) : 0.0;
    fit.empty_fraction = static_cast<double>(empty) / n;
    return fit;
  }

  // Whether some submap observed the cell of `p_map` (a ray of the map's scans crossed or ended
  // in it).
  bool position_observed(const Eigen::Vector2d& p_map) const {
    for (std::size_t s = 0; s < submaps.size(); ++s) {
      const Eigen::Vector2d q = submaps[s].T_world_submap.inverse() * p_map;
      if (map.submaps[static_cast<std::size_t>(submap_index[s])].grid.known(q)) return true;
    }
    return false;
  }

  // Whether `fit` (ICP against the whole map without a prior) is a partly mapped place that
  // explains the scan as far as the map observed it (Localizer2dOptions::look_alike_places), at
  // least kPlaceSeparation_m from `T_map_accepted`.
  bool explains_as_observed(const std::vector<Eigen::Vector2d>& points, const IcpResult& fit,
                            const core::SE2& T_map_accepted) const {
    if ((fit.T_map_sensor.translation() - T_map_accepted.translation()).norm() < kPlaceSeparation_m) return false;
    // Explained points are observed, so a place that passes has at least this inlier fraction.
    if (fit.inlier_fraction < options.look_alike_min_observed_fraction * options.verification_min_inlier_fraction)
      return false;
    if (!position_observed(fit.T_map_sensor.translation())) return false;
    const ObservedFit observed = observed_fit(points, fit.T_map_sensor);
    return observed.observed_fraction >= options.look_alike_min_observed_fraction &&
           observed.explained_of_observed >= options.verification_min_inlier_fraction &&
           observed.empty_fraction <= options.verification_max_free_fraction;
  }

  // The partly mapped look-alike test before `h` is accepted (Localizer2dOptions::
  // look_alike_places): true when a place other than h's explains the scan as far as the map
  // observed it. The look-alike found last time is checked first, from its odometry prediction.
  bool partly_mapped_look_alike(const std::vector<Eigen::Vector2d>& points, Hypothesis& h, const core::SE2& odom,
                                Localizer2dSummary& summary) {
    if (options.look_alike_places == 0) return false;
    const auto start = Clock::now();
    const core::SE2 T_map_accepted = h.evidence.back().T_map_laser;
    IcpOptions icp_options = matching.icp;
    icp_options.prior_translation_sigma_m = 0.0;  // no prior: the fit decides
    const auto found = [&](const IcpResult& fit) {
      h.look_alike_T_map_odom = fit.T_map_sensor * odom.inverse();
      summary.times.confirmation_search_s += seconds_since(start);
      return true;
    };
    if (h.look_alike_T_map_odom) {
      ++summary.uniqueness_tests;
      const IcpResult fit = match_icp(tracking_map, points, *h.look_alike_T_map_odom * odom, nullptr, icp_options);
      if (explains_as_observed(points, fit, T_map_accepted)) return found(fit);
      h.look_alike_T_map_odom.reset();
    }
    // Candidates: the coarse ranking of the whole scan, then of two overlapping sectors (a
    // partly mapped place scores low for the whole scan: its unobserved part scores as unknown).
    std::vector<Ranked> places = rank_submaps(points, options.look_alike_places, summary);
    std::vector<std::pair<double, Eigen::Vector2d>> by_bearing;
    by_bearing.reserve(points.size());
    for (const Eigen::Vector2d& p : points) by_bearing.emplace_back(std::atan2(p.y(), p.x()), p);
    std::sort(by_bearing.begin(), by_bearing.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const std::size_t n = by_bearing.size();
    for (const auto& [begin, end] : {std::pair<std::size_t, std::size_t>{0, 2 * n / 3}, {n / 3, n}}) {
      if (end - begin < static_cast<std::size_t>(std::max(1, matching.min_matching_points))) continue;
      std::vector<Eigen::Vector2d> sector;
      sector.reserve(end - begin);
      for (std::size_t k = begin; k < end; ++k) sector.push_back(by_bearing[k].second);
      const std::vector<Ranked> more = rank_submaps(sector, std::max(1, options.look_alike_places / 2), summary);
      places.insert(places.end(), more.begin(), more.end());
    }
    std::vector<core::SE2> tried;
    for (const Ranked& place : places) {
      if ((place.T_map_laser.translation() - T_map_accepted.translation()).norm() < kPlaceSeparation_m) continue;
      if (std::any_of(tried.begin(), tried.end(), [&](const core::SE2& t) { return agrees(t, place.T_map_laser); })) continue;
      tried.push_back(place.T_map_laser);
      const BranchAndBoundResult fine = refine_place(place.submap, points, place.T_map_laser, 0.0, summary);
      const IcpResult fit =
          match_icp(tracking_map, points, fine.found ? fine.T_map_sensor : place.T_map_laser, nullptr, icp_options);
      if (explains_as_observed(points, fit, T_map_accepted)) return found(fit);
    }
    summary.times.confirmation_search_s += seconds_since(start);
    return false;
  }

  // The tracking check (see the file comment). Returns the reason when tracking must end.
  std::optional<std::string> check_tracking(const std::vector<Eigen::Vector2d>& points, const core::SE2& odom,
                                            core::Timestamp time, const IcpResult& tracked, Localizer2dSummary& summary) {
    if (!hypotheses.empty()) follow_hypotheses(points, odom, time, summary);
    // Every check_every_n_scans scans: the next submap in turn, or when few points match (a
    // kidnapped robot's scans rarely fit the wrong place well) the submap the coarse ranking
    // puts first, where the robot most likely is instead.
    const bool poor = tracked.inlier_fraction < options.ok_min_inlier_fraction;
    if (scan_index % static_cast<std::size_t>(options.check_every_n_scans) == 0) {
      ++summary.tracking_checks;
      global_searches(choose_submaps(points, poor ? 1 : 0, poor ? 0 : 1, spread_order, next_check, summary), points, odom,
                      time, summary);
    }
    // A match that agrees with the tracked pose is no rival.
    std::erase_if(hypotheses, [&](const Hypothesis& h) { return agrees(h.T_map_odom * odom, T_map_laser); });
    for (const Hypothesis& h : hypotheses) {
      if (h.support < options.confirmations || h.last_support_scan != scan_index) continue;
      // A confirmed rival: does the whole map explain the scan at the tracked pose as well as a
      // verified match must (this scan's tracking match: inlier fraction, residual,
      // degeneracy)? No ambiguity test: continuity has already chosen between places that look
      // alike, such as the two halves of a symmetric building.
      if (tracked.inlier_fraction >= options.verification_min_inlier_fraction && tracked.rms_m <= matching.loop_max_rms_m &&
          tracked.degeneracy >= options.verification_min_degeneracy) {
        ++summary.rivals_refuted;
        for (const Hypothesis& rival : hypotheses) refuted.push_back(rival.T_map_odom);
        while (refuted.size() > 4) refuted.erase(refuted.begin());
        hypotheses.clear();
        return std::nullopt;
      }
      const double distance = ((h.T_map_odom * odom).translation() - T_map_laser.translation()).norm();
      return "lost: " + std::to_string(h.support) + " scans' verified matches place the robot " + fixed(distance, 2) +
             " m from the tracked pose, where the map explains less of the scan (inlier fraction " +
             fixed(tracked.inlier_fraction, 3) + "); both are followed until the scans stop fitting one";
    }
    return std::nullopt;
  }

  /// The health a scan leaves and why (HealthEvent's reason).
  struct Verdict {
    Health next = Health::kLost;
    std::string reason;
  };

  /// 1. Tracking: odometry prediction, ICP against the map with the prediction as prior, then the
  /// tracking check; the pose is given while still tracking.
  void track(const ScanPoints& points, const io::LaserScan& scan, bool enough_points, LocalizationResult& result,
             Verdict& verdict, Localizer2dSummary& summary) {
    const core::SE2& odom = scan.T_odom_laser;
    const auto track_start = Clock::now();
    const core::SE2 predicted = T_map_laser * (previous_odom.inverse() * odom);
    T_map_laser = predicted;
    IcpResult tracked_match;
    if (!enough_points) {
      verdict.next = Health::kDegraded;
      result.dead_reckoning = true;
      verdict.reason = "too few returns to match (" + std::to_string(points.matching.size()) + "); following odometry";
    } else {
      tracked_match = match_tracked(points.matching, predicted, odom, result, verdict, summary);
    }
    summary.times.tracking_s += seconds_since(track_start);
    // The tracking check: a confirmed match elsewhere that the tracked pose cannot match.
    if (state == LocalizationState::kTracking && enough_points)
      check_for_rival(points.matching, scan, tracked_match, result, verdict, summary);
    if (state == LocalizationState::kTracking) {
      result.localised = true;
      result.T_map_laser = T_map_laser;
    } else {
      result.confidence = 0.0;
      result.dead_reckoning = false;
      result.covariance.setZero();
    }
  }

  /// The tracking match from `predicted`: accepted (tracked_match_accepted) or a failure
  /// (tracked_match_failed). Returns the ICP result.
  IcpResult match_tracked(const std::vector<Eigen::Vector2d>& points, const core::SE2& predicted, const core::SE2& odom,
                          LocalizationResult& result, Verdict& verdict, Localizer2dSummary& summary) {
    // Unlike Slam2d, no retry from rotated guesses without the prior when few points match:
    // against a whole building's map such a retry found another corridor (Intel's second
    // half: a 1.1 m jump, then 30 scans 2 m off). A slipped odometry makes the match fail
    // instead, and the search finds the robot again.
    const IcpResult icp = match_icp(tracking_map, points, predicted, &predicted, matching.icp);
    result.confidence = icp.inlier_fraction;
    result.degeneracy = icp.degeneracy;
    result.rms_m = icp.rms_m;
    if (icp.inlier_fraction >= options.tracking_min_inlier_fraction) {
      tracked_match_accepted(points, icp, result, verdict);
    } else {
      tracked_match_failed(icp, odom, result, verdict, summary);
    }
    return icp;
  }

  /// A tracking match good enough to follow: the pose and covariance are taken, free space is
  /// checked and the health graded.
  void tracked_match_accepted(const std::vector<Eigen::Vector2d>& points, const IcpResult& icp, LocalizationResult& result,
                              Verdict& verdict) {
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(icp.hessian);
    if (ldlt.info() == Eigen::Success && ldlt.isPositive() && icp.hessian.determinant() > 0.0)
      result.covariance = icp.hessian.inverse();
    T_map_laser = icp.T_map_sensor;
    failures_in_a_row = 0;
    // What the scan sees where the map saw through (the submap holding the pose): a robot
    // carried to a place whose scans still half fit where it was puts points there.
    const int holding = submap_holding(icp.T_map_sensor.translation());
    if (holding >= 0) {
      const Submap& submap = submaps[static_cast<std::size_t>(holding)];
      result.free_space_fraction = free_space_fraction(
          map.submaps[static_cast<std::size_t>(submap_index[static_cast<std::size_t>(holding)])].grid, points,
          submap.T_world_submap.inverse() * icp.T_map_sensor);
    }
    // Once contradicted, the pose stays suspect until a scan verifies it (the verification
    // thresholds, free space included): the unexplained points of a wrong pose can move
    // into space the map never saw while the robot turns (simulated kidnapping: 10 % in
    // empty space for 14 scans, then none, at 0.70-0.72 inliers, 9 m off).
    if (result.free_space_fraction > options.verification_max_free_fraction) {
      contradicted = true;
    } else if (icp.inlier_fraction >= options.verification_min_inlier_fraction && icp.rms_m <= matching.loop_max_rms_m &&
               icp.degeneracy >= options.verification_min_degeneracy) {
      contradicted = false;
    }
    if (icp.inlier_fraction < options.ok_min_inlier_fraction) {
      verdict.next = Health::kDegraded;
      verdict.reason = "few scan points agree with the map (inlier fraction " + fixed(icp.inlier_fraction, 3) + ")";
    } else if (contradicted) {
      verdict.next = Health::kDegraded;
      verdict.reason = "scan points where the map saw empty space (" + fixed(100.0 * result.free_space_fraction, 1) +
                       " % now); degraded until a scan verifies the pose";
    } else if (icp.degeneracy < matching.degraded_min_degeneracy) {
      verdict.next = Health::kDegraded;
      verdict.reason = "degenerate geometry (degeneracy " + fixed(icp.degeneracy, 4) + "): the scan barely constrains " +
                       name_direction(icp.degenerate_direction, icp.T_map_sensor) + "; odometry carries it";
    } else {
      verdict.next = Health::kOk;
      verdict.reason = "matching the map";
    }
  }

  /// A failed tracking match: the pose follows odometry; `matching.lost_after_scans` failures in
  /// a row start the search.
  void tracked_match_failed(const IcpResult& icp, const core::SE2& odom, LocalizationResult& result, Verdict& verdict,
                            Localizer2dSummary& summary) {
    ++summary.tracking_failures;
    ++failures_in_a_row;
    verdict.next = Health::kDegraded;
    result.dead_reckoning = true;
    verdict.reason = "scan does not match the map (inlier fraction " + fixed(icp.inlier_fraction, 3) + ", " +
                     std::to_string(failures_in_a_row) + " in a row); following odometry";
    if (failures_in_a_row >= matching.lost_after_scans) {
      // The prior for the search: where odometry says the robot is, from the last good match.
      start_searching(T_map_laser * odom.inverse());
      hypotheses.clear();
      verdict.next = Health::kLost;
      verdict.reason = "lost: the scan did not match the map " + std::to_string(failures_in_a_row) +
                       " times in a row; searching the whole map";
      failures_in_a_row = 0;
    }
  }

  /// The tracking check (check_tracking); a confirmed rival the tracked pose cannot match ends
  /// tracking, the tracked pose kept as a hypothesis.
  void check_for_rival(const std::vector<Eigen::Vector2d>& points, const io::LaserScan& scan, const IcpResult& tracked_match,
                       LocalizationResult& result, Verdict& verdict, Localizer2dSummary& summary) {
    const core::SE2& odom = scan.T_odom_laser;
    if (const auto contradiction = check_tracking(points, odom, scan.time, tracked_match, summary)) {
      ++summary.tracking_contradicted;
      start_searching(T_map_laser * odom.inverse());
      Hypothesis tracked;
      tracked.T_map_odom = T_map_laser * odom.inverse();
      tracked.created_scan = scan_index;
      hypotheses.insert(hypotheses.begin(), tracked);
      verdict.next = Health::kLost;
      verdict.reason = *contradiction;
      result.covariance.setZero();
    }
  }

  /// 2. Searching: hypotheses followed, global searches; no pose until one is accepted.
  void search_while_lost(const std::vector<Eigen::Vector2d>& points, const io::LaserScan& scan, bool enough_points,
                         LocalizationResult& result, Verdict& verdict, Localizer2dSummary& summary) {
    verdict.next = Health::kLost;
    verdict.reason =
        summary.first_localised_scan ? "lost: searching the whole map" : "not localised yet: searching the whole map";
    if (!enough_points) return;
    if (const auto relocalisation = search_scan(points, scan.T_odom_laser, scan.time, summary))
      accept_relocalisation(*relocalisation, result, verdict, summary);
  }

  /// An accepted relocalisation: tracking starts from its last match.
  void accept_relocalisation(const Relocalisation& relocalisation, LocalizationResult& result, Verdict& verdict,
                             Localizer2dSummary& summary) {
    const LocalizationMatch& match = relocalisation.evidence.back();
    state = LocalizationState::kTracking;
    T_map_laser = match.T_map_laser;
    failures_in_a_row = 0;
    hypotheses.clear();
    result.localised = true;
    result.relocalised = true;
    result.T_map_laser = match.T_map_laser;
    result.confidence = match.inlier_fraction;
    result.degeneracy = match.degeneracy;
    result.rms_m = match.rms_m;
    verdict.next = Health::kOk;
    std::vector<std::size_t> scans;
    for (const auto& e : relocalisation.evidence)
      if (scans.empty() || scans.back() != e.scan) scans.push_back(e.scan);
    verdict.reason = std::string(summary.first_localised_scan ? "relocalised" : "localised") + " after " +
                     std::to_string(scan_index - searching_since + 1) + " scans of search: " +
                     std::to_string(relocalisation.evidence.size()) + " agreeing verified matches on " +
                     std::to_string(scans.size()) + " scans (last: submap " + std::to_string(match.submap) + ", score " +
                     fixed(match.score, 3) + ", inlier fraction " + fixed(match.inlier_fraction, 3) + ")";
    summary.relocalisations.push_back(relocalisation);
  }

  /// 3. Records the scan: a health event when the health changed (or a relocalisation was
  /// accepted), the result's state and health, the counts; moves on to the next scan.
  void record_scan(const io::LaserScan& scan, const Verdict& verdict, LocalizationResult& result, Localizer2dSummary& summary) {
    const Health next = verdict.next;
    if (next != health || result.relocalised) {
      summary.health_events.push_back({scan.time, scan_index, health, next, verdict.reason});
      health = next;
    }
    result.state = state;
    result.health = next;
    if (result.localised) {
      ++summary.scans_localised;
      if (!summary.first_localised_scan) summary.first_localised_scan = scan_index;
    }
    if (next == Health::kOk) ++summary.scans_ok;
    if (next == Health::kDegraded) ++summary.scans_degraded;
    if (next == Health::kLost) ++summary.scans_lost;
    previous_odom = scan.T_odom_laser;
    ++scan_index;
    ++summary.scans;
  }

  void start_searching(std::optional<core::SE2> prior) {
    state = LocalizationState::kSearching;
    contradicted = false;
    refuted.clear();
    prior_T_map_odom = prior;
    order_stale = true;
    hypotheses_died = 0;
    searching_since = scan_index;
  }
};

Localizer2d::Localizer2d(SavedMap2D map, const Localizer2dOptions& options) {
  std::string error;
  if (!options.is_valid(&error)) throw std::invalid_argument("invalid localisation options: " + error);
  const auto start = Clock::now();
  impl_ = std::make_unique<Impl>(std::move(map), options);
  Impl& m = *impl_;
  std::vector<Eigen::Vector2d> all_points;
  for (std::size_t s = 0; s < m.map.submaps.size(); ++s) {
    const SavedSubmap& saved = m.map.submaps[s];
    Impl::Submap submap;
    submap.T_world_submap = saved.T_world_submap;
    if (saved.points_submap.empty() || !observed_extent(saved.grid, submap.lower_submap, submap.upper_submap)) continue;
    // The path the map was built along, in the submap frame: where a robot that sees what the
    // submap holds is (global searches span it plus a margin, clamped to the observed extent).
    submap.path_lower_submap = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity());
    submap.path_upper_submap = -submap.path_lower_submap;
    const std::size_t first = static_cast<std::size_t>(saved.first_keyframe);
    const std::size_t end = std::min(m.map.keyframes.size(), first + static_cast<std::size_t>(saved.keyframe_count));
    for (std::size_t k = first; k < end; ++k) {
      const Eigen::Vector2d t = saved.T_world_submap.inverse() * m.map.keyframes[k].T_world_laser.translation();
      submap.path_lower_submap = submap.path_lower_submap.cwiseMin(t);
      submap.path_upper_submap = submap.path_upper_submap.cwiseMax(t);
    }
    if (first >= end) submap.path_lower_submap = submap.path_upper_submap = Eigen::Vector2d::Zero();  // the anchor
    submap.centre_world = saved.T_world_submap * (0.5 * (submap.path_lower_submap + submap.path_upper_submap));
    submap.stack = std::make_unique<PrecomputationGridStack>(saved.grid, m.matching.loop_search, &m.stack_memory);
    submap.coarse_stack = std::make_unique<PrecomputationGridStack>(max_pooled(saved.grid, options.coarse_cell_factor),
                                                                    m.coarse_options.search, &m.stack_memory);
    submap.points = std::make_unique<PointMap>(m.matching.map_points);
    submap.points->build(saved.points_submap);
    for (const auto& p : saved.points_submap) all_points.push_back(saved.T_world_submap * p);
    summary_.precomputation_bytes += submap.stack->memory_bytes() + submap.coarse_stack->memory_bytes();
    m.submaps.push_back(std::move(submap));
    m.submap_index.push_back(static_cast<int>(s));
  }
  if (m.submaps.empty()) throw std::invalid_argument("the map holds no submap with points: nothing to localise in");
  // Submaps overlap (each keyframe lies in two): one voxel filter keeps the tracking map even.
  m.tracking_map.build(voxel_filter(all_points, m.matching.filter.voxel_size_m));
  m.make_spread_order();
  summary_.map_submaps = m.submaps.size();
  summary_.map_points = m.tracking_map.points().size();
  summary_.times.setup_s = seconds_since(start);
}

Localizer2d::~Localizer2d() = default;

const SavedMap2D& Localizer2d::map() const { return impl_->map; }

LocalizationState Localizer2d::state() const { return impl_->state; }

void Localizer2d::set_prior(const core::SE2& T_map_laser_guess, const core::SE2& T_odom_laser) {
  impl_->prior_T_map_odom = T_map_laser_guess * T_odom_laser.inverse();
  impl_->order_stale = true;
}

LocalizationResult Localizer2d::add_scan(const io::LaserScan& scan) {
  Impl& m = *impl_;
  const auto start = Clock::now();
  const ScanPoints points = preprocess_scan(scan, m.matching.filter);
  summary_.times.preprocess_s += seconds_since(start);
  LocalizationResult result;
  result.time = scan.time;
  result.matching_points = static_cast<int>(points.matching.size());
  const bool enough_points = static_cast<int>(points.matching.size()) >= m.matching.min_matching_points;
  Impl::Verdict verdict{m.health, {}};
  if (m.state == LocalizationState::kTracking) {
    m.track(points, scan, enough_points, result, verdict, summary_);
  } else {
    m.search_while_lost(points.matching, scan, enough_points, result, verdict, summary_);
  }
  m.record_scan(scan, verdict, result, summary_);
  const double scan_s = seconds_since(start);
  summary_.total_s += scan_s;
  summary_.max_scan_s = std::max(summary_.max_scan_s, scan_s);
  return result;
}

}  // namespace cairn::slam2d
