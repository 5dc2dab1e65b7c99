// Where cairn's time goes on one pose graph: the median over repeated solves of the chordal
// initialisation and of each solver stage (linearisation, numeric factorisation, solves with
// the factor, and the rest: analysis, cost evaluations, steps), with the options of
// bench_pose_graph_vs_ceres (Ceres' default stopping rule, one solver thread).
//
// Usage: bench_pose_graph_stages GRAPH.g2o [REPETITIONS=300]

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <variant>
#include <vector>

#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

using namespace cairn;
using Clock = std::chrono::steady_clock;

double median_ms(std::vector<double> seconds) {
  std::sort(seconds.begin(), seconds.end());
  return 1e3 * seconds[seconds.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || argc > 3) {
    std::fprintf(stderr, "usage: %s GRAPH.g2o [REPETITIONS=300]\n", argv[0]);
    return 2;
  }
  int repetitions = 300;
  if (argc == 3) {
    try {
      repetitions = std::stoi(argv[2]);
    } catch (const std::exception&) {
      repetitions = 0;
    }
    if (repetitions < 1) {
      std::fprintf(stderr, "%s: REPETITIONS must be a positive integer, got '%s'\n", argv[0], argv[2]);
      return 2;
    }
  }
  try {
    const io::GraphFile file = io::read_graph(argv[1]);
    std::visit(
        [&](const auto& graph) {
          std::vector<double> init, solve, linearize, factorize, solves, total;
          backend::OptimizerSummary last;
          for (int r = 0; r < repetitions; ++r) {
            auto problem = backend::make_problem(graph, argv[1]);
            const auto t0 = Clock::now();
            backend::initialize_chordal(problem);
            const auto t1 = Clock::now();
            backend::OptimizerOptions options;
            options.function_tolerance = 1e-6;
            options.gradient_tolerance = 1e-10;
            options.parameter_tolerance = 1e-8;
            options.max_iterations = 50;
            options.threads = 1;
            last = backend::optimize(problem, options);
            const auto t2 = Clock::now();
            init.push_back(std::chrono::duration<double>(t1 - t0).count());
            solve.push_back(std::chrono::duration<double>(t2 - t1).count());
            total.push_back(std::chrono::duration<double>(t2 - t0).count());
            linearize.push_back(last.linearize_s);
            factorize.push_back(last.factorize_s);
            solves.push_back(last.solve_s);
          }
          std::printf("%s: median of %d, ms: total %.4g = chordal initialisation %.4g + solver %.4g "
                      "(linearisation %.4g, factorisation %.4g, solves %.4g, analysis %.4g in the last run); "
                      "%d iterations, %d factorisations, chi2 %.9g\n",
                      argv[1], repetitions, median_ms(total), median_ms(init), median_ms(solve), median_ms(linearize),
                      median_ms(factorize), median_ms(solves), 1e3 * last.analyze_s, last.iterations,
                      last.factorizations, last.final_cost);
        },
        file.graph);
  } catch (const io::ParseError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
