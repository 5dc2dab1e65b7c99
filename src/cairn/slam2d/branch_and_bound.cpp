#include "cairn/slam2d/branch_and_bound.hpp"

#include <algorithm>
#include <cmath>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::slam2d {
namespace {

std::uint8_t quantise_up(double p) {
  return static_cast<std::uint8_t>(std::clamp(std::ceil(p * 255.0), 0.0, 255.0));
}

/// Level 0's values over the observed box [i0, i0 + width) x [j0, j0 + height) of `grid` (row
/// by row into `values`, already filled with the outside value): probability * 255
/// rounded up, `unknown` where the grid is unknown.
void fill_level_zero(const ProbabilityGrid& grid, bool observed, int i0, int j0, int known_width, int known_height,
                     std::uint8_t unknown, std::uint8_t* values) {
  float last_log_odds = 0.0f;
  std::uint8_t last_value = quantise_up(ProbabilityGrid::probability_of_log_odds(0.0f));
  for (int j = 0; observed && j < known_height; ++j) {
    const float* log_odds = grid.log_odds_row(j + j0) + i0;
    const std::uint8_t* known = grid.known_row(j + j0) + i0;
    std::uint8_t* row = values + static_cast<std::size_t>(j) * static_cast<std::size_t>(known_width);
    for (int i = 0; i < known_width; ++i) {
      if (known[i] == 0) {
        row[i] = unknown;
        continue;
      }
      if (log_odds[i] != last_log_odds) {
        last_log_odds = log_odds[i];
        last_value = quantise_up(ProbabilityGrid::probability_of_log_odds(last_log_odds));
      }
      row[i] = last_value;
    }
  }
}

/// One level from the previous one (`previous`, previous_width x previous_height), squares of
/// side 2 half: `horizontal` and `padded` are scratch, `values` (width x height, filled with
/// `outside`) is the result.
void max_of_four(const std::uint8_t* previous, int previous_width, int previous_height, int half,
                 std::size_t width, int height, std::uint8_t outside, std::vector<std::uint8_t>& horizontal,
                 std::vector<std::uint8_t>& padded, std::uint8_t* values) {
  // horizontal(i, j) = max(previous(i - half, j), previous(i, j)), rows j of the previous level.
  horizontal.assign(width * static_cast<std::size_t>(previous_height), outside);
  padded.assign(width + static_cast<std::size_t>(half), outside);
  for (int j = 0; j < previous_height; ++j) {
    const std::uint8_t* source = previous + static_cast<std::size_t>(j) * static_cast<std::size_t>(previous_width);
    std::copy(source, source + previous_width, padded.begin() + half);
    std::uint8_t* out = horizontal.data() + static_cast<std::size_t>(j) * width;
    const std::uint8_t* a = padded.data();
    const std::uint8_t* b = padded.data() + half;
    for (std::size_t i = 0; i < width; ++i) out[i] = std::max(a[i], b[i]);
  }
  // level(i, j) = max(horizontal(i, j - half), horizontal(i, j)); rows outside: unknown.
  for (int j = 0; j < height; ++j) {
    std::uint8_t* out = values + static_cast<std::size_t>(j) * width;
    const bool low = j - half >= 0 && j - half < previous_height;
    const bool high = j < previous_height;
    const std::uint8_t* a = low ? horizontal.data() + static_cast<std::size_t>(j - half) * width : nullptr;
    const std::uint8_t* b = high ? horizontal.data() + static_cast<std::size_t>(j) * width : nullptr;
    if (low && high) {
      for (std::size_t i = 0; i < width; ++i) out[i] = std::max(a[i], b[i]);
    } else if (low || high) {
      const std::uint8_t* c = low ? a : b;
      for (std::size_t i = 0; i < width; ++i) out[i] = std::max(c[i], outside);
    }
  }
}

}  // namespace

PrecomputationGridStack::PrecomputationGridStack(const ProbabilityGrid& grid, const BranchAndBoundOptions& options,
                                                 core::PageArena* arena)
    : resolution_(grid.resolution()) {
  CAIRN_ASSERT(options.depth >= 1 && options.depth <= 12, "branch-and-bound depth must be in [1, 12]");
  CAIRN_ASSERT(options.angular_step_range_quantile > 0.0 && options.angular_step_range_quantile <= 1.0,
               "angular_step_range_quantile must be in (0, 1]");
  outside_ = quantise_up(options.unknown_probability);
  // Only the observed part of the grid matters (the grid grows by doubling, mostly unknown).
  int i0 = 0, j0 = 0, i1 = -1, j1 = -1;
  const bool observed = grid.known_bounds(i0, j0, i1, j1);
  if (!observed) i0 = j0 = i1 = j1 = 0;
  const int known_width = i1 - i0 + 1, known_height = j1 - j0 + 1;
  const long base_i = grid.offset_i() + i0;
  const long base_j = grid.offset_j() + j0;
  // Every level's place in one block: level h covers the observed box grown by 2^h - 1 cells
  // towards lower indices (its squares start there).
  std::size_t total = 0;
  for (int h = 0; h < options.depth; ++h) {
    const int w = 1 << h;
    Level level;
    level.offset_i = base_i - (w - 1);
    level.offset_j = base_j - (w - 1);
    level.width = known_width + w - 1;
    level.height = known_height + w - 1;
    level.start = total;
    total += static_cast<std::size_t>(level.width) * static_cast<std::size_t>(level.height);
    levels_.push_back(level);
  }
  if (arena != nullptr) {
    storage_ = arena->allocate(total);
  } else {
    storage_.chunk = std::shared_ptr<std::uint8_t[]>(new std::uint8_t[total]);
    storage_.data = storage_.chunk.get();
    storage_.size = total;
  }
  std::fill(storage_.data, storage_.data + total, outside_);
  // Level 0: the observed box, probability * 255 rounded up. Submaps store few distinct
  // log-odds values, so the probability of each is computed once per run of equal values (the
  // same arithmetic as ProbabilityGrid::cell_probability, hence the same bytes).
  fill_level_zero(grid, observed, i0, j0, known_width, known_height, quantise_up(options.unknown_probability),
                  storage_.data + levels_[0].start);
  // Level h from level h - 1: a square of side w = 2^h is four squares of side w / 2, so
  //   L_h(i, j) = max(L_{h-1}(i - w/2, j - w/2), L_{h-1}(i, j - w/2), L_{h-1}(i - w/2, j), L_{h-1}(i, j))
  // in each level's own indices (level h starts w/2 cells before level h - 1; outside a level:
  // unknown). Separable: a horizontal max of two shifted rows, then a vertical max of two
  // rows, both plain byte loops the compiler vectorises. Exact, O(area) per level. Measured
  // (perf, MIT CSAIL, 2026-11-25): the bounds-checked four-way version was 9 % of the run's
  // CPU time, the largest part of a submap's build.
  std::vector<std::uint8_t> padded, horizontal;
  for (int h = 1; h < options.depth; ++h) {
    const int half = 1 << (h - 1);
    const Level& previous = levels_[static_cast<std::size_t>(h - 1)];
    const Level& level = levels_[static_cast<std::size_t>(h)];
    CAIRN_ASSERT(level.width == previous.width + half && level.height == previous.height + half, "levels grow by half a square");
    max_of_four(storage_.data + previous.start, previous.width, previous.height, half, static_cast<std::size_t>(level.width),
                level.height, outside_, horizontal, padded, storage_.data + level.start);
  }
}

std::size_t PrecomputationGridStack::memory_bytes() const {
  std::size_t bytes = 0;
  for (const auto& level : levels_) bytes += static_cast<std::size_t>(level.width) * static_cast<std::size_t>(level.height);
  return bytes;
}

namespace {
struct Candidate {
  int angle_index = 0;
  long dx = 0;  ///< offset in cells
  long dy = 0;
  double score = 0.0;
};

/// The angular step of the search: Hess 2016, eq. (7), with d_max the
/// angular_step_range_quantile of the scan's ranges.
double angular_step_of(const std::vector<Eigen::Vector2d>& points_sensor, double r, const BranchAndBoundOptions& options) {
  std::vector<double> ranges;
  for (const auto& p : points_sensor) ranges.push_back(p.norm());
  const auto quantile = static_cast<std::size_t>(std::ceil(options.angular_step_range_quantile * static_cast<double>(ranges.size()))) - 1;
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(quantile), ranges.end());
  const double d_max = ranges[std::min(quantile, ranges.size() - 1)];
  // Hess 2016, eq. (7).
  return d_max > r ? std::acos(1.0 - r * r / (2.0 * d_max * d_max)) : 0.1;
}

// floor(x / r) by a multiplication: x * (1 / r) differs from the correctly rounded x / r by a
// few units in the last place at most, which moves the floor only when the quotient lies that
// close to an integer; there the division decides. The cells are exactly those of floor(x / r),
// at a fraction of the cost (measured with perf on MIT CSAIL, 2026-11-25: the divisions and
// library floors of this table were a third of the branch-and-bound time, with a store-
// forwarding stall in the compiled SE2 product; an ambiguity search's angular window can
// reach +-180 degrees, over a thousand angles at 10 m ranges).
/// The cell index floor(x / r), clamped far outside any grid (`inverse_r` = 1 / r).
std::int32_t cell_index(double x, double r, double inverse_r) {
  const double y = std::clamp(x * inverse_r, -1e9, 1e9);
  const auto truncated = static_cast<std::int64_t>(y);
  std::int64_t cell = truncated - (y < static_cast<double>(truncated) ? 1 : 0);  // floor(y)
  const double fraction = y - static_cast<double>(cell);
  const double tolerance = 1e-12 * (1.0 + std::abs(y));
  if (fraction < tolerance || fraction > 1.0 - tolerance) cell = static_cast<std::int64_t>(std::clamp(std::floor(x / r), -1e9, 1e9));
  return static_cast<std::int32_t>(cell);
}

#if defined(__SSE2__)
/// cell_index of two coordinates at once: truncate, step down where the truncation rounded up,
/// and let the division decide the lanes whose quotient lies within the tolerance of an integer.
void cell_index2(__m128d q, double r, double inverse_r, std::int32_t* out) {
  const __m128d vinverse = _mm_set1_pd(inverse_r), low = _mm_set1_pd(-1e9), high = _mm_set1_pd(1e9);
  const __m128d one = _mm_set1_pd(1.0), tiny = _mm_set1_pd(1e-12);
  const __m128d sign_mask = _mm_set1_pd(-0.0);
  const __m128d y = _mm_min_pd(_mm_max_pd(_mm_mul_pd(q, vinverse), low), high);
  const __m128d truncated = _mm_cvtepi32_pd(_mm_cvttpd_epi32(y));
  const __m128d cell = _mm_sub_pd(truncated, _mm_and_pd(_mm_cmplt_pd(y, truncated), one));
  const __m128d fraction = _mm_sub_pd(y, cell);
  const __m128d tolerance = _mm_mul_pd(tiny, _mm_add_pd(one, _mm_andnot_pd(sign_mask, y)));
  const __m128d doubtful = _mm_or_pd(_mm_cmplt_pd(fraction, tolerance), _mm_cmpgt_pd(fraction, _mm_sub_pd(one, tolerance)));
  alignas(16) double cells[2];
  _mm_store_pd(cells, cell);
  out[0] = static_cast<std::int32_t>(cells[0]);
  out[1] = static_cast<std::int32_t>(cells[1]);
  if (_mm_movemask_pd(doubtful) != 0) {
    alignas(16) double qs[2];
    _mm_store_pd(qs, q);
    out[0] = cell_index(qs[0], r, inverse_r);
    out[1] = cell_index(qs[1], r, inverse_r);
  }
}
#endif

/// The scan discretised per angle (Hess eq. (9)-(10)): the cell of each point at zero offset, one
/// flat array, angle-major. 32-bit cells (half the memory of 64-bit ones: the arrays are scanned
/// once per node scored); clamped far outside any grid (levels lie within 1e8 cells of the
/// origin, ProbabilityGrid).
struct DiscretisedScan {
  std::size_t n = 0;  ///< points per angle
  std::vector<std::int32_t> cell_i, cell_j;
  std::vector<double> angle_of;  ///< rotation of each angle index relative to the initial pose
};

/// The cells of the points (xs, ys) rotated by (c, s) and moved by (tx, ty) into out_i / out_j:
/// q = T * p written out as SO2 and SE2 compute it, (c x - s y) + t_x and (s x + c y) + t_y, two
/// points at a time where SSE2 is available.
void rotated_cells(const std::vector<double>& xs, const std::vector<double>& ys, double c, double s, double tx, double ty,
                   double r, double inverse_r, std::int32_t* out_i, std::int32_t* out_j) {
  const std::size_t n = xs.size();
  std::size_t k = 0;
#if defined(__SSE2__)
  const __m128d vc = _mm_set1_pd(c), vs = _mm_set1_pd(s), vtx = _mm_set1_pd(tx), vty = _mm_set1_pd(ty);
  for (; k + 2 <= n; k += 2) {
    const __m128d x = _mm_loadu_pd(xs.data() + k), y = _mm_loadu_pd(ys.data() + k);
    const __m128d qx = _mm_add_pd(_mm_sub_pd(_mm_mul_pd(vc, x), _mm_mul_pd(vs, y)), vtx);
    const __m128d qy = _mm_add_pd(_mm_add_pd(_mm_mul_pd(vs, x), _mm_mul_pd(vc, y)), vty);
    cell_index2(qx, r, inverse_r, out_i + k);
    cell_index2(qy, r, inverse_r, out_j + k);
  }
#endif
  for (; k < n; ++k) {
    out_i[k] = cell_index((c * xs[k] - s * ys[k]) + tx, r, inverse_r);
    out_j[k] = cell_index((s * xs[k] + c * ys[k]) + ty, r, inverse_r);
  }
}

/// The scan at each of the 2 angular_steps + 1 angles around `initial`, discretised at the
/// stack's resolution `r`.
DiscretisedScan discretise_scan(const std::vector<Eigen::Vector2d>& points_sensor, const core::SE2& initial, double r,
                                int angular_steps, double angular_step) {
  const int angles = 2 * angular_steps + 1;
  DiscretisedScan scan;
  scan.n = points_sensor.size();
  const std::size_t n = scan.n;
  scan.cell_i.resize(static_cast<std::size_t>(angles) * n);
  scan.cell_j.resize(static_cast<std::size_t>(angles) * n);
  const double inverse_r = 1.0 / r;
  scan.angle_of.resize(static_cast<std::size_t>(angles));
  std::vector<double> xs(n), ys(n);
  for (std::size_t k = 0; k < n; ++k) {
    xs[k] = points_sensor[k].x();
    ys[k] = points_sensor[k].y();
  }
  const double tx = initial.translation().x(), ty = initial.translation().y();
  for (int a = 0; a < angles; ++a) {
    const double angle = (a - angular_steps) * angular_step;
    scan.angle_of[static_cast<std::size_t>(a)] = angle;
    const core::SO2 R = initial.so2() * core::SO2(angle);
    rotated_cells(xs, ys, R.cos(), R.sin(), tx, ty, r, inverse_r, scan.cell_i.data() + static_cast<std::size_t>(a) * n,
                  scan.cell_j.data() + static_cast<std::size_t>(a) * n);
  }
  return scan;
}

/// Scores of search-tree nodes: the mean of the stored bytes over the points, summed exactly in
/// integers, / 255 (the same arithmetic as PrecomputationGridStack::raw_value, with the level's
/// lookups hoisted).
class NodeScorer {
 public:
  NodeScorer(const PrecomputationGridStack& stack, const DiscretisedScan& scan)
      : scan_(scan), scale_(1.0 / (255.0 * static_cast<double>(scan.n))) {
    for (int h = 0; h < stack.depth(); ++h) levels_.push_back(stack.level(h));
  }

  /// The score of node `c` at `height` (Hess eq. (15): a bound of its leaves' scores); counted in
  /// `nodes_scored`.
  double score(const Candidate& c, int height, long& nodes_scored) const {
    const PrecomputationGridStack::LevelView& level = levels_[static_cast<std::size_t>(height)];
    const long di = c.dx - level.offset_i, dj = c.dy - level.offset_j;
    const std::int32_t* is = scan_.cell_i.data() + static_cast<std::size_t>(c.angle_index) * scan_.n;
    const std::int32_t* js = scan_.cell_j.data() + static_cast<std::size_t>(c.angle_index) * scan_.n;
    std::uint64_t sum = 0;
    for (std::size_t k = 0; k < scan_.n; ++k) {
      const long li = is[k] + di, lj = js[k] + dj;
      const bool inside = static_cast<unsigned long>(li) < static_cast<unsigned long>(level.width) &&
                          static_cast<unsigned long>(lj) < static_cast<unsigned long>(level.height);
      sum += inside ? level.values[lj * level.width + li] : level.outside;
    }
    ++nodes_scored;
    return static_cast<double>(sum) * scale_;
  }

  /// The four children of a node (offsets 0 / half in x and y) in one pass over the points: the
  /// points' cells are loaded once instead of four times and the four lookups are independent.
  /// Integer sums, so exactly the four scores `score` gives. sums: (0, 0), (half, 0), (0, half),
  /// (half, half).
  void score_children(const Candidate& parent, int height, long half, std::uint64_t sums[4]) const {
    const PrecomputationGridStack::LevelView& level = levels_[static_cast<std::size_t>(height)];
    const long di = parent.dx - level.offset_i, dj = parent.dy - level.offset_j;
    const auto width = static_cast<unsigned long>(level.width), rows = static_cast<unsigned long>(level.height);
    const std::uint8_t* values = level.values;
    const std::uint8_t outside = level.outside;
    const std::int32_t* is = scan_.cell_i.data() + static_cast<std::size_t>(parent.angle_index) * scan_.n;
    const std::int32_t* js = scan_.cell_j.data() + static_cast<std::size_t>(parent.angle_index) * scan_.n;
    std::uint64_t s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (std::size_t k = 0; k < scan_.n; ++k) {
      const long li0 = is[k] + di, lj0 = js[k] + dj;
      const long li1 = li0 + half, lj1 = lj0 + half;
      const bool in_i0 = static_cast<unsigned long>(li0) < width, in_i1 = static_cast<unsigned long>(li1) < width;
      const bool in_j0 = static_cast<unsigned long>(lj0) < rows, in_j1 = static_cast<unsigned long>(lj1) < rows;
      const long row0 = lj0 * level.width, row1 = lj1 * level.width;
      s0 += in_i0 && in_j0 ? values[row0 + li0] : outside;
      s1 += in_i1 && in_j0 ? values[row0 + li1] : outside;
      s2 += in_i0 && in_j1 ? values[row1 + li0] : outside;
      s3 += in_i1 && in_j1 ? values[row1 + li1] : outside;
    }
    sums[0] = s0;
    sums[1] = s1;
    sums[2] = s2;
    sums[3] = s3;
  }

  /// The score of a node whose byte sum is `sum`.
  double scaled(std::uint64_t sum) const { return static_cast<double>(sum) * scale_; }

 private:
  const DiscretisedScan& scan_;
  double scale_;
  std::vector<PrecomputationGridStack::LevelView> levels_;
};

/// What the search explores: the offsets in cells (+-linear_steps in x and y), the top height,
/// and where a leaf lies (pose_of) and whether it is excluded.
struct SearchWindow {
  const core::SE2& initial;
  const DiscretisedScan& scan;
  double r = 0.0;
  int angles = 0;
  long linear_steps = 0;
  int top = 0;
  const core::SE2* excluded = nullptr;
  double excluded_distance_m = 0.0;
  double excluded_angle_rad = 0.0;

  /// The pose of a candidate.
  core::SE2 pose_of(const Candidate& c) const {
    return core::SE2(initial.so2() * core::SO2(scan.angle_of[static_cast<std::size_t>(c.angle_index)]),
                     initial.translation() + Eigen::Vector2d(static_cast<double>(c.dx) * r, static_cast<double>(c.dy) * r));
  }
  /// Whether a leaf lies within the excluded distance and angle of the excluded pose.
  bool is_excluded(const Candidate& c) const {
    if (excluded == nullptr) return false;
    const core::SE2 T = pose_of(c);
    return (T.translation() - excluded->translation()).norm() <= excluded_distance_m &&
           std::abs(core::wrap_angle(T.angle() - excluded->angle())) <= excluded_angle_rad;
  }
};

/// Root candidates at the top height (Hess Alg. 2), sorted by bound, best first.
std::vector<Candidate> root_candidates(const SearchWindow& window, const NodeScorer& scorer, long& nodes_scored) {
  const long top_width = 1L << window.top;
  std::vector<Candidate> roots;
  for (int a = 0; a < window.angles; ++a) {
    for (long dx = -window.linear_steps; dx <= window.linear_steps; dx += top_width) {
      for (long dy = -window.linear_steps; dy <= window.linear_steps; dy += top_width) {
        Candidate c{a, dx, dy, 0.0};
        c.score = scorer.score(c, window.top, nodes_scored);
        roots.push_back(c);
      }
    }
  }
  std::sort(roots.begin(), roots.end(), [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  return roots;
}

/// The children of `c` (at `height` >= 1) scoring above `best`, worst first (so the best is
/// explored next from the stack).
void branch(const Candidate& c, int height, double best, const SearchWindow& window, const NodeScorer& scorer,
            long& nodes_scored, std::vector<Candidate>& children) {
  const long half = 1L << (height - 1);
  children.clear();
  std::uint64_t sums[4];
  scorer.score_children(c, height - 1, half, sums);
  for (const long ox : {0L, half}) {
    for (const long oy : {0L, half}) {
      Candidate child{c.angle_index, c.dx + ox, c.dy + oy, 0.0};
      if (child.dx > window.linear_steps || child.dy > window.linear_steps) continue;
      ++nodes_scored;
      child.score = scorer.scaled(sums[(ox != 0 ? 1 : 0) + (oy != 0 ? 2 : 0)]);
      if (child.score > best) children.push_back(child);
    }
  }
  std::sort(children.begin(), children.end(), [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
}

/// Depth-first branch and bound (Hess Alg. 3) from the roots, explicit stack of (candidate,
/// height): the best leaf above `min_score` that is not excluded, into `best_candidate` (and
/// `result.found`, `result.nodes_scored`). Returns its score (`min_score` when none).
double search_depth_first(const std::vector<Candidate>& roots, double min_score, const SearchWindow& window,
                        const NodeScorer& scorer, BranchAndBoundResult& result, Candidate& best_candidate) {
  double best = min_score;
  std::vector<std::pair<Candidate, int>> pending;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) pending.emplace_back(*it, window.top);
  std::vector<Candidate> children;
  while (!pending.empty()) {
    const auto [c, height] = pending.back();
    pending.pop_back();
    if (c.score <= best) continue;
    if (height == 0) {
      if (window.is_excluded(c)) continue;
      best = c.score;
      best_candidate = c;
      result.found = true;
      continue;
    }
    branch(c, height, best, window, scorer, result.nodes_scored, children);
    for (const auto& child : children) pending.emplace_back(child, height - 1);  // best child on top
  }
  return best;
}
}  // namespace

BranchAndBoundResult match_branch_and_bound(const PrecomputationGridStack& stack,
                                            const std::vector<Eigen::Vector2d>& points_sensor,
                                            const core::SE2& initial, double min_score,
                                            const BranchAndBoundOptions& options, const core::SE2* excluded,
                                            double excluded_distance_m, double excluded_angle_rad) {
  BranchAndBoundResult result;
  if (points_sensor.empty()) return result;
  const double r = stack.resolution();
  const double angular_step = angular_step_of(points_sensor, r, options);
  const int angular_steps = static_cast<int>(std::ceil(options.angular_search_window_rad / angular_step));
  const long linear_steps = static_cast<long>(std::ceil(options.linear_search_window_m / r));
  const DiscretisedScan scan = discretise_scan(points_sensor, initial, r, angular_steps, angular_step);
  const NodeScorer scorer(stack, scan);
  const SearchWindow window{initial,  scan,     r, 2 * angular_steps + 1, linear_steps, stack.depth() - 1,
                            excluded, excluded_distance_m, excluded_angle_rad};
  const std::vector<Candidate> roots = root_candidates(window, scorer, result.nodes_scored);
  Candidate best_candidate;
  const double best = search_depth_first(roots, min_score, window, scorer, result, best_candidate);
  if (result.found) {
    result.T_map_sensor = window.pose_of(best_candidate);
    result.score = best;
  }
  return result;
}

}  // namespace cairn::slam2d
