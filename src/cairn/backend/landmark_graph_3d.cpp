#include "cairn/backend/landmark_graph_3d.hpp"

#include <cmath>
#include <memory>
#include <type_traits>
#include <utility>

#include <Eigen/Cholesky>

#include "cairn/backend/factors.hpp"
#include "cairn/backend/landmark_factors_3d.hpp"
#include "cairn/backend/least_squares.hpp"
#include "cairn/core/assert.hpp"

namespace cairn::backend {
namespace {

using RowMajor6 = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

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



class OdometryFactor3D final : public Factor {
 public:
  explicit OdometryFactor3D(const PoseFactor3D& f) : factor_(f), S_(square_root_information<6>(f.information)) {}
  int residual_size() const override { return 6; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    Matrix6 J_i, J_j;
    const bool want = jacobians != nullptr;
    const Vector6 e = odometry_residual(se3_from_values(values[0]), se3_from_values(values[1]), factor_, want ? &J_i : nullptr,
                                        want ? &J_j : nullptr);
    Eigen::Map<Vector6>{residual} = S_ * e;
    if (want && jacobians[0] != nullptr) Eigen::Map<RowMajor6>{jacobians[0]} = S_ * J_i;
    if (want && jacobians[1] != nullptr) Eigen::Map<RowMajor6>{jacobians[1]} = S_ * J_j;
    return true;
  }

 private:
  PoseFactor3D factor_;
  Matrix6 S_;
};

class ObservationFactor3D final : public Factor {
 public:
  explicit ObservationFactor3D(const LandmarkFactor3D& f) : factor_(f), S_(square_root_information<3>(f.information)) {}
  int residual_size() const override { return 3; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    Matrix36 J_pose;
    Matrix3 J_landmark;
    const bool want = jacobians != nullptr;
    const Vector3 e = observation_residual(se3_from_values(values[0]), Eigen::Map<const Vector3>(values[1]), factor_,
                                           want ? &J_pose : nullptr, want ? &J_landmark : nullptr);
    if (!e.allFinite()) return false;
    Eigen::Map<Vector3>{residual} = S_ * e;
    if (want && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>>{jacobians[0]} = S_ * J_pose;
    }
    if (want && jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>{jacobians[1]} = S_ * J_landmark;
    }
    return true;
  }

 private:
  LandmarkFactor3D factor_;
  Matrix3 S_;
};

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
  LandmarkGraphSummary summary;
  summary.variables = 6 * (graph.poses.size() - 1) + 3 * graph.landmarks.size();
  summary.initial_cost = summary.final_cost = graph.cost();
  if (summary.variables == 0) {
    summary.status = LandmarkGraphStatus::kConverged;
    summary.message = "nothing to optimise (only the fixed pose)";
    return summary;
  }
  // A front end over the least-squares engine (least_squares.hpp): poses on SE(3), pose 0
  // constant, landmarks in the eliminated group.
  std::vector<double> pose_values(7 * graph.poses.size());
  LeastSquaresProblem problem;
  for (std::size_t i = 0; i < graph.poses.size(); ++i) {
    double* x = pose_values.data() + 7 * i;
    se3_to_values(graph.poses[i], x);
    problem.add_variable(x, se3_manifold());
  }
  problem.set_constant(0);
  const int first_landmark = static_cast<int>(graph.poses.size());
  for (Vector3& landmark : graph.landmarks) {
    problem.add_variable(landmark.data(), euclidean_manifold(3), VariableGroup::kEliminate);
  }
  for (const PoseFactor3D& f : graph.odometry) {
    problem.add_factor(std::make_unique<OdometryFactor3D>(f), {static_cast<int>(f.from), static_cast<int>(f.to)});
  }
  for (const LandmarkFactor3D& f : graph.observations) {
    problem.add_factor(std::make_unique<ObservationFactor3D>(f),
                       {static_cast<int>(f.pose), first_landmark + static_cast<int>(f.landmark)});
  }
  LeastSquaresOptions engine;
  engine.linear_solver = options.elimination == LandmarkElimination::kSchur ? LinearSolverType::kSparseSchur
                                                                            : LinearSolverType::kSparseNormalCholesky;
  engine.max_iterations = options.max_iterations;
  engine.initial_trust_region_radius = 1.0 / options.initial_lambda;  // damping lambda D = D / radius
  engine.function_tolerance = options.relative_cost_tolerance;
  engine.parameter_tolerance = options.step_tolerance;
  engine.gradient_tolerance = 0.0;
  engine.threads = 1;
  const LeastSquaresSummary result = solve(problem, engine);
  for (std::size_t i = 0; i < graph.poses.size(); ++i) graph.poses[i] = se3_from_values(pose_values.data() + 7 * i);
  copy_engine_summary(result, summary);
  summary.final_cost = graph.cost();
  return summary;
}

}  // namespace cairn::backend
