#include "cairn/backend/keyframe_graph.hpp"

#include "cairn/backend/gnc.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"

namespace cairn::backend {

template <class Group>
KeyframeGraphSolve solve_keyframe_graph(PoseGraphProblem<Group>& problem, bool gnc, const std::vector<bool>& is_loop,
                                        const KeyframeGraphSolveOptions& options) {
  OptimizerOptions solver;
  solver.max_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  solver.threads = 1;
  solver.should_stop = options.should_stop;
  KeyframeGraphSolve solve;
  if (!gnc) {
    optimize(problem, solver);
    solve.applied = true;
    return solve;
  }
  GncOptions gnc_options;
  gnc_options.inner = solver;
  const GncSummary result = optimize_gnc(problem, gnc_options);
  if (result.interrupted) return solve;
  solve.applied = true;
  solve.keep.assign(is_loop.size(), true);
  for (std::size_t e = 0; e < is_loop.size(); ++e) {
    if (!result.weights.empty() && result.weights[e] <= 0.5 && is_loop[e]) {
      solve.keep[e] = false;
      solve.rejected_loops.push_back(e);
    }
  }
  return solve;
}

template KeyframeGraphSolve solve_keyframe_graph(PoseGraphProblem<core::SE2>&, bool, const std::vector<bool>&,
                                                 const KeyframeGraphSolveOptions&);
template KeyframeGraphSolve solve_keyframe_graph(PoseGraphProblem<core::SE3>&, bool, const std::vector<bool>&,
                                                 const KeyframeGraphSolveOptions&);

}  // namespace cairn::backend
