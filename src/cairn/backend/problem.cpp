#include "cairn/backend/problem.hpp"

#include "cairn/backend/least_squares.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <numeric>
#include <unordered_map>

#include "cairn/io/parse_error.hpp"

namespace cairn::backend {

template <class Group>
int PoseGraphProblem<Group>::index_of(std::int64_t id) const {
  const auto it = std::lower_bound(ids.begin(), ids.end(), id);
  if (it != ids.end() && *it == id) return static_cast<int>(it - ids.begin());
  const auto linear = std::find(ids.begin(), ids.end(), id);
  return linear == ids.end() ? -1 : static_cast<int>(linear - ids.begin());
}

template <class Group>
Anchoring check_anchoring(const PoseGraphProblem<Group>& problem) {
  // Union-find over poses, joined by the edges.
  std::vector<int> parent(static_cast<std::size_t>(problem.size()));
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  };
  for (const auto& edge : problem.edges) parent[static_cast<std::size_t>(find(edge.i))] = find(edge.j);
  std::vector<char> anchored(static_cast<std::size_t>(problem.size()), 0);
  for (int p = 0; p < problem.size(); ++p) {
    if (problem.fixed[static_cast<std::size_t>(p)]) anchored[static_cast<std::size_t>(find(p))] = 1;
  }
  Anchoring result;
  for (int p = 0; p < problem.size(); ++p) {
    if (find(p) != p) continue;
    ++result.components;
    if (!anchored[static_cast<std::size_t>(p)] && result.unanchored++ == 0) result.example = p;
  }
  return result;
}

namespace {

// SE-Sync's read_g2o_file: tau = d / tr(Omega_t^-1); kappa = I33 in 2D, 3 / (2 tr(Omega_R^-1)) in 3D.
template <class Group>
bool sesync_weights(const Eigen::Matrix<double, Group::kDoF, Group::kDoF>& I, double& kappa, double& tau) {
  constexpr int d = Group::kDoF == 3 ? 2 : 3;
  const Eigen::Matrix<double, d, d> It = I.template topLeftCorner<d, d>();
  const double trace_t = It.inverse().trace();
  if constexpr (d == 2) {
    kappa = I(2, 2);
  } else {
    const Eigen::Matrix3d IR = I.template bottomRightCorner<3, 3>();
    kappa = 3.0 / (2.0 * IR.inverse().trace());
  }
  tau = static_cast<double>(d) / trace_t;
  return std::isfinite(kappa) && std::isfinite(tau) && kappa > 0.0 && tau > 0.0;
}

}  // namespace

template <class Group>
PoseGraphProblem<Group> make_problem(const io::PoseGraphT<Group>& graph, const std::string& path) {
  PoseGraphProblem<Group> problem;
  std::unordered_map<std::int64_t, int> index;
  if (!graph.vertices.empty()) {
    problem.has_initial_guess = true;
    for (const auto& v : graph.vertices) {
      index.emplace(v.id, problem.size());
      problem.ids.push_back(v.id);
      problem.T_world_pose.push_back(v.T_world_pose);
    }
  } else {
    std::vector<std::int64_t> ids;
    for (const auto& e : graph.edges) {
      ids.push_back(e.from);
      ids.push_back(e.to);
    }
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    for (const auto id : ids) {
      index.emplace(id, problem.size());
      problem.ids.push_back(id);
    }
    problem.T_world_pose.assign(ids.size(), Group());
  }
  if (problem.size() == 0) throw io::ParseError(path, 0, "the graph has no poses");
  problem.fixed.assign(static_cast<std::size_t>(problem.size()), 0);
  for (const auto id : graph.fixed) problem.fixed[static_cast<std::size_t>(index.at(id))] = 1;
  if (graph.fixed.empty()) problem.fixed[0] = 1;

  for (const auto& e : graph.edges) {
    PoseEdge<Group> edge;
    edge.i = index.at(e.from);
    edge.j = index.at(e.to);
    edge.T_i_j = e.T_from_to;
    edge.information = e.information;
    edge.sqrt_information = square_root_information<Group::kDoF>(e.information);
    edge.kind = (e.to - e.from == 1 || e.from - e.to == 1) ? EdgeKind::kOdometry : EdgeKind::kLoopClosure;
    edge.line = e.line;
    if (!sesync_weights<Group>(e.information, edge.kappa, edge.tau)) {
      throw io::ParseError(path, e.line,
                           "the translation or rotation block of the information matrix is singular: "
                           "expected positive definite diagonal blocks (SE-Sync weights)");
    }
    problem.edges.push_back(edge);
  }
  const Anchoring anchoring = check_anchoring(problem);
  if (anchoring.unanchored > 0) {
    const std::int64_t example = problem.ids[static_cast<std::size_t>(anchoring.example)];
    throw io::ParseError(path, 0,
                         "the graph has " + std::to_string(anchoring.components) + " connected components and " +
                             std::to_string(anchoring.unanchored) + " of them (one contains pose " + std::to_string(example) +
                             ") have no fixed pose: expected a connected graph, or a FIX pose in every component");
  }
  return problem;
}

template <class Group>
io::PoseGraphT<Group> to_graph(const PoseGraphProblem<Group>& problem, const io::PoseGraphT<Group>& original) {
  io::PoseGraphT<Group> graph;
  graph.edges = original.edges;
  graph.fixed = original.fixed;
  for (int p = 0; p < problem.size(); ++p) {
    graph.vertices.push_back({problem.ids[static_cast<std::size_t>(p)], problem.T_world_pose[static_cast<std::size_t>(p)]});
  }
  return graph;
}

template struct PoseGraphProblem<core::SE2>;
template struct PoseGraphProblem<core::SE3>;
template Anchoring check_anchoring(const Problem2D&);
template Anchoring check_anchoring(const Problem3D&);
template Problem2D make_problem(const io::PoseGraph2D&, const std::string&);
template Problem3D make_problem(const io::PoseGraph3D&, const std::string&);
template io::PoseGraph2D to_graph(const Problem2D&, const io::PoseGraph2D&);
template io::PoseGraph3D to_graph(const Problem3D&, const io::PoseGraph3D&);

}  // namespace cairn::backend
