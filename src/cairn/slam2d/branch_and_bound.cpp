#include "cairn/slam2d/branch_and_bound.hpp"

#include <algorithm>
#include <cmath>

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
  if (!grid.known_bounds(i0, j0, i1, j1)) i0 = j0 = i1 = j1 = 0;
  const int known_width = i1 - i0 + 1, known_height = j1 - j0 + 1;
  const long base_i = grid.offset_i() + i0;
  const long base_j = grid.offset_j() + j0;
  for (int h = 0; h < options.depth; ++h) {
    const int w = 1 << h;
    Level level;
    // Cell (i, j) of level h holds the maximum over cells [i, i + w) x [j, j + w) of the map:
    // it touches the map for i in [base - w + 1, base + width).
    level.offset_i = base_i - (w - 1);
    level.offset_j = base_j - (w - 1);
    level.width = known_width + w - 1;
    level.height = known_height + w - 1;
    level.values.assign(static_cast<std::size_t>(level.width) * static_cast<std::size_t>(level.height), outside_);
    if (h == 0) {
      for (int j = 0; j < known_height; ++j) {
        for (int i = 0; i < known_width; ++i) {
          const bool known = grid.cell_known(i + i0, j + j0);
          const double p = known ? grid.cell_probability(i + i0, j + j0) : options.unknown_probability;
          level.values[static_cast<std::size_t>(j * level.width + i)] = quantise_up(p);
        }
      }
    } else {
      // A square of side w is four squares of side w / 2: the maximum of four cells of the
      // previous level (outside it: unknown). Exact, O(area) per level.
      const Level& previous = levels_.back();
      const long half = w / 2;
      auto at = [&](long gi, long gj) {
        const long li = gi - previous.offset_i, lj = gj - previous.offset_j;
        if (li < 0 || lj < 0 || li >= previous.width || lj >= previous.height) return outside_;
        return previous.values[static_cast<std::size_t>(lj * previous.width + li)];
      };
      for (int j = 0; j < level.height; ++j) {
        const long gj = level.offset_j + j;
        for (int i = 0; i < level.width; ++i) {
          const long gi = level.offset_i + i;
          level.values[static_cast<std::size_t>(j * level.width + i)] =
              std::max(std::max(at(gi, gj), at(gi + half, gj)), std::max(at(gi, gj + half), at(gi + half, gj + half)));
        }
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
  std::vector<long> cell_i(static_cast<std::size_t>(angles) * n), cell_j(static_cast<std::size_t>(angles) * n);
  std::vector<double> angle_of(static_cast<std::size_t>(angles));
  for (int a = 0; a < angles; ++a) {
    const double angle = (a - angular_steps) * angular_step;
    angle_of[static_cast<std::size_t>(a)] = angle;
    const core::SE2 T(initial.so2() * core::SO2(angle), initial.translation());
    for (std::size_t k = 0; k < n; ++k) {
      const Eigen::Vector2d q = T * points_sensor[k];
      cell_i[static_cast<std::size_t>(a) * n + k] = static_cast<long>(std::floor(q.x() / r));
      cell_j[static_cast<std::size_t>(a) * n + k] = static_cast<long>(std::floor(q.y() / r));
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
    const long* is = cell_i.data() + static_cast<std::size_t>(c.angle_index) * n;
    const long* js = cell_j.data() + static_cast<std::size_t>(c.angle_index) * n;
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
    for (const long ox : {0L, half}) {
      for (const long oy : {0L, half}) {
        Candidate child{c.angle_index, c.dx + ox, c.dy + oy, 0.0};
        if (child.dx > linear_steps || child.dy > linear_steps) continue;
        child.score = score(child, height - 1);
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
