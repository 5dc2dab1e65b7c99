#include "cairn/lidar3d/loam_features.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <tbb/parallel_for.h>

#include "cairn/core/problems.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {

bool LoamFeatureOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (neighbours < 1 || neighbours > 1000) problems.add("loam.neighbours must be in [1, 1000]");
  if (sectors_per_ring < 1 || sectors_per_ring > 1000) problems.add("loam.sectors_per_ring must be in [1, 1000]");
  if (sharp_per_sector < 0 || less_sharp_per_sector < 0 || flat_per_sector < 0) {
    problems.add("loam.sharp_per_sector, less_sharp_per_sector and flat_per_sector must be >= 0");
  }
  if (!std::isfinite(edge_curvature) || !std::isfinite(plane_curvature)) {
    problems.add("loam.edge_curvature and plane_curvature must be finite");
  }
  if (!(depth_jump_ratio >= 0.0) || !std::isfinite(depth_jump_ratio)) problems.add("loam.depth_jump_ratio must be >= 0");
  if (!(less_flat_voxel_m > 0.0) || !std::isfinite(less_flat_voxel_m)) problems.add("loam.less_flat_voxel_m must be > 0");
  return problems.report(why);
}

namespace {

/// One ring's points ordered by azimuth, with their ranges.
struct RingScan {
  std::vector<Eigen::Vector3d> p;
  std::vector<double> range;
};

RingScan sort_by_azimuth(const std::vector<Eigen::Vector3d>& points, const std::vector<std::size_t>& indices) {
  std::vector<double> azimuth(indices.size());
  for (std::size_t j = 0; j < indices.size(); ++j) azimuth[j] = std::atan2(points[indices[j]].y(), points[indices[j]].x());
  std::vector<std::size_t> order(indices.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return azimuth[a] < azimuth[b]; });
  RingScan ring{std::vector<Eigen::Vector3d>(indices.size()), std::vector<double>(indices.size())};
  for (std::size_t j = 0; j < order.size(); ++j) {
    ring.p[j] = points[indices[order[j]]];
    ring.range[j] = ring.p[j].norm();
  }
  return ring;
}

/// Smoothness c of every point with k neighbours on each side (Zhang and Singh 2014, eq. 1);
/// those points are marked usable.
std::vector<double> smoothness(const RingScan& ring, int k, std::vector<char>& usable) {
  const int n = static_cast<int>(ring.p.size());
  std::vector<double> c(ring.p.size(), 0.0);
  for (int i = k; i < n - k; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j = -k; j <= k; ++j) sum += ring.p[static_cast<std::size_t>(i + j)] - ring.p[static_cast<std::size_t>(i)];
    c[static_cast<std::size_t>(i)] = sum.norm() / (2.0 * k * ring.range[static_cast<std::size_t>(i)]);
    usable[static_cast<std::size_t>(i)] = 1;
  }
  return c;
}

/// Unreliable points (Zhang and Singh 2014, Fig. 4) are not usable.
void drop_unreliable(const RingScan& ring, int k, double depth_jump_ratio, std::vector<char>& usable) {
  const int n = static_cast<int>(ring.p.size());
  const std::vector<Eigen::Vector3d>& p = ring.p;
  const std::vector<double>& range = ring.range;
  for (int i = k; i < n - k - 1; ++i) {
    const auto a = static_cast<std::size_t>(i), b = a + 1;
    // Depth jump: the farther side may be occluded (Fig. 4b); drop its k points.
    if (std::abs(range[a] - range[b]) > depth_jump_ratio * std::min(range[a], range[b])) {
      const bool a_farther = range[a] > range[b];
      for (int j = 0; j < k; ++j) {
        const int index = a_farther ? i - j : i + 1 + j;
        if (index >= 0 && index < n) usable[static_cast<std::size_t>(index)] = 0;
      }
    }
    // A surface nearly parallel to the beam (Fig. 4a): both neighbours far from the point.
    if (i > 0) {
      const double before = (p[a] - p[a - 1]).norm(), after = (p[b] - p[a]).norm();
      if (before > 0.02 * range[a] && after > 0.02 * range[a]) usable[a] = 0;
    }
  }
}

/// One ring's features: in each of sectors_per_ring sectors, the sharpest usable points as edges
/// and the flattest as planes, each pick blocking its k neighbours; every other usable flat point
/// is less flat.
LoamFeatures ring_features(const RingScan& ring, const std::vector<double>& c, const std::vector<char>& usable,
                           const LoamFeatureOptions& options) {
  LoamFeatures out;
  const int k = options.neighbours;
  const int n = static_cast<int>(ring.p.size());
  const std::vector<Eigen::Vector3d>& p = ring.p;
  std::vector<char> picked(p.size(), 0);
  std::vector<char> is_edge(p.size(), 0);
  auto block = [&](int i) {
    for (int j = -k; j <= k; ++j) {
      const int index = i + j;
      if (index >= 0 && index < n) picked[static_cast<std::size_t>(index)] = 1;
    }
  };
  const int sectors = options.sectors_per_ring;
  for (int s = 0; s < sectors; ++s) {
    const int begin = k + (n - 2 * k) * s / sectors;
    const int end = k + (n - 2 * k) * (s + 1) / sectors;
    if (end <= begin) continue;
    std::vector<int> by_c(static_cast<std::size_t>(end - begin));
    std::iota(by_c.begin(), by_c.end(), begin);
    std::sort(by_c.begin(), by_c.end(), [&](int a, int b) { return c[static_cast<std::size_t>(a)] > c[static_cast<std::size_t>(b)]; });
    int edges = 0;
    for (int i : by_c) {
      const auto u = static_cast<std::size_t>(i);
      if (!usable[u] || picked[u] || c[u] <= options.edge_curvature) continue;
      if (edges < options.sharp_per_sector) out.sharp.push_back(p[u]);
      if (edges >= options.less_sharp_per_sector) break;
      out.less_sharp.push_back(p[u]);
      is_edge[u] = 1;
      ++edges;
      block(i);
    }
    int flats = 0;
    for (auto it = by_c.rbegin(); it != by_c.rend() && flats < options.flat_per_sector; ++it) {
      const auto u = static_cast<std::size_t>(*it);
      if (!usable[u] || picked[u] || c[u] >= options.plane_curvature) continue;
      out.flat.push_back(p[u]);
      ++flats;
      block(*it);
    }
    for (int i = begin; i < end; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (usable[u] && !is_edge[u] && c[u] < options.plane_curvature) out.less_flat.push_back(p[u]);
    }
  }
  return out;
}

}  // namespace

LoamFeatures extract_loam_features(const std::vector<Eigen::Vector3d>& points, const std::vector<std::uint16_t>& ring,
                                   const LoamFeatureOptions& options) {
  LoamFeatures features;
  if (points.empty() || ring.size() != points.size()) return features;
  const int max_ring = *std::max_element(ring.begin(), ring.end());
  std::vector<std::vector<std::size_t>> rings(static_cast<std::size_t>(max_ring) + 1);
  for (std::size_t i = 0; i < points.size(); ++i) rings[ring[i]].push_back(i);
  const int k = options.neighbours;
  // Rings are independent: one task each, results joined in ring order (the same for any number
  // of threads).
  std::vector<LoamFeatures> per_ring(rings.size());
  tbb::parallel_for(std::size_t{0}, rings.size(), [&](std::size_t r) {
    if (static_cast<int>(rings[r].size()) < 2 * k + 1) return;
    const RingScan scan = sort_by_azimuth(points, rings[r]);
    std::vector<char> usable(scan.p.size(), 0);
    const std::vector<double> c = smoothness(scan, k, usable);
    drop_unreliable(scan, k, options.depth_jump_ratio, usable);
    per_ring[r] = ring_features(scan, c, usable, options);
  });
  std::vector<Eigen::Vector3d> less_flat;
  for (const LoamFeatures& f : per_ring) {
    features.sharp.insert(features.sharp.end(), f.sharp.begin(), f.sharp.end());
    features.less_sharp.insert(features.less_sharp.end(), f.less_sharp.begin(), f.less_sharp.end());
    features.flat.insert(features.flat.end(), f.flat.begin(), f.flat.end());
    less_flat.insert(less_flat.end(), f.less_flat.begin(), f.less_flat.end());
  }
  features.less_flat = voxel_downsample(less_flat, options.less_flat_voxel_m);
  return features;
}

}  // namespace cairn::lidar3d
