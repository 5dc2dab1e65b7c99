#include "cairn/backend/pose_graph_engine.hpp"

#include <memory>

namespace cairn::backend {
namespace {

template <class Group>
constexpr int kAmbient = Group::kDoF == 3 ? 3 : 7;

template <class Group>
Group pose_from_values(const double* x) {
  if constexpr (Group::kDoF == 3) {
    return se2_from_values(x);
  } else {
    return se3_from_values(x);
  }
}

template <class Group>
void values_from_pose(const Group& T, double* x) {
  if constexpr (Group::kDoF == 3) {
    se2_to_values(T, x);
  } else {
    se3_to_values(T, x);
  }
}

/// One edge of the graph as an engine factor; Factor is GeodesicFactor<Group> or
/// ChordalFactor<Group>, whose residuals are already whitened.
template <class Group, class EdgeFactor>
class EdgeAsFactor final : public Factor {
 public:
  explicit EdgeAsFactor(const PoseEdge<Group>& edge) : edge_(edge) {}
  int residual_size() const override { return EdgeFactor::kResidualDim; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    using Jacobian = typename EdgeFactor::Jacobian;
    Jacobian J_i, J_j;
    const bool want = jacobians != nullptr;
    const auto r = EdgeFactor::evaluate(pose_from_values<Group>(values[0]), pose_from_values<Group>(values[1]), edge_,
                                        want ? &J_i : nullptr, want ? &J_j : nullptr);
    Eigen::Map<typename EdgeFactor::Residual>{residual} = r;
    using RowMajor = Eigen::Matrix<double, EdgeFactor::kResidualDim, Group::kDoF, Eigen::RowMajor>;
    if (want && jacobians[0] != nullptr) Eigen::Map<RowMajor>{jacobians[0]} = J_i;
    if (want && jacobians[1] != nullptr) Eigen::Map<RowMajor>{jacobians[1]} = J_j;
    return true;
  }

 private:
  PoseEdge<Group> edge_;
};

}  // namespace

template <class Group>
LeastSquaresSummary optimize_on_engine(PoseGraphProblem<Group>& problem, Objective objective,
                                       const LeastSquaresOptions& options) {
  constexpr int ambient = kAmbient<Group>;
  std::vector<double> values(static_cast<std::size_t>(ambient) * problem.T_world_pose.size());
  const Manifold& manifold = Group::kDoF == 3 ? se2_manifold() : se3_manifold();
  LeastSquaresProblem ls;
  for (std::size_t k = 0; k < problem.T_world_pose.size(); ++k) {
    values_from_pose(problem.T_world_pose[k], values.data() + ambient * k);
    ls.add_variable(values.data() + ambient * k, manifold);
    if (problem.fixed[k]) ls.set_constant(static_cast<int>(k));
  }
  for (const PoseEdge<Group>& edge : problem.edges) {
    with_factor<Group>(objective, [&](auto factor) {
      using EdgeFactor = decltype(factor);
      ls.add_factor(std::make_unique<EdgeAsFactor<Group, EdgeFactor>>(edge), {edge.i, edge.j});
    });
  }
  LeastSquaresOptions engine = options;
  engine.linear_solver = LinearSolverType::kSparseNormalCholesky;
  const LeastSquaresSummary summary = solve(ls, engine);
  for (std::size_t k = 0; k < problem.T_world_pose.size(); ++k) {
    problem.T_world_pose[k] = pose_from_values<Group>(values.data() + ambient * k);
  }
  return summary;
}

template LeastSquaresSummary optimize_on_engine(Problem2D&, Objective, const LeastSquaresOptions&);
template LeastSquaresSummary optimize_on_engine(Problem3D&, Objective, const LeastSquaresOptions&);

}  // namespace cairn::backend
