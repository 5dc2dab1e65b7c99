#pragma once
/// \file
/// A 2D point map with a normal per point, for point-to-line ICP (Censi, "An ICP variant using a
/// point-to-line metric", ICRA 2008). Points are hashed into square cells of the search radius,
/// so a nearest-neighbour query visits 3 x 3 cells (as KISS-ICP's voxel hash map does, Vizzo et
/// al., RA-L 2023). The normal of each point is the direction of least spread of its neighbours
/// within `normal_radius_m` (principal component analysis); points whose neighbourhood is not
/// line-like keep no normal and are matched point-to-point.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

namespace cairn::slam2d {

struct PointMapOptions {
  double cell_size_m = 0.4;        ///< hash cell; also the largest distance a query can return; > 0
  /// Neighbourhood for the normal; > 0. 0.4 m measured best on the ACES relations among
  /// 0.15 / 0.25 / 0.4 / 0.6 (docs/benchmarks.md).
  double normal_radius_m = 0.4;
  int normal_min_neighbours = 3;   ///< fewer neighbours: no normal
  /// Line-likeness: smallest / largest eigenvalue of the neighbourhood's covariance below this.
  double normal_max_eigenvalue_ratio = 0.1;
};

struct MapPoint {
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
  bool has_normal = false;
};

class PointMap {
 public:
  explicit PointMap(const PointMapOptions& options = {});

  /// Replaces the map's contents and computes the normals.
  void build(const std::vector<Eigen::Vector2d>& points);
  /// The nearest point within `max_distance_m` (<= cell size), if any.
  const MapPoint* nearest(const Eigen::Vector2d& query, double max_distance_m) const;

  const std::vector<MapPoint>& points() const { return points_; }
  bool empty() const { return points_.empty(); }

 private:
  /// The points of one cell: order_[begin, end) (point indices in insertion order).
  struct Cell {
    std::uint64_t key = 0;
    std::uint32_t begin = 0;
    std::uint32_t end = 0;  ///< 0 marks an empty slot (a used cell has end > begin)
    std::uint32_t block = 0;  ///< its first block in blocks_
  };
  /// Bounding box of kBlock consecutive points of a cell (order_[begin + kBlock b, ...)): a
  /// query skips a block whose box lies farther than what it has already found, exactly (no
  /// point of the block could be nearer), visiting the rest in the same order as before.
  struct Block {
    double low_x = 0.0, low_y = 0.0, high_x = 0.0, high_y = 0.0;
  };
  static constexpr std::uint32_t kBlock = 8;
  std::uint64_t key(const Eigen::Vector2d& p) const;
  static std::uint64_t key(std::int64_t i, std::int64_t j);
  const Cell* find(std::uint64_t key) const;
  /// The cell (i, j): from the dense index when there is one, else from the hash table.
  const Cell* find(std::int64_t i, std::int64_t j) const;

  PointMapOptions options_;
  std::vector<MapPoint> points_;
  std::vector<std::uint32_t> order_;  ///< point indices grouped by cell
  std::vector<Cell> table_;           ///< open addressing, linear probing, power-of-two size
  /// The positions in order_'s order (a query reads a cell's points contiguously).
  std::vector<Eigen::Vector2d> sorted_;
  std::vector<Block> blocks_;
  /// Dense index of the cells' bounding box when it is small (local maps and submaps: a few
  /// thousand cells), cell (i, j) at (j - dense_j0_) * dense_width_ + (i - dense_i0_); empty
  /// otherwise. A lookup is an array access instead of a hash probe.
  std::vector<Cell> dense_;
  std::int64_t dense_i0_ = 0, dense_j0_ = 0, dense_width_ = 0, dense_height_ = 0;
};

}  // namespace cairn::slam2d
