#pragma once
/// \file
/// A pose graph as stored in a file: poses (vertices) with an optional initial guess, relative-pose
/// measurements (edges) with information matrices, and fixed poses. This is the exchange model
/// between the file formats and the back end; it keeps every value exactly as read (after the
/// documented normalisation of quaternions and angles), so a graph written and read back is
/// identical.

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <variant>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"

namespace cairn::io {

/// One pose and its initial guess T_world_pose.
template <class Group>
struct GraphVertex {
  std::int64_t id = 0;
  Group T_world_pose;
};

/// A relative-pose measurement from pose `from` to pose `to`: T_from_to, with the information
/// matrix (inverse covariance) over the tangent in the order the file defines (translation first
/// for every format cairn reads; see docs/conventions.md for what the rotation block means).
template <class Group>
struct GraphEdge {
  using Information = Eigen::Matrix<double, Group::kDoF, Group::kDoF>;
  std::int64_t from = 0;
  std::int64_t to = 0;
  Group T_from_to;
  Information information = Information::Identity();
  /// Line of the file this edge came from (0 when built in memory).
  std::size_t line = 0;
};

template <class Group>
struct PoseGraphT {
  static constexpr int kDimension = Group::kDoF == 3 ? 2 : 3;
  /// In file order. Empty when the file carries no initial guess (SE-Sync's CSAIL.g2o, ...).
  std::vector<GraphVertex<Group>> vertices;
  /// In file order.
  std::vector<GraphEdge<Group>> edges;
  /// Ids of fixed poses (g2o FIX), in file order.
  std::vector<std::int64_t> fixed;
};

using PoseGraph2D = PoseGraphT<core::SE2>;
using PoseGraph3D = PoseGraphT<core::SE3>;
/// A graph is 2D or 3D, never both.
using PoseGraph = std::variant<PoseGraph2D, PoseGraph3D>;

inline int dimension(const PoseGraph& graph) { return graph.index() == 0 ? 2 : 3; }

}  // namespace cairn::io
