// Optimise a g2o or TORO pose graph with cairn::backend and write the result.
//   optimize_graph IN.g2o OUT.g2o
#include <cstdio>
#include <exception>
#include <string>
#include <variant>

#include "cairn/backend/pose_graph_job.hpp"
#include "cairn/io/graph_io.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s IN.g2o OUT.g2o\n", argv[0]);
    return 2;
  }
  try {
    const cairn::io::GraphFile file = cairn::io::read_graph(argv[1]);
    cairn::backend::PoseGraphJobOptions options;  // Levenberg-Marquardt, geodesic cost
    return std::visit(
        [&](const auto& graph) {
          const auto result = cairn::backend::run_pose_graph_job(graph, argv[1], options);
          std::printf("%s\n", result.summary.solve.brief_report().c_str());
          if (!result.summary.is_solution_usable()) return 1;
          cairn::io::write_graph(argv[2], cairn::io::PoseGraph(result.optimized), cairn::io::GraphFormat::kG2o);
          std::printf("chi2 %.10g -> %.10g\n", result.summary.cost_after_initialization, result.summary.final_chi2_geodesic);
          return 0;
        },
        file.graph);
  } catch (const std::exception& e) {  // cairn::io::ParseError: file, line, what was wrong
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
