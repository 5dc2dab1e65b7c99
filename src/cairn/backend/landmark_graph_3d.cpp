#include "cairn/backend/landmark_graph_3d.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <type_traits>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/SparseCore>

#include "cairn/backend/factors.hpp"
#include "cairn/backend/landmark_factors_3d.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"

namespace cairn::backend {
namespace {

using Clock = std::chrono::steady_clock;
using Matrix63 = Eigen::Matrix<double, 6, 3>;
using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// Free pose i (>= 1) is block i - 1; pose 0 is fixed.
int pose_block(std::size_t i) { return static_cast<int>(i) - 1; }

Vector3 observation_residual(const core::SE3& T_world_body, const Vector3& p_world, const LandmarkFactor3D& f,
                             Matrix36* J_e_pose, Matrix3* J_e_landmark) {
  return f.model == LandmarkModel3D::kPoint
             ? point_residual_3d(T_world_body, p_world, f.z, J_e_pose, J_e_landmark)
             : range_bearing_elevation_residual_3d(T_world_body, p_world, f.z, J_e_pose, J_e_landmark);
}

Vector6 odometry_residual(const core::SE3& T_world_i, const core::SE3& T_world_j, const PoseFactor3D& f,
                          Matrix6* J_e_i, Matrix6* J_e_j) {
  const Vector6 e = between_error(T_world_i, T_world_j, f.T_from_to);
  if (J_e_i != nullptr || J_e_j != nullptr) {
    const Matrix6 Jr_inv = core::SE3::right_jacobian_inverse(e);
    if (J_e_j != nullptr) *J_e_j = Jr_inv;
    if (J_e_i != nullptr) *J_e_i = -Jr_inv * (T_world_j.inverse() * T_world_i).Adj();
  }
  return e;
}

// The normal equations H dx = -b split as [A W; W^T V] (see the header), kept in blocks.
struct Normal {
  std::vector<Matrix6> A_diagonal;    // per free pose
  std::vector<Matrix6> A_odometry;    // per odometry factor: block (from, to), zero if either is fixed
  std::vector<Vector6> b_pose;        // per free pose
  std::vector<Matrix3> V;             // per landmark
  std::vector<Vector3> b_landmark;    // per landmark
  std::vector<Matrix63> W;            // per (landmark, free pose) link
};

// Distinct (landmark, free pose) pairs: the non-zero blocks of W.
struct Links {
  std::vector<std::pair<std::size_t, int>> link;        // (landmark, pose block)
  std::vector<int> of_observation;                       // link index, -1 when the pose is fixed
  std::vector<std::vector<int>> of_landmark;             // link indices, sorted by pose block
};

Links make_links(const LandmarkGraph3D& graph) {
  Links links;
  links.of_observation.assign(graph.observations.size(), -1);
  links.of_landmark.resize(graph.landmarks.size());
  std::vector<std::vector<std::pair<int, std::size_t>>> by_landmark(graph.landmarks.size());  // (block, observation)
  for (std::size_t k = 0; k < graph.observations.size(); ++k) {
    const LandmarkFactor3D& f = graph.observations[k];
    if (f.pose != 0) by_landmark[f.landmark].emplace_back(pose_block(f.pose), k);
  }
  for (std::size_t l = 0; l < by_landmark.size(); ++l) {
    std::sort(by_landmark[l].begin(), by_landmark[l].end());
    int last_block = -1;
    for (const auto& [block, k] : by_landmark[l]) {
      if (block != last_block) {
        links.of_landmark[l].push_back(static_cast<int>(links.link.size()));
        links.link.emplace_back(l, block);
        last_block = block;
      }
      links.of_observation[k] = static_cast<int>(links.link.size()) - 1;
    }
  }
  return links;
}

double linearise(const LandmarkGraph3D& graph, const Links& links, Normal* n) {
  const std::size_t free_poses = graph.poses.size() - 1;
  n->A_diagonal.assign(free_poses, Matrix6::Zero());
  n->A_odometry.assign(graph.odometry.size(), Matrix6::Zero());
  n->b_pose.assign(free_poses, Vector6::Zero());
  n->V.assign(graph.landmarks.size(), Matrix3::Zero());
  n->b_landmark.assign(graph.landmarks.size(), Vector3::Zero());
  n->W.assign(links.link.size(), Matrix63::Zero());
  double cost = 0.0;
  for (std::size_t k = 0; k < graph.odometry.size(); ++k) {
    const PoseFactor3D& f = graph.odometry[k];
    Matrix6 J_i;
    Matrix6 J_j;
    const Vector6 e = odometry_residual(graph.poses[f.from], graph.poses[f.to], f, &J_i, &J_j);
    cost += e.dot(f.information * e);
    const Matrix6 OJ_i = f.information * J_i;
    const Matrix6 OJ_j = f.information * J_j;
    if (f.from != 0) {
      n->A_diagonal[pose_block(f.from)] += J_i.transpose() * OJ_i;
      n->b_pose[pose_block(f.from)] += J_i.transpose() * (f.information * e);
    }
    if (f.to != 0) {
      n->A_diagonal[pose_block(f.to)] += J_j.transpose() * OJ_j;
      n->b_pose[pose_block(f.to)] += J_j.transpose() * (f.information * e);
    }
    if (f.from != 0 && f.to != 0) n->A_odometry[k] = J_i.transpose() * OJ_j;
  }
  for (std::size_t k = 0; k < graph.observations.size(); ++k) {
    const LandmarkFactor3D& f = graph.observations[k];
    Matrix36 J_p;
    Matrix3 J_l;
    const Vector3 e = observation_residual(graph.poses[f.pose], graph.landmarks[f.landmark], f, &J_p, &J_l);
    const Vector3 Oe = f.information * e;
    cost += e.dot(Oe);
    n->V[f.landmark] += J_l.transpose() * f.information * J_l;
    n->b_landmark[f.landmark] += J_l.transpose() * Oe;
    if (f.pose != 0) {
      n->A_diagonal[pose_block(f.pose)] += J_p.transpose() * f.information * J_p;
      n->b_pose[pose_block(f.pose)] += J_p.transpose() * Oe;
      n->W[links.of_observation[k]] += J_p.transpose() * f.information * J_l;
    }
  }
  return cost;
}

// (M + lambda diag(M)), Marquardt's scaling.
template <int D>
Eigen::Matrix<double, D, D> damped(const Eigen::Matrix<double, D, D>& M, double lambda) {
  Eigen::Matrix<double, D, D> out = M;
  out.diagonal() *= (1.0 + lambda);
  return out;
}

// The LM step by Schur elimination of the landmarks. Returns false when a damped block or the
// reduced system is not positive definite.
class SchurSolver {
 public:
  SchurSolver(const LandmarkGraph3D& graph, const Links& links) : graph_(graph), links_(links) {
    const int blocks = static_cast<int>(graph.poses.size()) - 1;
    std::vector<std::pair<int, int>> pairs;
    for (const PoseFactor3D& f : graph.odometry) {
      if (f.from != 0 && f.to != 0) pairs.emplace_back(pose_block(f.from), pose_block(f.to));
    }
    for (const std::vector<int>& of_landmark : links.of_landmark) {
      for (std::size_t a = 0; a < of_landmark.size(); ++a) {
        for (std::size_t b = a + 1; b < of_landmark.size(); ++b) {
          pairs.emplace_back(links.link[of_landmark[a]].second, links.link[of_landmark[b]].second);
        }
      }
    }
    if (blocks > 0) {
      pattern_ = std::make_unique<BlockPattern>(blocks, 6, pairs);
      const std::vector<int> ordering = pattern_->block_amd_ordering();
      cholesky_.analyze(pattern_->matrix(), &ordering);
    }
  }

  bool solve(const Normal& n, double lambda, Eigen::VectorXd* dx_poses, std::vector<Vector3>* dx_landmarks) {
    const std::size_t landmarks = graph_.landmarks.size();
    std::vector<Matrix3> V_inverse(landmarks);
    for (std::size_t l = 0; l < landmarks; ++l) {
      const Eigen::LLT<Matrix3> llt(damped<3>(n.V[l], lambda));
      if (llt.info() != Eigen::Success) return false;
      V_inverse[l] = llt.solve(Matrix3::Identity());
    }
    const int blocks = static_cast<int>(graph_.poses.size()) - 1;
    dx_poses->setZero(6 * blocks);
    if (blocks > 0) {
      pattern_->set_zero();
      Eigen::VectorXd rhs(6 * blocks);
      for (int p = 0; p < blocks; ++p) {
        const RowMajor6 A = damped<6>(n.A_diagonal[p], lambda);
        pattern_->add_diagonal(p, A.data());
        rhs.segment<6>(6 * p) = -n.b_pose[p];
      }
      for (std::size_t k = 0; k < graph_.odometry.size(); ++k) {
        const PoseFactor3D& f = graph_.odometry[k];
        if (f.from == 0 || f.to == 0) continue;
        const int i = pose_block(f.from);
        const int j = pose_block(f.to);
        const RowMajor6 M = i < j ? RowMajor6(n.A_odometry[k]) : RowMajor6(n.A_odometry[k].transpose());
        pattern_->add_off_diagonal(std::min(i, j), std::max(i, j), M.data());
      }
      // S -= W V^-1 W^T and rhs += W V^-1 b_l, landmark by landmark.
      std::vector<Matrix63> WV;
      for (std::size_t l = 0; l < landmarks; ++l) {
        const std::vector<int>& of_landmark = links_.of_landmark[l];
        WV.resize(of_landmark.size());
        for (std::size_t a = 0; a < of_landmark.size(); ++a) {
          WV[a] = n.W[of_landmark[a]] * V_inverse[l];
          rhs.segment<6>(6 * links_.link[of_landmark[a]].second) += WV[a] * n.b_landmark[l];
        }
        for (std::size_t a = 0; a < of_landmark.size(); ++a) {
          const int pa = links_.link[of_landmark[a]].second;
          const RowMajor6 diagonal = -WV[a] * n.W[of_landmark[a]].transpose();
          pattern_->add_diagonal(pa, diagonal.data());
          for (std::size_t b = a + 1; b < of_landmark.size(); ++b) {
            // Links of a landmark are sorted by pose block, so pa < pb.
            const RowMajor6 off = -WV[a] * n.W[of_landmark[b]].transpose();
            pattern_->add_off_diagonal(pa, links_.link[of_landmark[b]].second, off.data());
          }
        }
      }
      if (cholesky_.factorize(pattern_->matrix()) != FactorizationStatus::kSuccess) return false;
      *dx_poses = cholesky_.solve(rhs);
      factor_nonzeros_ = cholesky_.factor_nonzeros();
    }
    dx_landmarks->resize(landmarks);
    for (std::size_t l = 0; l < landmarks; ++l) {
      Vector3 r = -n.b_landmark[l];
      for (const int link : links_.of_landmark[l]) {
        r -= n.W[link].transpose() * dx_poses->segment<6>(6 * links_.link[link].second);
      }
      (*dx_landmarks)[l] = V_inverse[l] * r;
    }
    return true;
  }

  std::size_t factorised_variables() const { return 6 * (graph_.poses.size() - 1); }
  std::size_t factor_nonzeros() const { return factor_nonzeros_; }

 private:
  const LandmarkGraph3D& graph_;
  const Links& links_;
  std::unique_ptr<BlockPattern> pattern_;
  SparseCholesky cholesky_;
  std::size_t factor_nonzeros_ = 0;
};

// The LM step on the joint system: one fill-reducing ordering over poses and landmarks chosen
// by CHOLMOD, the same sparse Cholesky as the Schur path (so that the two differ only in the
// elimination order).
class JointSolver {
 public:
  JointSolver(const LandmarkGraph3D& graph, const Links& links) : graph_(graph), links_(links) {}

  bool solve(const Normal& n, double lambda, Eigen::VectorXd* dx_poses, std::vector<Vector3>* dx_landmarks) {
    const Eigen::Index pose_size = 6 * static_cast<Eigen::Index>(graph_.poses.size() - 1);
    const Eigen::Index size = pose_size + 3 * static_cast<Eigen::Index>(graph_.landmarks.size());
    std::vector<Eigen::Triplet<double>> triplets;
    const auto add = [&](Eigen::Index row, Eigen::Index column, const auto& block) {
      for (Eigen::Index r = 0; r < block.rows(); ++r) {
        for (Eigen::Index c = 0; c < block.cols(); ++c) {
          if (row + r >= column + c) triplets.emplace_back(static_cast<int>(row + r), static_cast<int>(column + c), block(r, c));
        }
      }
    };
    Eigen::VectorXd rhs(size);
    for (std::size_t p = 0; p + 1 < graph_.poses.size(); ++p) {
      const Eigen::Index c = 6 * static_cast<Eigen::Index>(p);
      add(c, c, damped<6>(n.A_diagonal[p], lambda));
      rhs.segment<6>(c) = -n.b_pose[p];
    }
    for (std::size_t k = 0; k < graph_.odometry.size(); ++k) {
      const PoseFactor3D& f = graph_.odometry[k];
      if (f.from == 0 || f.to == 0) continue;
      const Eigen::Index i = 6 * pose_block(f.from);
      const Eigen::Index j = 6 * pose_block(f.to);
      if (i > j) {
        add(i, j, n.A_odometry[k]);
      } else {
        add(j, i, Matrix6(n.A_odometry[k].transpose()));
      }
    }
    for (std::size_t l = 0; l < graph_.landmarks.size(); ++l) {
      const Eigen::Index c = pose_size + 3 * static_cast<Eigen::Index>(l);
      add(c, c, damped<3>(n.V[l], lambda));
      rhs.segment<3>(c) = -n.b_landmark[l];
      for (const int link : links_.of_landmark[l]) {
        add(c, 6 * static_cast<Eigen::Index>(links_.link[link].second), Eigen::Matrix<double, 3, 6>(n.W[link].transpose()));
      }
    }
    Eigen::SparseMatrix<double> H_lower(size, size);
    H_lower.setFromTriplets(triplets.begin(), triplets.end());
    // CHOLMOD takes the upper triangle in compressed columns: the transpose of the lower one.
    Eigen::SparseMatrix<double> H_upper = H_lower.transpose();
    H_upper.makeCompressed();
    UpperCsc A;
    A.size = static_cast<int>(size);
    A.column_start.assign(H_upper.outerIndexPtr(), H_upper.outerIndexPtr() + size + 1);
    A.row.assign(H_upper.innerIndexPtr(), H_upper.innerIndexPtr() + H_upper.nonZeros());
    A.value.assign(H_upper.valuePtr(), H_upper.valuePtr() + H_upper.nonZeros());
    if (!analysed_) {
      cholesky_.analyze(A);  // CHOLMOD's own fill-reducing ordering (AMD, METIS if AMD fills badly)
      analysed_ = true;
    }
    if (cholesky_.factorize(A) != FactorizationStatus::kSuccess) return false;
    const Eigen::VectorXd dx = cholesky_.solve(rhs);
    factor_nonzeros_ = cholesky_.factor_nonzeros();
    *dx_poses = dx.head(pose_size);
    dx_landmarks->resize(graph_.landmarks.size());
    for (std::size_t l = 0; l < graph_.landmarks.size(); ++l) {
      (*dx_landmarks)[l] = dx.segment<3>(pose_size + 3 * static_cast<Eigen::Index>(l));
    }
    return true;
  }

  std::size_t factorised_variables() const { return 6 * (graph_.poses.size() - 1) + 3 * graph_.landmarks.size(); }
  std::size_t factor_nonzeros() const { return factor_nonzeros_; }

 private:
  const LandmarkGraph3D& graph_;
  const Links& links_;
  SparseCholesky cholesky_;
  bool analysed_ = false;
  std::size_t factor_nonzeros_ = 0;
};

template <class Solver>
LandmarkGraphSummary levenberg_marquardt(LandmarkGraph3D& graph, const LandmarkGraph3DOptions& options) {
  LandmarkGraphSummary summary;
  summary.variables = 6 * (graph.poses.size() - 1) + 3 * graph.landmarks.size();
  summary.initial_cost = summary.final_cost = graph.cost();
  if (summary.variables == 0) {
    summary.status = LandmarkGraphStatus::kConverged;
    summary.message = "nothing to optimise (only the fixed pose)";
    return summary;
  }
  const Links links = make_links(graph);
  auto start = Clock::now();
  Solver solver(graph, links);  // symbolic analysis once
  summary.time_solve_s += seconds_since(start);
  summary.factorised_variables = solver.factorised_variables();
  Normal normal;
  start = Clock::now();
  double cost = linearise(graph, links, &normal);
  summary.time_linearise_s += seconds_since(start);
  double lambda = options.initial_lambda;
  double nu = 2.0;
  summary.status = LandmarkGraphStatus::kMaxIterations;
  summary.message = "reached max_iterations";
  Eigen::VectorXd dx_poses;
  std::vector<Vector3> dx_landmarks;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    summary.iterations = iteration + 1;
    start = Clock::now();
    const bool solved = solver.solve(normal, lambda, &dx_poses, &dx_landmarks);
    summary.time_solve_s += seconds_since(start);
    if (!solved) {
      lambda *= 10.0;
      if (lambda > 1e12) {
        summary.status = LandmarkGraphStatus::kFailed;
        summary.message = "the damped normal equations are not positive definite (unconstrained variable?)";
        break;
      }
      continue;
    }
    summary.factor_nonzeros = solver.factor_nonzeros();
    // The graph is referenced by the solver: evaluate the trial on a copy's poses / points.
    std::vector<core::SE3> trial_poses = graph.poses;
    std::vector<Vector3> trial_landmarks = graph.landmarks;
    double largest_step = dx_poses.size() > 0 ? dx_poses.lpNorm<Eigen::Infinity>() : 0.0;
    for (std::size_t i = 1; i < trial_poses.size(); ++i) {
      trial_poses[i] = trial_poses[i] * core::SE3::exp(dx_poses.segment<6>(6 * pose_block(i)));
    }
    for (std::size_t l = 0; l < trial_landmarks.size(); ++l) {
      trial_landmarks[l] += dx_landmarks[l];
      largest_step = std::max(largest_step, dx_landmarks[l].lpNorm<Eigen::Infinity>());
    }
    std::swap(graph.poses, trial_poses);
    std::swap(graph.landmarks, trial_landmarks);
    const double trial_cost = graph.cost();
    // Decrease predicted by the damped quadratic model: with (H + lambda D) dx = -b,
    // m(0) - m(dx) = -b^T dx + lambda dx^T D dx (cost = e^T Omega e, D = diag(H)).
    double predicted = 0.0;
    for (std::size_t p = 0; p + 1 < graph.poses.size(); ++p) {
      const Vector6 d = dx_poses.segment<6>(6 * static_cast<Eigen::Index>(p));
      predicted += -normal.b_pose[p].dot(d) + lambda * d.dot(normal.A_diagonal[p].diagonal().cwiseProduct(d));
    }
    for (std::size_t l = 0; l < graph.landmarks.size(); ++l) {
      const Vector3& d = dx_landmarks[l];
      predicted += -normal.b_landmark[l].dot(d) + lambda * d.dot(normal.V[l].diagonal().cwiseProduct(d));
    }
    if (std::isfinite(trial_cost) && trial_cost <= cost) {
      const double decrease = cost - trial_cost;
      start = Clock::now();
      cost = linearise(graph, links, &normal);
      summary.time_linearise_s += seconds_since(start);
      // Nielsen's update (Madsen, Nielsen & Tingleff 2004, "Methods for non-linear least squares
      // problems", eq. 2.21; Ceres' LevenbergMarquardtStrategy): shrink lambda by up to 3x
      // when the model predicted the decrease well (rho near 1), keep it when it did not.
      const double rho = predicted > 0.0 ? decrease / predicted : 0.0;
      const double t = 2.0 * rho - 1.0;
      lambda = std::max(lambda * std::max(1.0 / 3.0, 1.0 - t * t * t), 1e-12);
      nu = 2.0;
      if (decrease <= options.relative_cost_tolerance * cost || largest_step <= options.step_tolerance) {
        summary.status = LandmarkGraphStatus::kConverged;
        summary.message = "converged";
        break;
      }
    } else {
      std::swap(graph.poses, trial_poses);  // reject: restore the previous estimate
      std::swap(graph.landmarks, trial_landmarks);
      lambda *= nu;
      nu *= 2.0;
      if (lambda > 1e12) {
        summary.status = LandmarkGraphStatus::kConverged;
        summary.message = "no step lowers the cost (at a minimum to machine precision)";
        break;
      }
    }
  }
  summary.final_cost = cost;
  return summary;
}

bool positive_definite(const auto& M) {
  if (!M.allFinite() || !M.isApprox(M.transpose(), 1e-9)) return false;
  return Eigen::LLT<std::decay_t<decltype(M)>>(M).info() == Eigen::Success;
}

}  // namespace

Vector3 landmark_from_observation_3d(const core::SE3& T_world_body, const LandmarkFactor3D& observation) {
  Vector3 q_body = observation.z;
  if (observation.model == LandmarkModel3D::kRangeBearingElevation) {
    const double r = observation.z.x();
    const double b = observation.z.y();
    const double el = observation.z.z();
    q_body = Vector3(r * std::cos(el) * std::cos(b), r * std::cos(el) * std::sin(b), r * std::sin(el));
  }
  return T_world_body.rotation_matrix() * q_body + T_world_body.translation();
}

std::string LandmarkGraph3D::check() const {
  if (poses.empty()) return "the graph has no poses";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!poses[i].matrix().allFinite()) return "pose " + std::to_string(i) + " is not finite";
  }
  for (std::size_t l = 0; l < landmarks.size(); ++l) {
    if (!landmarks[l].allFinite()) return "landmark " + std::to_string(l) + " is not finite";
  }
  for (std::size_t k = 0; k < odometry.size(); ++k) {
    const PoseFactor3D& f = odometry[k];
    const std::string name = "odometry factor " + std::to_string(k);
    if (f.from >= poses.size() || f.to >= poses.size() || f.from == f.to) return name + " names a missing pose";
    if (!f.T_from_to.matrix().allFinite()) return name + " has a non-finite measurement";
    if (!positive_definite(f.information)) return name + " has an information matrix that is not positive definite";
  }
  std::vector<char> observed(landmarks.size(), 0);
  for (std::size_t k = 0; k < observations.size(); ++k) {
    const LandmarkFactor3D& f = observations[k];
    const std::string name = "observation factor " + std::to_string(k);
    if (f.pose >= poses.size()) return name + " names a missing pose";
    if (f.landmark >= landmarks.size()) return name + " names a missing landmark";
    if (!f.z.allFinite()) return name + " has a non-finite measurement";
    if (f.model == LandmarkModel3D::kRangeBearingElevation && !(f.z.x() > 0.0)) return name + " has a range <= 0";
    if (!positive_definite(f.information)) return name + " has an information matrix that is not positive definite";
    observed[f.landmark] = 1;
  }
  for (std::size_t l = 0; l < landmarks.size(); ++l) {
    if (observed[l] == 0) return "landmark " + std::to_string(l) + " is never observed (unconstrained)";
  }
  return {};
}

double LandmarkGraph3D::cost() const {
  double total = 0.0;
  for (const PoseFactor3D& f : odometry) {
    const Vector6 e = odometry_residual(poses[f.from], poses[f.to], f, nullptr, nullptr);
    total += e.dot(f.information * e);
  }
  for (const LandmarkFactor3D& f : observations) {
    const Vector3 e = observation_residual(poses[f.pose], landmarks[f.landmark], f, nullptr, nullptr);
    total += e.dot(f.information * e);
  }
  return total;
}

LandmarkGraphSummary optimize(LandmarkGraph3D& graph, const LandmarkGraph3DOptions& options) {
  CAIRN_ASSERT(graph.check().empty(), "optimize(LandmarkGraph3D): graph.check() must be empty");
  CAIRN_ASSERT(options.is_valid(nullptr), "optimize(LandmarkGraph3D): invalid options");
  return options.elimination == LandmarkElimination::kSchur ? levenberg_marquardt<SchurSolver>(graph, options)
                                                            : levenberg_marquardt<JointSolver>(graph, options);
}

}  // namespace cairn::backend
