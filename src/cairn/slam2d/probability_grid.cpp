#include "cairn/slam2d/probability_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "cairn/core/assert.hpp"

namespace cairn::slam2d {
namespace {
double log_odds(double p) { return std::log(p / (1.0 - p)); }
double probability_of(double l) { return 1.0 - 1.0 / (1.0 + std::exp(l)); }
}  // namespace

ProbabilityGrid::ProbabilityGrid(const ProbabilityGridOptions& options) : options_(options) {
  CAIRN_ASSERT(options.resolution_m > 0.0 && options.hit_probability > 0.5 && options.hit_probability < 1.0 &&
                   options.miss_probability > 0.0 && options.miss_probability < 0.5 &&
                   options.min_probability < options.max_probability,
               "invalid ProbabilityGridOptions");
  min_log_odds_ = log_odds(options.min_probability);
  max_log_odds_ = log_odds(options.max_probability);
}

// Cells are indexed globally by floor(p / r), and the grid stores the global index of its first
// cell, so growing the grid never moves a point to another cell.
bool ProbabilityGrid::cell_of(const Eigen::Vector2d& p, int& i, int& j) const {
  const double gi = std::floor(p.x() / options_.resolution_m) - static_cast<double>(offset_i_);
  const double gj = std::floor(p.y() / options_.resolution_m) - static_cast<double>(offset_j_);
  if (!(gi >= 0.0 && gj >= 0.0 && gi < width_ && gj < height_)) return false;
  i = static_cast<int>(gi);
  j = static_cast<int>(gj);
  return true;
}

// Coordinates come from the log (a pose in UTM metres) or a saved map: out of the grid's reach
// is the input's fault, said as an error, not an assertion.
void ProbabilityGrid::throw_too_far(const Eigen::Vector2d& p) const {
  char text[256];
  std::snprintf(text, sizeof text,
                "a map point at (%.6g, %.6g) m lies more than 1e8 cells of %.6g m from the origin: the grid cannot "
                "hold it (poses in UTM-sized coordinates, or a resolution far too fine)",
                p.x(), p.y(), options_.resolution_m);
  throw std::out_of_range(text);
}

void ProbabilityGrid::grow_to_contain(const Eigen::Vector2d& p) {
  const double r = options_.resolution_m;
  const double gi = std::floor(p.x() / r);
  const double gj = std::floor(p.y() / r);
  if (!(std::abs(gi) < 1e8 && std::abs(gj) < 1e8)) throw_too_far(p);
  if (width_ == 0) {
    offset_i_ = static_cast<long>(gi) - 16;
    offset_j_ = static_cast<long>(gj) - 16;
    width_ = 32;
    height_ = 32;
    log_odds_.assign(static_cast<std::size_t>(width_ * height_), 0.0f);
    known_.assign(log_odds_.size(), 0);
  }
  int i = 0;
  int j = 0;
  if (cell_of(p, i, j)) return;
  // Double the grid in the needed directions until p fits.
  long low_i = offset_i_, low_j = offset_j_;
  long high_i = offset_i_ + width_, high_j = offset_j_ + height_;
  const long pi = static_cast<long>(gi), pj = static_cast<long>(gj);
  while (pi < low_i) low_i -= (high_i - low_i);
  while (pj < low_j) low_j -= (high_j - low_j);
  while (pi >= high_i) high_i += (high_i - low_i);
  while (pj >= high_j) high_j += (high_j - low_j);
  resize_to(low_i, low_j, high_i, high_j);
}

void ProbabilityGrid::resize_to(long low_i, long low_j, long high_i, long high_j) {
  const int new_width = static_cast<int>(high_i - low_i);
  const int new_height = static_cast<int>(high_j - low_j);
  const int di = static_cast<int>(offset_i_ - low_i);
  const int dj = static_cast<int>(offset_j_ - low_j);
  std::vector<float> grown(static_cast<std::size_t>(new_width) * static_cast<std::size_t>(new_height), 0.0f);
  std::vector<std::uint8_t> grown_known(grown.size(), 0);
  for (int jj = 0; jj < height_; ++jj) {
    const std::size_t from = static_cast<std::size_t>(jj) * static_cast<std::size_t>(width_);
    const std::size_t to = static_cast<std::size_t>(jj + dj) * static_cast<std::size_t>(new_width) + static_cast<std::size_t>(di);
    std::copy(log_odds_.begin() + static_cast<std::ptrdiff_t>(from), log_odds_.begin() + static_cast<std::ptrdiff_t>(from + static_cast<std::size_t>(width_)),
              grown.begin() + static_cast<std::ptrdiff_t>(to));
    std::copy(known_.begin() + static_cast<std::ptrdiff_t>(from), known_.begin() + static_cast<std::ptrdiff_t>(from + static_cast<std::size_t>(width_)),
              grown_known.begin() + static_cast<std::ptrdiff_t>(to));
  }
  offset_i_ = low_i;
  offset_j_ = low_j;
  width_ = new_width;
  height_ = new_height;
  log_odds_ = std::move(grown);
  known_ = std::move(grown_known);
}

void ProbabilityGrid::update(int i, int j, double change) {
  const std::size_t k = static_cast<std::size_t>(j * width_ + i);
  const double l = std::clamp(static_cast<double>(log_odds_[k]) + change, min_log_odds_, max_log_odds_);
  log_odds_[k] = static_cast<float>(l);
  known_[k] = 1;
}

void ProbabilityGrid::insert(const core::SE2& T_map_sensor, const std::vector<Eigen::Vector2d>& points_sensor,
                             const std::vector<bool>& hit) {
  CAIRN_ASSERT(points_sensor.size() == hit.size(), "one hit flag per point");
  const Eigen::Vector2d origin_map = T_map_sensor.translation();
  grow_to_contain(origin_map);
  const double miss = log_odds(options_.miss_probability);
  const double hit_change = log_odds(options_.hit_probability);
  for (std::size_t k = 0; k < points_sensor.size(); ++k) {
    const Eigen::Vector2d end = T_map_sensor * points_sensor[k];
    grow_to_contain(end);
    int i0 = 0, j0 = 0, i1 = 0, j1 = 0;
    const bool ok = cell_of(origin_map, i0, j0) && cell_of(end, i1, j1);
    CAIRN_ASSERT(ok, "grow_to_contain guarantees both cells exist");
    // Bresenham's line from the sensor cell to the end cell (exclusive): misses.
    int di = std::abs(i1 - i0), dj = -std::abs(j1 - j0);
    const int si = i0 < i1 ? 1 : -1, sj = j0 < j1 ? 1 : -1;
    int error = di + dj;
    int i = i0, j = j0;
    while (i != i1 || j != j1) {
      update(i, j, miss);
      const int e2 = 2 * error;
      if (e2 >= dj) {
        error += dj;
        i += si;
      }
      if (e2 <= di) {
        error += di;
        j += sj;
      }
    }
    update(i1, j1, hit[k] ? hit_change : miss);
  }
}

double ProbabilityGrid::cell_probability(int i, int j) const {
  if (i < 0 || j < 0 || i >= width_ || j >= height_) return 0.5;
  const std::size_t k = static_cast<std::size_t>(j * width_ + i);
  return known_[k] ? probability_of(log_odds_[k]) : 0.5;
}

double ProbabilityGrid::probability_of_log_odds(float l) { return probability_of(l); }

void ProbabilityGrid::reserve(const Eigen::Vector2d& lower, const Eigen::Vector2d& upper) {
  if (!(lower.array() <= upper.array()).all()) return;
  const double r = options_.resolution_m;
  const double i0 = std::floor(lower.x() / r), j0 = std::floor(lower.y() / r);
  const double i1 = std::floor(upper.x() / r), j1 = std::floor(upper.y() / r);
  if (!(std::abs(i0) < 1e8 && std::abs(j0) < 1e8)) throw_too_far(lower);
  if (!(std::abs(i1) < 1e8 && std::abs(j1) < 1e8)) throw_too_far(upper);
  if (width_ > 0) {
    // In one copy, on the sides the box crosses only, by at least a quarter of the grid's
    // side there (so a grid that grows keyframe by keyframe, as slam2d's submaps do, is copied
    // a few times, not at every keyframe), not by doubling (up to four times the area needed).
    long low_i = offset_i_, low_j = offset_j_, high_i = offset_i_ + width_, high_j = offset_j_ + height_;
    if (i0 < static_cast<double>(low_i)) low_i = std::min(static_cast<long>(i0), low_i - width_ / 4);
    if (j0 < static_cast<double>(low_j)) low_j = std::min(static_cast<long>(j0), low_j - height_ / 4);
    if (i1 >= static_cast<double>(high_i)) high_i = std::max(static_cast<long>(i1) + 1, high_i + width_ / 4);
    if (j1 >= static_cast<double>(high_j)) high_j = std::max(static_cast<long>(j1) + 1, high_j + height_ / 4);
    if (low_i != offset_i_ || low_j != offset_j_ || high_i != offset_i_ + width_ || high_j != offset_j_ + height_)
      resize_to(low_i, low_j, high_i, high_j);
    return;
  }
  offset_i_ = static_cast<long>(i0);
  offset_j_ = static_cast<long>(j0);
  width_ = static_cast<int>(i1 - i0) + 1;
  height_ = static_cast<int>(j1 - j0) + 1;
  log_odds_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0f);
  known_.assign(log_odds_.size(), 0);
}

float ProbabilityGrid::cell_log_odds(int i, int j) const {
  if (i < 0 || j < 0 || i >= width_ || j >= height_) return 0.0f;
  const std::size_t k = static_cast<std::size_t>(j * width_ + i);
  return known_[k] ? log_odds_[k] : 0.0f;
}

ProbabilityGrid ProbabilityGrid::from_cells(const ProbabilityGridOptions& options, long offset_i, long offset_j, int width,
                                            int height, std::vector<float> log_odds, std::vector<std::uint8_t> known) {
  ProbabilityGrid grid(options);
  CAIRN_ASSERT(width >= 0 && height >= 0 && (width == 0) == (height == 0), "grid size must be both zero or both positive");
  CAIRN_ASSERT(std::labs(offset_i) < 100000000L && std::labs(offset_j) < 100000000L, "grid offset too far from the origin");
  const std::size_t cells = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  CAIRN_ASSERT(log_odds.size() == cells && known.size() == cells, "one log-odds value and one known flag per cell");
  for (std::size_t k = 0; k < cells; ++k) {
    const double l = log_odds[k];
    if (known[k] != 0) {
      CAIRN_ASSERT(std::isfinite(l) && l >= grid.min_log_odds_ - 1e-5 && l <= grid.max_log_odds_ + 1e-5,
                   "known cell log-odds outside the clamp bounds");
      known[k] = 1;
    } else {
      CAIRN_ASSERT(l == 0.0, "unknown cells hold log-odds 0");
    }
  }
  grid.offset_i_ = offset_i;
  grid.offset_j_ = offset_j;
  grid.width_ = width;
  grid.height_ = height;
  grid.log_odds_ = std::move(log_odds);
  grid.known_ = std::move(known);
  return grid;
}

bool ProbabilityGrid::cell_known(int i, int j) const {
  if (i < 0 || j < 0 || i >= width_ || j >= height_) return false;
  return known_[static_cast<std::size_t>(j * width_ + i)] != 0;
}

bool ProbabilityGrid::known_bounds(int& i0, int& j0, int& i1, int& j1) const {
  i0 = width_;
  j0 = height_;
  i1 = -1;
  j1 = -1;
  for (int j = 0; j < height_; ++j) {
    const std::uint8_t* row = known_.data() + static_cast<std::size_t>(j) * static_cast<std::size_t>(width_);
    int first = -1, last = -1;
    for (int i = 0; i < width_; ++i) {
      if (row[i] == 0) continue;
      if (first < 0) first = i;
      last = i;
    }
    if (first < 0) continue;
    i0 = std::min(i0, first);
    i1 = std::max(i1, last);
    j0 = std::min(j0, j);
    j1 = j;
  }
  return i1 >= 0;
}

double ProbabilityGrid::probability(const Eigen::Vector2d& p) const {
  int i = 0, j = 0;
  return cell_of(p, i, j) ? cell_probability(i, j) : 0.5;
}

bool ProbabilityGrid::known(const Eigen::Vector2d& p) const {
  int i = 0, j = 0;
  return cell_of(p, i, j) && known_[static_cast<std::size_t>(j * width_ + i)] != 0;
}

}  // namespace cairn::slam2d
