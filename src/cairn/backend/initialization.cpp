#include "cairn/backend/initialization.hpp"

#include <chrono>
#include <deque>
#include <stdexcept>

#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::backend {

std::string_view to_string(Initialization initialization) {
  switch (initialization) {
    case Initialization::kFile: return "file";
    case Initialization::kOdometry: return "odometry";
    case Initialization::kChordal: return "chordal";
  }
  return "?";
}

namespace {

using core::Clock;
using core::seconds_since;

// The unknowns of both linear systems: pose -> block, -1 for fixed poses, blocks numbered in a
// fill-reducing elimination order (block_amd_labels) shared by the rotation and the
// translation system, whose block graphs are the same.
struct Unknowns {
  std::vector<int> variable;
  int count = 0;
  std::vector<std::pair<int, int>> pairs;  // coupled blocks, one per edge between free poses
};

Unknowns number_unknowns(const std::vector<char>& fixed, const std::vector<std::pair<int, int>>& edges,
                         BlockOrderCache& order) {
  Unknowns u;
  u.variable.assign(fixed.size(), -1);
  for (std::size_t p = 0; p < fixed.size(); ++p) {
    if (!fixed[p]) u.variable[p] = u.count++;
  }
  for (const auto& [i, j] : edges) {
    const int a = u.variable[static_cast<std::size_t>(i)];
    const int b = u.variable[static_cast<std::size_t>(j)];
    if (a >= 0 && b >= 0) u.pairs.emplace_back(a, b);
  }
  const std::vector<int>& label = block_amd_labels(u.count, u.pairs, order);
  apply_block_labels(label, u.variable, u.pairs);
  return u;
}

// Solves the block-Laplacian-like system sum over edges of w ||x_j - A_ij x_i - c_ij||^2 with
// x fixed at fixed poses, x in R^{d x m} per pose (m right-hand sides solved together).
// For rotations: A_ij = R~^T, c = 0 (`c` empty), m = d (row k of R is column k of x). For
// translations: A_ij = I (`A` empty), c_ij = R_i t~, m = d, d = 1 (a scalar Laplacian).
// Returns x of every pose, stacked (pose p in rows p d .. p d + d - 1).
template <int d, int m>
Eigen::MatrixXd solve_linear(const Unknowns& unknowns, const std::vector<Eigen::Matrix<double, d, m>>& known,
                             const std::vector<std::pair<int, int>>& edges,
                             const std::vector<Eigen::Matrix<double, d, d>>& A,
                             const std::vector<Eigen::Matrix<double, d, m>>& c, const std::vector<double>& w) {
  using MatrixD = Eigen::Matrix<double, d, d>;
  using RowMajorD = Eigen::Matrix<double, d, d, Eigen::RowMajor>;
  using Block = Eigen::Matrix<double, d, m>;
  const std::vector<int>& variable = unknowns.variable;
  const int n = unknowns.count;
  const int poses = static_cast<int>(variable.size());
  BlockPattern pattern(n, d, unknowns.pairs);
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n * d, m);
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const auto [i, j] = edges[e];
    const int vi = variable[static_cast<std::size_t>(i)];
    const int vj = variable[static_cast<std::size_t>(j)];
    // residual r = x_j - A x_i - c ; J_i = -A, J_j = I.
    const MatrixD Ae = A.empty() ? MatrixD::Identity() : A[e];
    if (vi >= 0) {
      const RowMajorD Hii = w[e] * Ae.transpose() * Ae;
      pattern.add_diagonal(vi, Hii.data());
    }
    if (vj >= 0) {
      const RowMajorD Hjj = w[e] * MatrixD::Identity();
      pattern.add_diagonal(vj, Hjj.data());
    }
    if (vi >= 0 && vj >= 0) {
      // H_ij = J_i^T J_j = -w A^T.
      if (vi < vj) {
        const RowMajorD Hij = -w[e] * Ae.transpose();
        pattern.add_off_diagonal(vi, vj, Hij.data());
      } else {
        const RowMajorD Hji = -w[e] * Ae;
        pattern.add_off_diagonal(vj, vi, Hji.data());
      }
    }
    // Right-hand side -J^T r0 with r0 the residual at x_free = 0 (known poses inserted).
    Block r0 = c.empty() ? Block::Zero() : Block(-c[e]);
    if (vj < 0) r0 += known[static_cast<std::size_t>(j)];
    if (vi < 0) r0 -= Ae * known[static_cast<std::size_t>(i)];
    if (vi >= 0) rhs.template block<d, m>(vi * d, 0) += w[e] * Ae.transpose() * r0;
    if (vj >= 0) rhs.template block<d, m>(vj * d, 0) -= w[e] * r0;
  }
  SparseCholesky cholesky;
  // Block AMD, as the optimiser (CHOLMOD's own choice may also try METIS on these graphs, which
  // costs more than the factorisation it saves), applied when the unknowns were numbered.
  cholesky.analyze_in_stored_order(pattern.matrix());
  const FactorizationStatus status = cholesky.factorize(pattern.matrix());
  // make_problem guarantees connectivity, so the system is singular only in floating point: an
  // information matrix 1e40 times another's cancels a pivot (a file's numbers, not a bug here).
  if (status != FactorizationStatus::kSuccess) {
    throw std::runtime_error(
        "the chordal initialisation's linear system is not positive definite in double precision (information "
        "matrices whose scales differ by ~1e30 or more): use --init odometry or rescale the information");
  }
  const Eigen::MatrixXd x = cholesky.solve(rhs);
  Eigen::MatrixXd result(poses * d, m);
  for (int p = 0; p < poses; ++p) {
    const int v = variable[static_cast<std::size_t>(p)];
    result.template block<d, m>(p * d, 0) = v >= 0 ? Block(x.template block<d, m>(v * d, 0)) : known[static_cast<std::size_t>(p)];
  }
  return result;
}

// The rotation nearest to M in the Frobenius norm (its orthonormal polar factor): for d = 2 in
// closed form, the normalised [[a, -b], [b, a]] with a = M00 + M11, b = M10 - M01
// (SO2::from_matrix's angle); for d = 3 SO3::from_matrix.
template <int d>
Eigen::Matrix<double, d, d> project_to_rotation(const Eigen::Matrix<double, d, d>& M) {
  using MatrixD = Eigen::Matrix<double, d, d>;
  if constexpr (d == 2) {
    const double a = M(0, 0) + M(1, 1);
    const double b = M(1, 0) - M(0, 1);
    const double norm = std::hypot(a, b);
    if (norm == 0.0) return MatrixD::Identity();  // every rotation is equally near
    MatrixD R;
    R << a / norm, -b / norm, b / norm, a / norm;
    return R;
  } else {
    return core::SO3::from_matrix(M).matrix();
  }
}

}  // namespace

template <class Group>
InitializationSummary initialize_odometry(PoseGraphProblem<Group>& problem) {
  const auto start = Clock::now();
  InitializationSummary summary;
  const std::size_t n = static_cast<std::size_t>(problem.size());
  std::vector<std::vector<std::size_t>> incident(n);
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    incident[static_cast<std::size_t>(problem.edges[e].i)].push_back(e);
    incident[static_cast<std::size_t>(problem.edges[e].j)].push_back(e);
  }
  std::vector<char> reached(n, 0);
  std::deque<int> queue;
  for (std::size_t p = 0; p < n; ++p) {
    if (problem.fixed[p]) {
      reached[p] = 1;
      queue.push_back(static_cast<int>(p));
    }
  }
  // Two passes: first along odometry edges only, so a wrong loop closure cannot enter the tree
  // while the odometry chain reaches a pose; then along any edge for poses still unreached.
  for (const bool odometry_only : {true, false}) {
    if (!odometry_only) {
      for (std::size_t p = 0; p < n; ++p) {
        if (reached[p]) queue.push_back(static_cast<int>(p));
      }
    }
    while (!queue.empty()) {
      const int p = queue.front();
      queue.pop_front();
      for (const std::size_t e : incident[static_cast<std::size_t>(p)]) {
        const auto& edge = problem.edges[e];
        if (odometry_only && edge.kind != EdgeKind::kOdometry) continue;
        const int q = edge.i == p ? edge.j : edge.i;
        if (reached[static_cast<std::size_t>(q)]) continue;
        reached[static_cast<std::size_t>(q)] = 1;
        const Group& T_world_p = problem.T_world_pose[static_cast<std::size_t>(p)];
        problem.T_world_pose[static_cast<std::size_t>(q)] =
            edge.i == p ? T_world_p * edge.T_i_j : T_world_p * edge.T_i_j.inverse();
        queue.push_back(q);
      }
    }
  }
  for (std::size_t p = 0; p < n; ++p) summary.poses_reached += reached[p];
  summary.total_s = seconds_since(start);
  return summary;
}

template <class Group>
InitializationSummary initialize_chordal(PoseGraphProblem<Group>& problem) {
  constexpr int d = kRotationDim<Group>;
  using MatrixD = Eigen::Matrix<double, d, d>;
  using VectorD = Eigen::Matrix<double, d, 1>;
  const auto start = Clock::now();
  InitializationSummary summary;
  const int n = problem.size();
  std::vector<std::pair<int, int>> edges;
  std::vector<MatrixD> A;
  std::vector<double> kappa;
  std::vector<double> tau;
  edges.reserve(problem.edges.size());
  A.reserve(problem.edges.size());
  for (const auto& edge : problem.edges) {
    edges.emplace_back(edge.i, edge.j);
    // Row k of R_j equals row k of R_i times R~: as columns, x_j = R~^T x_i with x = R^T.
    A.push_back(rotation_matrix_of(edge.T_i_j).transpose());
    kappa.push_back(edge.kappa);
    tau.push_back(edge.tau);
  }
  // (1) Rotations: unknown X_i = R_i^T (d x d), all d columns at once.
  std::vector<MatrixD> known_R(static_cast<std::size_t>(n), MatrixD::Zero());
  for (int p = 0; p < n; ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) {
      known_R[static_cast<std::size_t>(p)] = rotation_matrix_of(problem.T_world_pose[static_cast<std::size_t>(p)]).transpose();
    }
  }
  const Unknowns unknowns = number_unknowns(problem.fixed, edges, problem.elimination_order);
  const Eigen::MatrixXd X = solve_linear<d, d>(unknowns, known_R, edges, A, {}, kappa);
  std::vector<MatrixD> R(static_cast<std::size_t>(n));
  for (int p = 0; p < n; ++p) {
    R[static_cast<std::size_t>(p)] = project_to_rotation<d>(X.template block<d, d>(p * d, 0).transpose());
  }
  // (2) Translations with the rotations fixed: sum tau ||t_j - t_i - R_i t~||^2 is the weighted
  // graph Laplacian times I_d, so the d coordinates are d right-hand sides of one scalar
  // Laplacian system (unknown x_i = t_i^T, 1 x d), d^3 times fewer factorisation flops than
  // the d x d block system.
  using RowD = Eigen::Matrix<double, 1, d>;
  std::vector<RowD> offsets;
  offsets.reserve(problem.edges.size());
  for (const auto& edge : problem.edges) {
    offsets.push_back((R[static_cast<std::size_t>(edge.i)] * VectorD(edge.T_i_j.translation())).transpose());
  }
  std::vector<RowD> known_t(static_cast<std::size_t>(n), RowD::Zero());
  for (int p = 0; p < n; ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) known_t[static_cast<std::size_t>(p)] = problem.T_world_pose[static_cast<std::size_t>(p)].translation().transpose();
  }
  const Eigen::MatrixXd t = solve_linear<1, d>(unknowns, known_t, edges, {}, offsets, tau);
  for (int p = 0; p < n; ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) continue;
    problem.T_world_pose[static_cast<std::size_t>(p)] = pose_from<Group>(R[static_cast<std::size_t>(p)], VectorD(t.row(p).transpose()));
  }
  summary.poses_reached = n;
  summary.total_s = seconds_since(start);
  return summary;
}

template InitializationSummary initialize_odometry(Problem2D&);
template InitializationSummary initialize_odometry(Problem3D&);
template InitializationSummary initialize_chordal(Problem2D&);
template InitializationSummary initialize_chordal(Problem3D&);

}  // namespace cairn::backend
