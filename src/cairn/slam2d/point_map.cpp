#include "cairn/slam2d/point_map.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdint>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define CAIRN_POINT_MAP_AVX 1
#endif

#include "cairn/core/assert.hpp"
#include "cairn/slam2d/cell_hash.hpp"

namespace cairn::slam2d {

PointMap::PointMap(const PointMapOptions& options) : options_(options) {
  CAIRN_ASSERT(options.cell_size_m > 0.0 && options.normal_radius_m > 0.0, "invalid PointMapOptions");
}

std::uint64_t PointMap::key(std::int64_t i, std::int64_t j) {
  return (static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffULL);
}

std::uint64_t PointMap::key(const Eigen::Vector2d& p) const {
  return key(static_cast<std::int64_t>(std::floor(p.x() / options_.cell_size_m)),
             static_cast<std::int64_t>(std::floor(p.y() / options_.cell_size_m)));
}

namespace {
// std::floor(x) as an integer without the library call (no SSE4.1 rounding at the default
// target): truncation, one down where it rounded up. Exact for |x| < 2^62.
std::int64_t floor_to_int(double x) {
  const auto truncated = static_cast<std::int64_t>(x);
  return truncated - (static_cast<double>(truncated) > x ? 1 : 0);
}


// A block of a cell's normal candidates: its bounding box and its range in the candidate arrays.
struct NormalCandidateBlock {
  double low_x = 0.0, low_y = 0.0, high_x = 0.0, high_y = 0.0;
  std::uint32_t begin = 0, end = 0;
};

#if defined(CAIRN_POINT_MAP_AVX)
// The normals' sums of four points in one AVX register (four lanes instead of SSE2's two), over
// the candidate blocks that reach one of the four: per lane the same subtractions, products, sums
// and `inside` test as the SSE2 loop in pack_normal_sums, in the same order (target "avx" only, no
// FMA, so no product is contracted), hence bit-identical sums; the blocks' reach test for the four
// points at once (a block is skipped only when its box is farther than the radius from all four,
// as in the SSE2 path). Chosen at run time (the default target has no AVX). Measured with perf on
// MIT CSAIL (2026-11-25): the normals were 15 % of `cairn slam2d`'s CPU time, two thirds of it on
// the front end's thread. A/B on MIT CSAIL (idle, 3 runs each, report.json): local_map
// 0.56-0.66 s -> 0.52 s (with the point-map queries below, wall 2.08-2.25 s -> 1.91-1.94 s).
__attribute__((target("avx"))) void normal_sums_avx(const double* xs, const double* ys, const NormalCandidateBlock* blocks,
                                                     std::size_t block_count, const double* px, const double* py,
                                                     double radius2, double* out) {
  const __m256d r2 = _mm256_set1_pd(radius2);
  const __m256d one = _mm256_set1_pd(1.0);
  const __m256d zero = _mm256_setzero_pd();
  const __m256d bx = _mm256_loadu_pd(px), by = _mm256_loadu_pd(py);
  __m256d ax = _mm256_setzero_pd(), ay = ax, axx = ax, axy = ax, ayy = ax, an = ax;
  for (std::size_t r = 0; r < block_count; ++r) {
    const NormalCandidateBlock& block = blocks[r];
    const __m256d gx = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_set1_pd(block.low_x), bx),
                                                   _mm256_sub_pd(bx, _mm256_set1_pd(block.high_x))), zero);
    const __m256d gy = _mm256_max_pd(_mm256_max_pd(_mm256_sub_pd(_mm256_set1_pd(block.low_y), by),
                                                   _mm256_sub_pd(by, _mm256_set1_pd(block.high_y))), zero);
    const __m256d reach =
        _mm256_cmp_pd(_mm256_add_pd(_mm256_mul_pd(gx, gx), _mm256_mul_pd(gy, gy)), r2, _CMP_NGT_US);
    if (_mm256_movemask_pd(reach) == 0) continue;
    for (std::uint32_t k = block.begin; k < block.end; ++k) {
      const __m256d qx = _mm256_set1_pd(xs[k]), qy = _mm256_set1_pd(ys[k]);
      const __m256d qxx = _mm256_mul_pd(qx, qx), qxy = _mm256_mul_pd(qx, qy), qyy = _mm256_mul_pd(qy, qy);
      const __m256d dx = _mm256_sub_pd(qx, bx), dy = _mm256_sub_pd(qy, by);
      const __m256d inside =
          _mm256_cmp_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), r2, _CMP_NGT_US);
      ax = _mm256_add_pd(ax, _mm256_and_pd(inside, qx));
      ay = _mm256_add_pd(ay, _mm256_and_pd(inside, qy));
      axx = _mm256_add_pd(axx, _mm256_and_pd(inside, qxx));
      axy = _mm256_add_pd(axy, _mm256_and_pd(inside, qxy));
      ayy = _mm256_add_pd(ayy, _mm256_and_pd(inside, qyy));
      an = _mm256_add_pd(an, _mm256_and_pd(inside, one));
    }
  }
  _mm256_storeu_pd(out, ax);
  _mm256_storeu_pd(out + 4, ay);
  _mm256_storeu_pd(out + 8, axx);
  _mm256_storeu_pd(out + 12, axy);
  _mm256_storeu_pd(out + 16, ayy);
  _mm256_storeu_pd(out + 20, an);
}
const bool kHaveAvx = [] {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx") != 0;
}();
#endif
}  // namespace

const PointMap::Cell* PointMap::find(std::uint64_t cell_key) const {
  if (table_.empty()) return nullptr;
  const std::size_t mask = table_.size() - 1;
  for (std::size_t slot = mix_cell_key(cell_key) & mask;; slot = (slot + 1) & mask) {
    const Cell& cell = table_[slot];
    if (cell.end == 0) return nullptr;
    if (cell.key == cell_key) return &cell;
  }
}

const PointMap::Cell* PointMap::find(std::int64_t i, std::int64_t j) const {
  if (dense_.empty()) return find(key(i, j));
  const std::int64_t di = i - dense_i0_, dj = j - dense_j0_;
  if (di < 0 || dj < 0 || di >= dense_width_ || dj >= dense_height_) return nullptr;
  const Cell& cell = dense_[static_cast<std::size_t>(dj * dense_width_ + di)];
  return cell.end == 0 ? nullptr : &cell;
}

namespace {
/// Fills `order` with the point indices grouped by cell key, keeping insertion order within a
/// cell (a stable sort).
void group_by_cell(const std::vector<std::uint64_t>& keys, std::vector<std::uint32_t>& order) {
  order.resize(keys.size());
  for (std::uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return keys[a] < keys[b]; });
}

/// Indexes the groups of `order` by an open-addressing table (linear probing, power-of-two size,
/// at most half full): one allocation instead of one per cell. (`Cell` is PointMap's.)
template <class Cell>
void index_cells(const std::vector<std::uint64_t>& keys, const std::vector<std::uint32_t>& order, std::vector<Cell>& table) {
  std::size_t cells = 0;
  for (std::size_t i = 0; i < order.size(); ++i)
    if (i == 0 || keys[order[i]] != keys[order[i - 1]]) ++cells;
  std::size_t size = 16;
  while (size < 2 * cells) size *= 2;
  table.assign(size, Cell{});
  const std::size_t mask = size - 1;
  for (std::size_t begin = 0; begin < order.size();) {
    std::size_t end = begin + 1;
    while (end < order.size() && keys[order[end]] == keys[order[begin]]) ++end;
    const std::uint64_t cell_key = keys[order[begin]];
    std::size_t slot = mix_cell_key(cell_key) & mask;
    while (table[slot].end != 0) slot = (slot + 1) & mask;
    table[slot] = Cell{cell_key, static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(end)};
    begin = end;
  }
}

/// The bounding box of every kBlockSize consecutive points of each cell (`sorted` in cell
/// order), each cell's first block recorded in it. (`Cell` and `Block` are PointMap's.)
template <std::uint32_t kBlockSize, class Cell, class Block>
void bound_blocks(const std::vector<Eigen::Vector2d>& sorted, std::vector<Cell>& table, std::vector<Block>& blocks) {
  blocks.clear();
  for (Cell& cell : table) {
    if (cell.end == 0) continue;
    cell.block = static_cast<std::uint32_t>(blocks.size());
    for (std::uint32_t first = cell.begin; first < cell.end; first += kBlockSize) {
      const std::uint32_t last = std::min(cell.end, first + kBlockSize);
      Block block{sorted[first].x(), sorted[first].y(), sorted[first].x(), sorted[first].y()};
      for (std::uint32_t o = first + 1; o < last; ++o) {
        block.low_x = std::min(block.low_x, sorted[o].x());
        block.low_y = std::min(block.low_y, sorted[o].y());
        block.high_x = std::max(block.high_x, sorted[o].x());
        block.high_y = std::max(block.high_y, sorted[o].y());
      }
      blocks.push_back(block);
    }
  }
}

/// The cells' bounding box, in cell indices (floor(p / cell size)).
struct CellBox {
  std::int64_t i_low = INT64_MAX, i_high = INT64_MIN, j_low = INT64_MAX, j_high = INT64_MIN;
};

/// The bounding box of the cells of `points`.
CellBox cell_box(const std::vector<MapPoint>& points, double cell_size_m) {
  CellBox box;
  for (const MapPoint& point : points) {
    const auto i = static_cast<std::int64_t>(std::floor(point.position.x() / cell_size_m));
    const auto j = static_cast<std::int64_t>(std::floor(point.position.y() / cell_size_m));
    box.i_low = std::min(box.i_low, i);
    box.i_high = std::max(box.i_high, i);
    box.j_low = std::min(box.j_low, j);
    box.j_high = std::max(box.j_high, j);
  }
  return box;
}

/// Copies every used cell of `table` into the dense index `dense` (width x height cells from
/// (i0, j0), already sized). (`Cell` is PointMap's.)
template <class Cell>
void fill_dense_index(const std::vector<Cell>& table, const std::vector<MapPoint>& points,
                      const std::vector<std::uint32_t>& order, double cell_size_m, std::int64_t i0, std::int64_t j0,
                      std::int64_t width, std::vector<Cell>& dense) {
  for (const Cell& cell : table) {
    if (cell.end == 0) continue;
    const Eigen::Vector2d& p = points[order[cell.begin]].position;
    const auto i = static_cast<std::int64_t>(std::floor(p.x() / cell_size_m));
    const auto j = static_cast<std::int64_t>(std::floor(p.y() / cell_size_m));
    dense[static_cast<std::size_t>((j - j0) * width + (i - i0))] = cell;
  }
}

// Normals cell by cell: the points of a cell share their candidate neighbours (the cells within
// `reach`), gathered once per cell in the same order a per-point scan would visit them, so the
// sums and the normals are exactly those of the per-point search. The sums are kept as the
// five distinct scalars of (sum q, sum q q^T).
//
// The candidates are copied into flat x / y arrays and a cell's points are done kPack at a
// time: one pass over the candidates updates the sums of kPack points, each with the
// candidates in the same order and the same double arithmetic as a per-point loop (a
// candidate outside the radius adds exactly 0), so the normals are bit-identical; the inner
// loop is branch-free, two lanes per SSE2 register (GCC did not vectorise the plain loop), and
// skips the candidate blocks out of every pack point's reach. Measured with perf on MIT CSAIL
// (2026-11-25): these sums were a fifth of `cairn slam2d`'s CPU time, most of it the local map
// rebuilt at every keyframe on the front end's thread; about 30 % less after this change
// (0.85 -> ~0.6 s of CPU; a shared, noisy machine).
constexpr int kPack = 4;

/// The candidate neighbours of one cell's points: flat x / y arrays and their blocks.
struct NormalCandidates {
  std::vector<double> x, y;
  std::vector<NormalCandidateBlock> blocks;  ///< ranges in x / y
};

/// Appends the points of cell `other` (in `sorted`, with its kBlockSize-point blocks' boxes in
/// `blocks`) to the candidates, block by block. (`Cell` and `Block` are PointMap's.)
template <std::uint32_t kBlockSize, class Cell, class Block>
void add_candidates(const Cell& other, const std::vector<Block>& blocks, const std::vector<Eigen::Vector2d>& sorted,
                    NormalCandidates& candidates) {
  const Block* block = blocks.data() + other.block;
  for (std::uint32_t start = other.begin; start < other.end; start += kBlockSize, ++block) {
    const std::uint32_t last = std::min(other.end, start + kBlockSize);
    const std::size_t at = candidates.x.size();
    candidates.blocks.push_back({block->low_x, block->low_y, block->high_x, block->high_y, static_cast<std::uint32_t>(at),
                                 static_cast<std::uint32_t>(at + (last - start))});
    candidates.x.resize(at + (last - start));
    candidates.y.resize(at + (last - start));
    for (std::uint32_t o = start; o < last; ++o) {
      candidates.x[at + (o - start)] = sorted[o].x();
      candidates.y[at + (o - start)] = sorted[o].y();
    }
  }
}

/// The normal sums of a pack of kPack points: per point, over the candidates within the radius,
/// sum q (sx, sy), sum q q^T (sxx, sxy, syy) and their count.
struct PackSums {
  double sx[kPack] = {}, sy[kPack] = {}, sxx[kPack] = {}, sxy[kPack] = {}, syy[kPack] = {}, count[kPack] = {};
};

/// Whether `bounds` lies within the radius of some point of the pack (px, py).
bool pack_reaches(const NormalCandidateBlock& bounds, const double* px, const double* py, double radius2) {
  for (int b = 0; b < kPack; ++b) {
    const double dx = std::max(0.0, std::max(bounds.low_x - px[b], px[b] - bounds.high_x));
    const double dy = std::max(0.0, std::max(bounds.low_y - py[b], py[b] - bounds.high_y));
    if (!(dx * dx + dy * dy > radius2)) return true;
  }
  return false;
}

#if defined(__SSE2__)
/// The sums of the pack (px, py) over the candidates, two lanes per SSE2 register.
PackSums pack_normal_sums_sse2(const NormalCandidates& candidates, const double* px, const double* py, double radius2) {
  PackSums out;
  const double* xs = candidates.x.data();
  const double* ys = candidates.y.data();
  // Two lanes per register, two registers per pack; the candidate's products are the same
  // for every lane. `inside` is !(d2 > radius2), the per-point loop's test.
  const __m128d r2 = _mm_set1_pd(radius2);
  const __m128d one = _mm_set1_pd(1.0);
  __m128d ax[2], ay[2], axx[2], axy[2], ayy[2], an[2], bx[2], by[2];
  for (int h = 0; h < 2; ++h) {
    ax[h] = ay[h] = axx[h] = axy[h] = ayy[h] = an[h] = _mm_setzero_pd();
    bx[h] = _mm_loadu_pd(px + 2 * h);
    by[h] = _mm_loadu_pd(py + 2 * h);
  }
  for (const NormalCandidateBlock& block : candidates.blocks) {
    if (!pack_reaches(block, px, py, radius2)) continue;
    for (std::uint32_t k = block.begin; k < block.end; ++k) {
      const __m128d qx = _mm_set1_pd(xs[k]), qy = _mm_set1_pd(ys[k]);
      const __m128d qxx = _mm_mul_pd(qx, qx), qxy = _mm_mul_pd(qx, qy), qyy = _mm_mul_pd(qy, qy);
      for (int h = 0; h < 2; ++h) {
        const __m128d dx = _mm_sub_pd(qx, bx[h]), dy = _mm_sub_pd(qy, by[h]);
        const __m128d inside = _mm_cmpngt_pd(_mm_add_pd(_mm_mul_pd(dx, dx), _mm_mul_pd(dy, dy)), r2);
        ax[h] = _mm_add_pd(ax[h], _mm_and_pd(inside, qx));
        ay[h] = _mm_add_pd(ay[h], _mm_and_pd(inside, qy));
        axx[h] = _mm_add_pd(axx[h], _mm_and_pd(inside, qxx));
        axy[h] = _mm_add_pd(axy[h], _mm_and_pd(inside, qxy));
        ayy[h] = _mm_add_pd(ayy[h], _mm_and_pd(inside, qyy));
        an[h] = _mm_add_pd(an[h], _mm_and_pd(inside, one));
      }
    }
  }
  for (int h = 0; h < 2; ++h) {
    _mm_storeu_pd(out.sx + 2 * h, ax[h]);
    _mm_storeu_pd(out.sy + 2 * h, ay[h]);
    _mm_storeu_pd(out.sxx + 2 * h, axx[h]);
    _mm_storeu_pd(out.sxy + 2 * h, axy[h]);
    _mm_storeu_pd(out.syy + 2 * h, ayy[h]);
    _mm_storeu_pd(out.count + 2 * h, an[h]);
  }
  return out;
}
#else
/// The sums of the pack (px, py) over the candidates, one point at a time.
PackSums pack_normal_sums_scalar(const NormalCandidates& candidates, const double* px, const double* py, double radius2) {
  PackSums out;
  const double* xs = candidates.x.data();
  const double* ys = candidates.y.data();
  for (const NormalCandidateBlock& block : candidates.blocks) {
    if (!pack_reaches(block, px, py, radius2)) continue;
    for (std::uint32_t k = block.begin; k < block.end; ++k) {
      const double qx = xs[k], qy = ys[k];
      for (int b = 0; b < kPack; ++b) {
        const double dx = qx - px[b], dy = qy - py[b];
        if (dx * dx + dy * dy > radius2) continue;
        out.sx[b] += qx;
        out.sy[b] += qy;
        out.sxx[b] += qx * qx;
        out.sxy[b] += qx * qy;
        out.syy[b] += qy * qy;
        out.count[b] += 1.0;
      }
    }
  }
  return out;
}
#endif

/// The sums of the pack (px, py) over the candidates: AVX when the CPU has it, else SSE2, else
/// scalar, with the same arithmetic in the same order (bit-identical sums). A block whose box
/// lies farther than the radius from every point of the pack adds nothing to any of them (every
/// candidate in it has d2 >= the box's d2 > radius2) and is skipped; the others are summed in
/// their order.
PackSums pack_normal_sums(const NormalCandidates& candidates, const double* px, const double* py, double radius2) {
#if defined(CAIRN_POINT_MAP_AVX)
  static_assert(kPack == 4, "normal_sums_avx does four points");
  if (kHaveAvx) {
    PackSums out;
    double sums[6 * kPack];
    normal_sums_avx(candidates.x.data(), candidates.y.data(), candidates.blocks.data(), candidates.blocks.size(), px, py,
                    radius2, sums);
    for (int b = 0; b < kPack; ++b) {
      out.sx[b] = sums[b];
      out.sy[b] = sums[4 + b];
      out.sxx[b] = sums[8 + b];
      out.sxy[b] = sums[12 + b];
      out.syy[b] = sums[16 + b];
      out.count[b] = sums[20 + b];
    }
    return out;
  }
#endif
#if defined(__SSE2__)
  return pack_normal_sums_sse2(candidates, px, py, radius2);
#else
  return pack_normal_sums_scalar(candidates, px, py, radius2);
#endif
}

/// Point `b` of the pack gets the direction of least spread of its neighbours as its normal when
/// it has enough of them and they lie along a line (PointMapOptions).
void fit_normal(const PackSums& sums, int b, const PointMapOptions& options, MapPoint& point) {
  const int n = static_cast<int>(sums.count[b]);  // exact: counts far below 2^53
  if (n < options.normal_min_neighbours) return;
  const Eigen::Vector2d mean = Eigen::Vector2d(sums.sx[b], sums.sy[b]) / n;
  Eigen::Matrix2d outer;
  outer << sums.sxx[b], sums.sxy[b], sums.sxy[b], sums.syy[b];
  const Eigen::Matrix2d covariance = outer / n - mean * mean.transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(covariance);
  const double largest = eigen.eigenvalues()(1);
  if (!(largest > 0.0) || eigen.eigenvalues()(0) > options.normal_max_eigenvalue_ratio * largest) return;
  point.normal = eigen.eigenvectors().col(0).normalized();
  point.has_normal = true;
}

/// The normals of the points order[begin, end) of one cell, kPack at a time, from the cell's
/// candidate neighbours.
void fit_cell_normals(const NormalCandidates& candidates, const std::vector<std::uint32_t>& order, std::uint32_t begin,
                      std::uint32_t end, double radius2, const PointMapOptions& options, std::vector<MapPoint>& points) {
  for (std::uint32_t o = begin; o < end; o += kPack) {
    const int pack = static_cast<int>(std::min<std::uint32_t>(kPack, end - o));
    double px[kPack], py[kPack];
    for (int b = 0; b < kPack; ++b) {
      // Unused lanes repeat the last point (their sums are discarded).
      const Eigen::Vector2d& p = points[order[o + static_cast<std::uint32_t>(std::min(b, pack - 1))]].position;
      px[b] = p.x();
      py[b] = p.y();
    }
    const PackSums sums = pack_normal_sums(candidates, px, py, radius2);
    for (int b = 0; b < pack; ++b) fit_normal(sums, b, options, points[order[o + static_cast<std::uint32_t>(b)]]);
  }
}
}  // namespace

void PointMap::build(const std::vector<Eigen::Vector2d>& points) {
  points_.clear();
  order_.clear();
  table_.clear();
  sorted_.clear();
  dense_.clear();
  dense_width_ = dense_height_ = 0;
  points_.reserve(points.size());
  std::vector<std::uint64_t> keys;
  keys.reserve(points.size());
  for (const auto& p : points) {
    if (!p.allFinite()) continue;
    keys.push_back(key(p));
    points_.push_back(MapPoint{p, Eigen::Vector2d::Zero(), false});
  }
  if (points_.empty()) return;
  // Group the point indices by cell, keeping insertion order within a cell (a stable sort), and
  // index the groups by an open-addressing table: one allocation instead of one per cell.
  group_by_cell(keys, order_);
  index_cells(keys, order_, table_);
  sorted_.resize(order_.size());
  for (std::size_t o = 0; o < order_.size(); ++o) sorted_[o] = points_[order_[o]].position;
  bound_blocks<kBlock>(sorted_, table_, blocks_);
  // The dense index, when the cells' bounding box holds at most 16 cells per point (or 4096).
  const CellBox cells = cell_box(points_, options_.cell_size_m);
  const double box = (static_cast<double>(cells.i_high) - static_cast<double>(cells.i_low) + 1.0) *
                     (static_cast<double>(cells.j_high) - static_cast<double>(cells.j_low) + 1.0);
  if (box <= std::max(4096.0, 16.0 * static_cast<double>(points_.size()))) {
    dense_i0_ = cells.i_low;
    dense_j0_ = cells.j_low;
    dense_width_ = cells.i_high - cells.i_low + 1;
    dense_height_ = cells.j_high - cells.j_low + 1;
    dense_.assign(static_cast<std::size_t>(dense_width_ * dense_height_), Cell{});
    fill_dense_index(table_, points_, order_, options_.cell_size_m, dense_i0_, dense_j0_, dense_width_, dense_);
  }
  // Normals cell by cell (see kPack), cells in parallel (each point's normal is written by one
  // task only: deterministic).
  const double radius2 = options_.normal_radius_m * options_.normal_radius_m;
  const int reach = static_cast<int>(std::ceil(options_.normal_radius_m / options_.cell_size_m));
  auto normals = [&](const tbb::blocked_range<std::size_t>& range) {
    NormalCandidates candidates;
    for (std::size_t slot = range.begin(); slot != range.end(); ++slot) {
      const Cell& cell = table_[slot];
      if (cell.end == 0) continue;
      const MapPoint& first = points_[order_[cell.begin]];
      const auto ci = static_cast<std::int64_t>(std::floor(first.position.x() / options_.cell_size_m));
      const auto cj = static_cast<std::int64_t>(std::floor(first.position.y() / options_.cell_size_m));
      candidates.x.clear();
      candidates.y.clear();
      candidates.blocks.clear();
      for (int di = -reach; di <= reach; ++di)
        for (int dj = -reach; dj <= reach; ++dj)
          if (const Cell* other = find(ci + di, cj + dj)) add_candidates<kBlock>(*other, blocks_, sorted_, candidates);
      fit_cell_normals(candidates, order_, cell.begin, cell.end, radius2, options_, points_);
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, table_.size(), 64), normals);
}

const MapPoint* PointMap::nearest(const Eigen::Vector2d& query, double max_distance_m) const {
  // Only the cells the disc of radius max_distance_m touches (1 to 4 of the 3 x 3 around the
  // query when the radius is below half a cell, as in ICP's final iterations).
  const double r = std::min(max_distance_m, options_.cell_size_m);
  const double c = options_.cell_size_m;
  const std::int64_t i_low = floor_to_int((query.x() - r) / c);
  const std::int64_t i_high = floor_to_int((query.x() + r) / c);
  const std::int64_t j_low = floor_to_int((query.y() - r) / c);
  const std::int64_t j_high = floor_to_int((query.y() + r) / c);
  double best_d2 = max_distance_m * max_distance_m;
#if defined(__SSE2__)
  // Each distance's x and y lanes in one SSE2 register (the same subtractions and products; the
  // sum x^2 + y^2 is the same double in either order), and the best kept as an index into sorted_,
  // updated without a branch (d2 < best_d2 as before: the first of equal distances wins), the
  // point looked up once at the end. Measured with perf on MIT CSAIL (2026-11-25): these queries
  // were a fifth of the front end's thread, the compare-and-branch per point and the pointer
  // computed at every improvement a large part of it; after this, local_match 0.56-0.59 s ->
  // 0.40 s (A/B, 3 runs each, outputs byte-identical on MIT CSAIL, ACES, Intel and fr079).
  const __m128d q = _mm_loadu_pd(query.data());
  const __m128d zero = _mm_setzero_pd();
  std::uint32_t best_o = UINT32_MAX;
  for (std::int64_t i = i_low; i <= i_high; ++i) {
    for (std::int64_t j = j_low; j <= j_high; ++j) {
      const Cell* cell = find(i, j);
      if (cell == nullptr) continue;
      const Block* block = blocks_.data() + cell->block;
      for (std::uint32_t first = cell->begin; first < cell->end; first += kBlock, ++block) {
        // The box's distance per axis, max(0, low - q, q - high) (0 inside): a lower bound of
        // every point's in the block, as in the scalar code below.
        __m128d gap = _mm_max_pd(_mm_max_pd(_mm_sub_pd(_mm_loadu_pd(&block->low_x), q), _mm_sub_pd(q, _mm_loadu_pd(&block->high_x))), zero);
        gap = _mm_mul_pd(gap, gap);
        if (_mm_cvtsd_f64(_mm_add_sd(gap, _mm_unpackhi_pd(gap, gap))) >= best_d2) continue;
        const std::uint32_t last = std::min(cell->end, first + kBlock);
        for (std::uint32_t o = first; o < last; ++o) {
          __m128d e = _mm_sub_pd(_mm_loadu_pd(sorted_[o].data()), q);
          e = _mm_mul_pd(e, e);
          const double d2 = _mm_cvtsd_f64(_mm_add_sd(e, _mm_unpackhi_pd(e, e)));
          const bool better = d2 < best_d2;
          best_d2 = better ? d2 : best_d2;
          best_o = better ? o : best_o;
        }
      }
    }
  }
  return best_o == UINT32_MAX ? nullptr : &points_[order_[best_o]];
#else
  const MapPoint* best = nullptr;
  for (std::int64_t i = i_low; i <= i_high; ++i) {
    for (std::int64_t j = j_low; j <= j_high; ++j) {
      const Cell* cell = find(i, j);
      if (cell == nullptr) continue;
      // Blocks whose box is not nearer than the best so far are skipped: every point in one has
      // d2 >= the box's d2 (rounding is monotone), and only d2 < best_d2 replaces the best.
      const Block* block = blocks_.data() + cell->block;
      for (std::uint32_t first = cell->begin; first < cell->end; first += kBlock, ++block) {
        const double dx = std::max(0.0, std::max(block->low_x - query.x(), query.x() - block->high_x));
        const double dy = std::max(0.0, std::max(block->low_y - query.y(), query.y() - block->high_y));
        if (dx * dx + dy * dy >= best_d2) continue;
        const std::uint32_t last = std::min(cell->end, first + kBlock);
        for (std::uint32_t o = first; o < last; ++o) {
          const double d2 = (sorted_[o] - query).squaredNorm();
          if (d2 < best_d2) {
            best_d2 = d2;
            best = &points_[order_[o]];
          }
        }
      }
    }
  }
  return best;
#endif
}

}  // namespace cairn::slam2d
