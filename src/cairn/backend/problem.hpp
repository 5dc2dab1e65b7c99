#pragma once
/// \file
/// The optimisation problem built from a pose graph file: poses by index, edges with their
/// whitening (square-root information) and SE-Sync's isotropic weights, the gauge (fixed poses).

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/io/pose_graph.hpp"

namespace cairn::backend {

enum class EdgeKind {
  kOdometry,     ///< between consecutive ids
  kLoopClosure,  ///< any other edge
};

template <class Group>
struct PoseEdge {
  static constexpr int kDoF = Group::kDoF;
  using Matrix = Eigen::Matrix<double, kDoF, kDoF>;
  int i = 0;  ///< index of pose `from`
  int j = 0;  ///< index of pose `to`
  Group T_i_j;
  Matrix information = Matrix::Identity();
  /// S with S^T S = information, so ||S r||^2 = r^T information r (eigen-decomposition square
  /// root; works for the singular positive semi-definite matrices the reader may produce).
  Matrix sqrt_information = Matrix::Identity();
  /// SE-Sync's isotropic weights (Rosen et al. 2019, see ../shared/data/README.md): rotation
  /// kappa and translation tau, from the diagonal blocks of the information matrix only.
  double kappa = 1.0;
  double tau = 1.0;
  EdgeKind kind = EdgeKind::kOdometry;
  std::size_t line = 0;  ///< line in the file (0 if none)
};

/// d of SE(d): 2 for SE(2), 3 for SE(3).
template <class Group>
inline constexpr int kRotationDim = Group::kDoF == 3 ? 2 : 3;

/// The rotation of a pose as a d x d matrix.
template <class Group>
Eigen::Matrix<double, kRotationDim<Group>, kRotationDim<Group>> rotation_matrix_of(const Group& T) {
  if constexpr (Group::kDoF == 3) {
    return T.so2().matrix();
  } else {
    return T.rotation_matrix();
  }
}

/// The pose with the rotation nearest to R (SO2/SO3::from_matrix project it) and translation t.
template <class Group>
Group pose_from(const Eigen::Matrix<double, kRotationDim<Group>, kRotationDim<Group>>& R,
                const Eigen::Matrix<double, kRotationDim<Group>, 1>& t) {
  if constexpr (Group::kDoF == 3) {
    return Group(core::SO2::from_matrix(R), t);
  } else {
    return Group(core::SO3::from_matrix(R), t);
  }
}

template <class Group>
struct PoseGraphProblem {
  static constexpr int kDoF = Group::kDoF;
  std::vector<std::int64_t> ids;   ///< index -> id in the file
  std::vector<Group> T_world_pose; ///< current estimate, by index
  std::vector<char> fixed;         ///< 1 = held constant (gauge)
  std::vector<PoseEdge<Group>> edges;
  bool has_initial_guess = false;  ///< T_world_pose came from the file's VERTEX lines
  /// Fill-reducing order of the free poses for these edges, shared by initialize_chordal and
  /// optimize (ordering twice took 0.37 ms more of intel's 6 ms); each refreshes it when the
  /// fixed poses or the coupled pairs are not the ones it was computed for.
  BlockOrderCache elimination_order;

  int size() const { return static_cast<int>(ids.size()); }
  int index_of(std::int64_t id) const;
};

using Problem2D = PoseGraphProblem<core::SE2>;
using Problem3D = PoseGraphProblem<core::SE3>;

/// Connected components of the poses joined by `problem.edges`, and those without a fixed pose
/// (example: a pose index in the first of them). A problem has a unique solution only when
/// `unanchored` is 0.
struct Anchoring {
  std::size_t components = 0;
  std::size_t unanchored = 0;
  int example = -1;
};
template <class Group>
Anchoring check_anchoring(const PoseGraphProblem<Group>& problem);

/// Builds the problem. Poses are the file's vertices (in file order) or, without vertices, the
/// ids the edges name (sorted; identity as placeholder guess). FIX poses are held; without any,
/// the first pose is held (gauge). Throws io::ParseError naming `path` when a connected component
/// has no fixed pose (the problem would have no unique solution) or when SE-Sync weights cannot
/// be formed (a singular diagonal block).
template <class Group>
PoseGraphProblem<Group> make_problem(const io::PoseGraphT<Group>& graph, const std::string& path);

/// The optimised poses written back into a graph (vertices for every pose, in index order;
/// edges and fixed ids unchanged).
template <class Group>
io::PoseGraphT<Group> to_graph(const PoseGraphProblem<Group>& problem, const io::PoseGraphT<Group>& original);

}  // namespace cairn::backend
