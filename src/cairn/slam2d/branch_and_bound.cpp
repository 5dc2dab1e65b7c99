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

}  // namespace

PrecomputationGridStack::PrecomputationGridStack(const ProbabilityGrid& grid, const BranchAndBoundOptions& options)
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
  // Level 0: the observed box, probability * 255 rounded up. Submaps store few distinct
  // log-odds values, so the probability of each is computed once per run of equal values (the
  // same arithmetic as ProbabilityGrid::cell_probability, hence the same bytes).
  {
    Level level;
    level.offset_i = base_i;
    level.offset_j = base_j;
    level.width = known_width;
    level.height = known_height;
    level.values.assign(static_cast<std::size_t>(level.width) * static_cast<std::size_t>(level.height), outside_);
    const std::uint8_t unknown = quantise_up(options.unknown_probability);
    float last_log_odds = 0.0f;
    std::uint8_t last_value = quantise_up(ProbabilityGrid::probability_of_log_odds(0.0f));
    for (int j = 0; observed && j < known_height; ++j) {
      const float* log_odds = grid.log_odds_row(j + j0) + i0;
      const std::uint8_t* known = grid.known_row(j + j0) + i0;
      std::uint8_t* row = level.values.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(level.width);
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
    levels_.push_back(std::move(level));
  }
  // Level h from level h - 1: a square of side w = 2^h is four squares of side w / 2, so
  //   L_h(i, j) = max(L_{h-1}(i - w/2, j - w/2), L_{h-1}(i, j - w/2), L_{h-1}(i - w/2, j), L_{h-1}(i, j))
  // in each level's own indices (level h starts w/2 cells before level h - 1; outside a level:
  // unknown). Separable: a horizontal max of two shifted rows, then a vertical max of two
  // rows, both plain byte loops the compiler vectorises. Exact, O(area) per level. Measured
  // (perf, MIT CSAIL, 2026-11-25): the bounds-checked four-way version was 9 % of the run's
  // CPU time, the largest part of a submap's build.
  std::vector<std::uint8_t> padded, horizontal;
  for (int h = 1; h < options.depth; ++h) {
    const int w = 1 << h;
    const int half = w / 2;
    const Level& previous = levels_.back();
    Level level;
    level.offset_i = base_i - (w - 1);
    level.offset_j = base_j - (w - 1);
    level.width = known_width + w - 1;
    level.height = known_height + w - 1;
    CAIRN_ASSERT(level.width == previous.width + half && level.height == previous.height + half, "levels grow by half a square");
    const auto width = static_cast<std::size_t>(level.width);
    // horizontal(i, j) = max(previous(i - half, j), previous(i, j)), rows j of the previous level.
    horizontal.assign(width * static_cast<std::size_t>(previous.height), outside_);
    padded.assign(width + static_cast<std::size_t>(half), outside_);
    for (int j = 0; j < previous.height; ++j) {
      const std::uint8_t* source = previous.values.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(previous.width);
      std::copy(source, source + previous.width, padded.begin() + half);
      std::uint8_t* out = horizontal.data() + static_cast<std::size_t>(j) * width;
      const std::uint8_t* a = padded.data();
      const std::uint8_t* b = padded.data() + half;
      for (std::size_t i = 0; i < width; ++i) out[i] = std::max(a[i], b[i]);
    }
    // level(i, j) = max(horizontal(i, j - half), horizontal(i, j)); rows outside: unknown.
    level.values.assign(width * static_cast<std::size_t>(level.height), outside_);
    for (int j = 0; j < level.height; ++j) {
      std::uint8_t* out = level.values.data() + static_cast<std::size_t>(j) * width;
      const bool low = j - half >= 0 && j - half < previous.height;
      const bool high = j < previous.height;
      const std::uint8_t* a = low ? horizontal.data() + static_cast<std::size_t>(j - half) * width : nullptr;
      const std::uint8_t* b = high ? horizontal.data() + static_cast<std::size_t>(j) * width : nullptr;
      if (low && high) {
        for (std::size_t i = 0; i < width; ++i) out[i] = std::max(a[i], b[i]);
      } else if (low || high) {
        const std::uint8_t* c = low ? a : b;
        for (std::size_t i = 0; i < width; ++i) out[i] = std::max(c[i], outside_);
      }
    }
    levels_.push_back(std::move(level));
  }
}

std::size_t PrecomputationGridStack::memory_bytes() const {
  std::size_t bytes = 0;
  for (const auto& level : levels_) bytes += level.values.size();
  return bytes;
}

namespace {
struct Candidate {
  int angle_index = 0;
  long dx = 0;  ///< offset in cells
  long dy = 0;
  double score = 0.0;
};
}  // namespace

BranchAndBoundResult match_branch_and_bound(const PrecomputationGridStack& stack,
                                            const std::vector<Eigen::Vector2d>& points_sensor,
                                            const core::SE2& initial, double min_score,
                                            const BranchAndBoundOptions& options, const core::SE2* excluded,
                                            double excluded_distance_m, double excluded_angle_rad) {
  BranchAndBoundResult result;
  if (points_sensor.empty()) return result;
  const double r = stack.resolution();
  std::vector<double> ranges;
  for (const auto& p : points_sensor) ranges.push_back(p.norm());
  const auto quantile = static_cast<std::size_t>(std::ceil(options.angular_step_range_quantile * static_cast<double>(ranges.size()))) - 1;
  std::nth_element(ranges.begin(), ranges.begin() + static_cast<std::ptrdiff_t>(quantile), ranges.end());
  const double d_max = ranges[std::min(quantile, ranges.size() - 1)];
  // Hess 2016, eq. (7).
  const double angular_step = d_max > r ? std::acos(1.0 - r * r / (2.0 * d_max * d_max)) : 0.1;
  const int angular_steps = static_cast<int>(std::ceil(options.angular_search_window_rad / angular_step));
  const long linear_steps = static_cast<long>(std::ceil(options.linear_search_window_m / r));
  const int top = stack.depth() - 1;
  const long top_width = 1L << top;

  // Per angle: the cell of each point at zero offset (Hess eq. (9)-(10): the discretised scan),
  // one flat array, angle-major.
  const int angles = 2 * angular_steps + 1;
  const std::size_t n = points_sensor.size();
  // 32-bit cells (half the memory of 64-bit ones: the arrays are scanned once per node scored);
  // clamped far outside any grid (levels lie within 1e8 cells of the origin, ProbabilityGrid).
  std::vector<std::int32_t> cell_i(static_cast<std::size_t>(angles) * n), cell_j(static_cast<std::size_t>(angles) * n);
  //
  // floor(x / r) by a multiplication: x * (1 / r) differs from the correctly rounded x / r by a
  // few units in the last place at most, which moves the floor only when the quotient lies that
  // close to an integer; there the division decides. The cells are exactly those of floor(x / r),
  // at a fraction of the cost (measured with perf on MIT CSAIL, 2026-11-25: the divisions and
  // library floors of this table were a third of the branch-and-bound time, with a store-
  // forwarding stall in the compiled SE2 product; an ambiguity search's angular window can
  // reach +-180 degrees, over a thousand angles at 10 m ranges).
  const double inverse_r = 1.0 / r;
  auto cell_index = [r, inverse_r](double x) {
    const double y = std::clamp(x * inverse_r, -1e9, 1e9);
    const auto truncated = static_cast<std::int64_t>(y);
    std::int64_t cell = truncated - (y < static_cast<double>(truncated) ? 1 : 0);  // floor(y)
    const double fraction = y - static_cast<double>(cell);
    const double tolerance = 1e-12 * (1.0 + std::abs(y));
    if (fraction < tolerance || fraction > 1.0 - tolerance) cell = static_cast<std::int64_t>(std::clamp(std::floor(x / r), -1e9, 1e9));
    return static_cast<std::int32_t>(cell);
  };
  std::vector<double> angle_of(static_cast<std::size_t>(angles));
  // The points as x and y arrays; q = T * p written out as SO2 and SE2 compute it,
  // (c x - s y) + t_x and (s x + c y) + t_y, two points at a time where SSE2 is available.
  std::vector<double> xs(n), ys(n);
  for (std::size_t k = 0; k < n; ++k) {
    xs[k] = points_sensor[k].x();
    ys[k] = points_sensor[k].y();
  }
  const double tx = initial.translation().x(), ty = initial.translation().y();
  for (int a = 0; a < angles; ++a) {
    const double angle = (a - angular_steps) * angular_step;
    angle_of[static_cast<std::size_t>(a)] = angle;
    const core::SO2 R = initial.so2() * core::SO2(angle);
    const double c = R.cos(), s = R.sin();
    std::int32_t* out_i = cell_i.data() + static_cast<std::size_t>(a) * n;
    std::int32_t* out_j = cell_j.data() + static_cast<std::size_t>(a) * n;
    std::size_t k = 0;
#if defined(__SSE2__)
    // floor as in cell_index: truncate, step down where the truncation rounded up, and let the
    // division decide the lanes whose quotient lies within the tolerance of an integer.
    const __m128d vc = _mm_set1_pd(c), vs = _mm_set1_pd(s), vtx = _mm_set1_pd(tx), vty = _mm_set1_pd(ty);
    const __m128d vinverse = _mm_set1_pd(inverse_r), low = _mm_set1_pd(-1e9), high = _mm_set1_pd(1e9);
    const __m128d one = _mm_set1_pd(1.0), tiny = _mm_set1_pd(1e-12);
    const __m128d sign_mask = _mm_set1_pd(-0.0);
    auto floor2 = [&](__m128d q, std::int32_t* out) {
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
        out[0] = cell_index(qs[0]);
        out[1] = cell_index(qs[1]);
      }
    };
    for (; k + 2 <= n; k += 2) {
      const __m128d x = _mm_loadu_pd(xs.data() + k), y = _mm_loadu_pd(ys.data() + k);
      const __m128d qx = _mm_add_pd(_mm_sub_pd(_mm_mul_pd(vc, x), _mm_mul_pd(vs, y)), vtx);
      const __m128d qy = _mm_add_pd(_mm_add_pd(_mm_mul_pd(vs, x), _mm_mul_pd(vc, y)), vty);
      floor2(qx, out_i + k);
      floor2(qy, out_j + k);
    }
#endif
    for (; k < n; ++k) {
      out_i[k] = cell_index((c * xs[k] - s * ys[k]) + tx);
      out_j[k] = cell_index((s * xs[k] + c * ys[k]) + ty);
    }
  }
  // The mean of the stored bytes over the points, summed exactly in integers, / 255 (the same
  // arithmetic as PrecomputationGridStack::raw_value, with the level's lookups hoisted).
  const double scale = 1.0 / (255.0 * static_cast<double>(n));
  std::vector<PrecomputationGridStack::LevelView> levels;
  for (int h = 0; h < stack.depth(); ++h) levels.push_back(stack.level(h));
  auto score = [&](const Candidate& c, int height) {
    const PrecomputationGridStack::LevelView& level = levels[static_cast<std::size_t>(height)];
    const long di = c.dx - level.offset_i, dj = c.dy - level.offset_j;
    const std::int32_t* is = cell_i.data() + static_cast<std::size_t>(c.angle_index) * n;
    const std::int32_t* js = cell_j.data() + static_cast<std::size_t>(c.angle_index) * n;
    std::uint64_t sum = 0;
    for (std::size_t k = 0; k < n; ++k) {
      const long li = is[k] + di, lj = js[k] + dj;
      const bool inside = static_cast<unsigned long>(li) < static_cast<unsigned long>(level.width) &&
                          static_cast<unsigned long>(lj) < static_cast<unsigned long>(level.height);
      sum += inside ? level.values[lj * level.width + li] : level.outside;
    }
    ++result.nodes_scored;
    return static_cast<double>(sum) * scale;
  };
  // The four children of a node (offsets 0 / half in x and y) in one pass over the points: the
  // points' cells are loaded once instead of four times and the four lookups are independent.
  // Integer sums, so exactly the four scores `score` gives. sums: (0, 0), (half, 0), (0, half),
  // (half, half).
  auto score_children = [&](const Candidate& parent, int height, long half, std::uint64_t sums[4]) {
    const PrecomputationGridStack::LevelView& level = levels[static_cast<std::size_t>(height)];
    const long di = parent.dx - level.offset_i, dj = parent.dy - level.offset_j;
    const auto width = static_cast<unsigned long>(level.width), rows = static_cast<unsigned long>(level.height);
    const std::uint8_t* values = level.values;
    const std::uint8_t outside = level.outside;
    const std::int32_t* is = cell_i.data() + static_cast<std::size_t>(parent.angle_index) * n;
    const std::int32_t* js = cell_j.data() + static_cast<std::size_t>(parent.angle_index) * n;
    std::uint64_t s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    for (std::size_t k = 0; k < n; ++k) {
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
  };
  auto pose_of = [&](const Candidate& c) {
    return core::SE2(initial.so2() * core::SO2(angle_of[static_cast<std::size_t>(c.angle_index)]),
                     initial.translation() + Eigen::Vector2d(static_cast<double>(c.dx) * r, static_cast<double>(c.dy) * r));
  };
  auto is_excluded = [&](const Candidate& c) {
    if (excluded == nullptr) return false;
    const core::SE2 T = pose_of(c);
    return (T.translation() - excluded->translation()).norm() <= excluded_distance_m &&
           std::abs(core::wrap_angle(T.angle() - excluded->angle())) <= excluded_angle_rad;
  };

  // Root candidates at the top height (Hess Alg. 2), sorted by bound, best first.
  std::vector<Candidate> roots;
  for (int a = 0; a < angles; ++a) {
    for (long dx = -linear_steps; dx <= linear_steps; dx += top_width) {
      for (long dy = -linear_steps; dy <= linear_steps; dy += top_width) {
        Candidate c{a, dx, dy, 0.0};
        c.score = score(c, top);
        roots.push_back(c);
      }
    }
  }
  std::sort(roots.begin(), roots.end(), [](const Candidate& a, const Candidate& b) { return a.score > b.score; });

  double best = min_score;
  Candidate best_candidate;
  // Depth-first (Hess Alg. 3), explicit stack of (candidate, height).
  std::vector<std::pair<Candidate, int>> pending;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) pending.emplace_back(*it, top);
  std::vector<Candidate> children;
  while (!pending.empty()) {
    const auto [c, height] = pending.back();
    pending.pop_back();
    if (c.score <= best) continue;
    if (height == 0) {
      if (is_excluded(c)) continue;
      best = c.score;
      best_candidate = c;
      result.found = true;
      continue;
    }
    const long half = 1L << (height - 1);
    children.clear();
    std::uint64_t sums[4];
    score_children(c, height - 1, half, sums);
    for (const long ox : {0L, half}) {
      for (const long oy : {0L, half}) {
        Candidate child{c.angle_index, c.dx + ox, c.dy + oy, 0.0};
        if (child.dx > linear_steps || child.dy > linear_steps) continue;
        ++result.nodes_scored;
        child.score = static_cast<double>(sums[(ox != 0 ? 1 : 0) + (oy != 0 ? 2 : 0)]) * scale;
        if (child.score > best) children.push_back(child);
      }
    }
    std::sort(children.begin(), children.end(), [](const Candidate& a, const Candidate& b) { return a.score < b.score; });
    for (const auto& child : children) pending.emplace_back(child, height - 1);  // best child on top
  }
  if (result.found) {
    result.T_map_sensor = pose_of(best_candidate);
    result.score = best;
  }
  return result;
}

}  // namespace cairn::slam2d
