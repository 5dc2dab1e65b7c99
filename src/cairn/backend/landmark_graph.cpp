#include "cairn/backend/landmark_graph.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>

#include <Eigen/Cholesky>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::backend {
namespace {

using SparseMatrix = Eigen::SparseMatrix<double>;
using Solver = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::AMDOrdering<int>>;


// Column of each variable in the normal equations: free poses (1..), then landmarks.
struct Layout {
  std::size_t pose_count = 0;
  std::size_t landmark_count = 0;
  // -1 for the fixed pose 0.
  Eigen::Index pose_column(std::size_t i) const { return i == 0 ? -1 : static_cast<Eigen::Index>(3 * (i - 1)); }
  Eigen::Index landmark_column(std::size_t l) const {
    return static_cast<Eigen::Index>(3 * (pose_count - 1) + 2 * l);
  }
  Eigen::Index size() const { return static_cast<Eigen::Index>(3 * (pose_count - 1) + 2 * landmark_count); }
};

// Adds J_a^T Omega J_b to the lower triangle (row >= column) of H as triplets.
template <int Ra, int Rb>
void add_block(std::vector<Eigen::Triplet<double>>* triplets, Eigen::Index row, Eigen::Index column,
               const Eigen::Matrix<double, Ra, Rb>& block) {
  for (int r = 0; r < Ra; ++r) {
    for (int c = 0; c < Rb; ++c) {
      if (row + r >= column + c) triplets->emplace_back(static_cast<int>(row + r), static_cast<int>(column + c), block(r, c));
    }
  }
}

// Builds the lower triangle of H = sum J^T Omega J and b = sum J^T Omega e (Grisetti et al.
// 2010, Algorithm 1).
double linearise(const LandmarkGraph2D& graph, const Layout& layout, SparseMatrix* H, Eigen::VectorXd* b) {
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(graph.odometry.size() * 21 + graph.observations.size() * 18);
  b->setZero(layout.size());
  double cost = 0.0;
  for (const OdometryFactor2D& f : graph.odometry) {
    Matrix3 J_i;
    Matrix3 J_j;
    const Vector3 e = odometry_residual_2d(graph.poses[f.from], graph.poses[f.to], f.u, &J_i, &J_j);
    cost += e.dot(f.information * e);
    const Eigen::Index ci = layout.pose_column(f.from);
    const Eigen::Index cj = layout.pose_column(f.to);
    if (ci >= 0) {
      add_block<3, 3>(&triplets, ci, ci, J_i.transpose() * f.information * J_i);
      b->segment<3>(ci) += J_i.transpose() * f.information * e;
    }
    if (cj >= 0) {
      add_block<3, 3>(&triplets, cj, cj, J_j.transpose() * f.information * J_j);
      b->segment<3>(cj) += J_j.transpose() * f.information * e;
    }
    if (ci >= 0 && cj >= 0) {
      if (cj > ci) {
        add_block<3, 3>(&triplets, cj, ci, J_j.transpose() * f.information * J_i);
      } else {
        add_block<3, 3>(&triplets, ci, cj, J_i.transpose() * f.information * J_j);
      }
    }
  }
  for (const RangeBearingFactor2D& f : graph.observations) {
    Matrix23 J_p;
    Matrix2 J_l;
    const Vector2 e = range_bearing_residual_2d(graph.poses[f.pose], graph.landmarks[f.landmark], f.z, &J_p, &J_l);
    cost += e.dot(f.information * e);
    const Eigen::Index cp = layout.pose_column(f.pose);
    const Eigen::Index cl = layout.landmark_column(f.landmark);
    add_block<2, 2>(&triplets, cl, cl, J_l.transpose() * f.information * J_l);
    b->segment<2>(cl) += J_l.transpose() * f.information * e;
    if (cp >= 0) {
      add_block<3, 3>(&triplets, cp, cp, J_p.transpose() * f.information * J_p);
      b->segment<3>(cp) += J_p.transpose() * f.information * e;
      // Landmark columns come after every pose column: the block lies in the lower triangle.
      add_block<2, 3>(&triplets, cl, cp, J_l.transpose() * f.information * J_p);
    }
  }
  H->resize(layout.size(), layout.size());
  H->setFromTriplets(triplets.begin(), triplets.end());
  return cost;
}

bool finite(const Eigen::MatrixXd& m) { return m.allFinite(); }

/// A pose stored as (x, y, theta), updated by x <- (x + dx, y + dy, wrap(theta + dtheta)): the
/// parameterisation of this file's Jacobians (see the header), as a manifold of the engine.
class PlanarPoseVector final : public Manifold {
 public:
  int ambient_size() const override { return 3; }
  int tangent_size() const override { return 3; }
  void plus(const double* x, const double* delta, double* x_plus) const override {
    x_plus[0] = x[0] + delta[0];
    x_plus[1] = x[1] + delta[1];
    x_plus[2] = core::wrap_angle(x[2] + delta[2]);
  }
  std::string_view name() const override { return "(x, y, theta)"; }
};


class OdometryFactor final : public Factor {
 public:
  explicit OdometryFactor(const OdometryFactor2D& f) : u_(f.u), S_(square_root_information<3>(f.information)) {}
  int residual_size() const override { return 3; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    Matrix3 J_i, J_j;
    const bool want = jacobians != nullptr;
    const Vector3 e = odometry_residual_2d(Eigen::Map<const Vector3>(values[0]), Eigen::Map<const Vector3>(values[1]), u_,
                                           want ? &J_i : nullptr, want ? &J_j : nullptr);
    Eigen::Map<Vector3>{residual} = S_ * e;
    using RowMajor3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
    if (want && jacobians[0] != nullptr) Eigen::Map<RowMajor3>{jacobians[0]} = S_ * J_i;
    if (want && jacobians[1] != nullptr) Eigen::Map<RowMajor3>{jacobians[1]} = S_ * J_j;
    return true;
  }

 private:
  Vector3 u_;
  Matrix3 S_;
};

class RangeBearingFactor final : public Factor {
 public:
  explicit RangeBearingFactor(const RangeBearingFactor2D& f) : z_(f.z), S_(square_root_information<2>(f.information)) {}
  int residual_size() const override { return 2; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    const Eigen::Map<const Vector3> pose(values[0]);
    const Eigen::Map<const Vector2> landmark(values[1]);
    if ((landmark - pose.head<2>()).squaredNorm() == 0.0) return false;  // bearing undefined
    Matrix23 J_pose;
    Matrix2 J_landmark;
    const bool want = jacobians != nullptr;
    const Vector2 e = range_bearing_residual_2d(pose, landmark, z_, want ? &J_pose : nullptr, want ? &J_landmark : nullptr);
    Eigen::Map<Vector2>{residual} = S_ * e;
    if (want && jacobians[0] != nullptr) Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>>{jacobians[0]} = S_ * J_pose;
    if (want && jacobians[1] != nullptr) Eigen::Map<Eigen::Matrix<double, 2, 2, Eigen::RowMajor>>{jacobians[1]} = S_ * J_landmark;
    return true;
  }

 private:
  Vector2 z_;
  Matrix2 S_;
};

}  // namespace

Vector3 odometry_residual_2d(const Vector3& pose_i, const Vector3& pose_j, const Vector3& u, Matrix3* J_e_pose_i,
                             Matrix3* J_e_pose_j) {
  const double c = std::cos(pose_i.z());
  const double s = std::sin(pose_i.z());
  const Vector2 d = pose_j.head<2>() - pose_i.head<2>();
  const Vector2 local(c * d.x() + s * d.y(), -s * d.x() + c * d.y());  // R_i^T (t_j - t_i)
  if (J_e_pose_i != nullptr) {
    *J_e_pose_i << -c, -s, local.y(),  //
        s, -c, -local.x(),             //
        0.0, 0.0, -1.0;
  }
  if (J_e_pose_j != nullptr) {
    *J_e_pose_j << c, s, 0.0,  //
        -s, c, 0.0,            //
        0.0, 0.0, 1.0;
  }
  return {local.x() - u.x(), local.y() - u.y(), core::wrap_angle(pose_j.z() - pose_i.z() - u.z())};
}

Vector2 range_bearing_residual_2d(const Vector3& pose, const Vector2& p_world, const Vector2& z, Matrix23* J_e_pose,
                                  Matrix2* J_e_landmark) {
  const Vector2 d = p_world - pose.head<2>();
  const double q = d.squaredNorm();
  const double r = std::sqrt(q);
  if (J_e_pose != nullptr) {
    *J_e_pose << -d.x() / r, -d.y() / r, 0.0,  //
        d.y() / q, -d.x() / q, -1.0;
  }
  if (J_e_landmark != nullptr) {
    *J_e_landmark << d.x() / r, d.y() / r,  //
        -d.y() / q, d.x() / q;
  }
  return {r - z.x(), core::wrap_angle(std::atan2(d.y(), d.x()) - pose.z() - z.y())};
}

std::string LandmarkGraph2D::check() const {
  if (poses.empty()) return "the graph has no poses";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (!poses[i].allFinite()) return "pose " + std::to_string(i) + " is not finite";
  }
  for (std::size_t l = 0; l < landmarks.size(); ++l) {
    if (!landmarks[l].allFinite()) return "landmark " + std::to_string(l) + " is not finite";
  }
  for (std::size_t k = 0; k < odometry.size(); ++k) {
    const OdometryFactor2D& f = odometry[k];
    if (f.from >= poses.size() || f.to >= poses.size() || f.from == f.to) {
      return "odometry factor " + std::to_string(k) + " names a missing pose";
    }
    if (!f.u.allFinite() || !finite(f.information)) return "odometry factor " + std::to_string(k) + " is not finite";
  }
  for (std::size_t k = 0; k < observations.size(); ++k) {
    const RangeBearingFactor2D& f = observations[k];
    if (f.pose >= poses.size() || f.landmark >= landmarks.size()) {
      return "observation factor " + std::to_string(k) + " names a missing pose or landmark";
    }
    if (!f.z.allFinite() || !finite(f.information) || !(f.z.x() > 0.0)) {
      return "observation factor " + std::to_string(k) + " is not finite or has a range <= 0";
    }
  }
  return {};
}

double LandmarkGraph2D::cost() const {
  double total = 0.0;
  for (const OdometryFactor2D& f : odometry) {
    const Vector3 e = odometry_residual_2d(poses[f.from], poses[f.to], f.u);
    total += e.dot(f.information * e);
  }
  for (const RangeBearingFactor2D& f : observations) {
    const Vector2 e = range_bearing_residual_2d(poses[f.pose], landmarks[f.landmark], f.z);
    total += e.dot(f.information * e);
  }
  return total;
}

bool LandmarkGraphOptions::is_valid(std::string* why) const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  if (max_iterations < 1) add("max_iterations must be >= 1");
  if (!(initial_lambda > 0.0 && std::isfinite(initial_lambda))) add("initial_lambda must be > 0");
  if (!(relative_cost_tolerance >= 0.0)) add("relative_cost_tolerance must be >= 0");
  if (!(step_tolerance >= 0.0)) add("step_tolerance must be >= 0");
  if (why != nullptr) *why = problems;
  return problems.empty();
}

void copy_engine_summary(const LeastSquaresSummary& result, LandmarkGraphSummary& summary) {
  summary.iterations = result.iterations;
  summary.factorised_variables = static_cast<std::size_t>(result.reduced_size);
  summary.factor_nonzeros = result.factor_nonzeros;
  summary.time_linearise_s = result.jacobian_s + result.residual_s + result.linear_system_s;
  summary.time_solve_s = result.linear_solve_s + result.analyze_s;
  summary.message = result.message;
  switch (result.termination) {
    case LeastSquaresTermination::kConvergence: summary.status = LandmarkGraphStatus::kConverged; break;
    case LeastSquaresTermination::kNoConvergence:
    case LeastSquaresTermination::kInterrupted: summary.status = LandmarkGraphStatus::kMaxIterations; break;
    case LeastSquaresTermination::kFailure: summary.status = LandmarkGraphStatus::kFailed; break;
  }
}

LandmarkGraphSummary optimize(LandmarkGraph2D& graph, const LandmarkGraphOptions& options) {
  // The graph holds the input's numbers (odometry of 1e308 m makes an infinite motion): an error
  // naming the problem, not an assertion.
  if (const std::string problem = graph.check(); !problem.empty()) throw std::invalid_argument("landmark graph: " + problem);
  CAIRN_ASSERT(options.is_valid(nullptr), "optimize(LandmarkGraph2D): invalid options");
  LandmarkGraphSummary summary;
  const Layout layout{graph.poses.size(), graph.landmarks.size()};
  summary.variables = static_cast<std::size_t>(layout.size());
  summary.factorised_variables = summary.variables;
  summary.initial_cost = summary.final_cost = graph.cost();
  if (layout.size() == 0) {
    summary.status = LandmarkGraphStatus::kConverged;
    summary.message = "nothing to optimise (only the fixed pose)";
    return summary;
  }
  // A front end over the least-squares engine (least_squares.hpp): poses and landmarks in one
  // system (no Schur elimination, see the header), pose 0 constant.
  static const PlanarPoseVector kPose;
  LeastSquaresProblem problem;
  for (Vector3& pose : graph.poses) problem.add_variable(pose.data(), kPose);
  problem.set_constant(0);
  const int first_landmark = static_cast<int>(graph.poses.size());
  for (Vector2& landmark : graph.landmarks) problem.add_variable(landmark.data(), euclidean_manifold(2));
  for (const OdometryFactor2D& f : graph.odometry) {
    problem.add_factor(std::make_unique<OdometryFactor>(f), {static_cast<int>(f.from), static_cast<int>(f.to)});
  }
  for (const RangeBearingFactor2D& f : graph.observations) {
    problem.add_factor(std::make_unique<RangeBearingFactor>(f),
                       {static_cast<int>(f.pose), first_landmark + static_cast<int>(f.landmark)});
  }
  LeastSquaresOptions engine;
  engine.linear_solver = LinearSolverType::kSparseNormalCholesky;
  engine.max_iterations = options.max_iterations;
  engine.initial_trust_region_radius = 1.0 / options.initial_lambda;
  engine.function_tolerance = options.relative_cost_tolerance;
  engine.parameter_tolerance = options.step_tolerance;
  engine.gradient_tolerance = 0.0;
  engine.threads = 1;
  const LeastSquaresSummary result = solve(problem, engine);
  copy_engine_summary(result, summary);
  summary.final_cost = graph.cost();
  return summary;
}

LandmarkGraphMarginals marginal_covariances(const LandmarkGraph2D& graph, const std::vector<std::size_t>& pose_indices,
                                            const std::vector<std::size_t>& landmark_indices) {
  LandmarkGraphMarginals out;
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  out.poses.assign(pose_indices.size(), Matrix3::Constant(kNaN));
  out.landmarks.assign(landmark_indices.size(), Matrix2::Constant(kNaN));
  const Layout layout{graph.poses.size(), graph.landmarks.size()};
  if (layout.size() == 0) return out;
  SparseMatrix H;
  Eigen::VectorXd b;
  linearise(graph, layout, &H, &b);
  Solver solver;
  solver.compute(H);
  if (solver.info() != Eigen::Success) return out;
  out.ok = true;
  // Columns of H^-1, one at a time: Sigma_k = (H^-1)_(k,k).
  Eigen::VectorXd unit = Eigen::VectorXd::Zero(layout.size());
  const auto fill = [&](Eigen::Index column, Eigen::Index size, double* out_block) {
    for (Eigen::Index c = 0; c < size; ++c) {
      unit(column + c) = 1.0;
      const Eigen::VectorXd x = solver.solve(unit);
      unit(column + c) = 0.0;
      for (Eigen::Index r = 0; r < size; ++r) out_block[c * size + r] = x(column + r);  // column-major
    }
  };
  for (std::size_t k = 0; k < pose_indices.size(); ++k) {
    const std::size_t i = pose_indices[k];
    if (i == 0) {
      out.poses[k].setZero();
    } else if (i < graph.poses.size()) {
      fill(layout.pose_column(i), 3, out.poses[k].data());
    }
  }
  for (std::size_t k = 0; k < landmark_indices.size(); ++k) {
    const std::size_t l = landmark_indices[k];
    if (l < graph.landmarks.size()) fill(layout.landmark_column(l), 2, out.landmarks[k].data());
  }
  return out;
}

}  // namespace cairn::backend
