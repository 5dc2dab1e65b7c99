// The pose-graph optimiser (optimizer.hpp) against the same graphs solved on the general
// least-squares engine (pose_graph_engine.hpp): how much the optimiser's special cases are worth,
// measured before the pose graph moves onto the engine (issue 21).
//
// Both start from the same chordal initialisation (not timed), minimise the geodesic objective
// with Ceres' default tolerances (function 1e-6, gradient 1e-10, parameter 1e-8, 50 iterations),
// one thread, undamped start (initial radius 1e16, the optimiser's default); the optimiser with
// its defaults (PCG on the previous factorisation), the engine with its sparse normal Cholesky.
// Times are medians of 5 solves from the same start; chi2 is the optimiser's evaluate_cost for
// both.
//
// Usage: bench_pose_graph_engine GRAPH.g2o [GRAPH.g2o ...]   (Markdown table on stdout)

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/pose_graph_engine.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

using namespace cairn;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

template <class Group>
void run(const std::string& name, const io::PoseGraphT<Group>& graph, const std::string& path) {
  backend::PoseGraphProblem<Group> start = backend::make_problem(graph, path);
  backend::initialize_chordal(start);
  backend::OptimizerOptions optimizer;
  optimizer.function_tolerance = 1e-6;
  optimizer.gradient_tolerance = 1e-10;
  optimizer.parameter_tolerance = 1e-8;
  optimizer.max_iterations = 50;
  optimizer.threads = 1;
  backend::LeastSquaresOptions engine;
  engine.function_tolerance = 1e-6;
  engine.gradient_tolerance = 1e-10;
  engine.parameter_tolerance = 1e-8;
  engine.max_iterations = 50;
  engine.threads = 1;
  engine.initial_trust_region_radius = 1e16;
  engine.max_trust_region_radius = 1e16;
  std::vector<double> t_optimizer, t_engine;
  int it_optimizer = 0, it_engine = 0;
  double chi2_optimizer = 0.0, chi2_engine = 0.0;
  for (int r = 0; r < 5; ++r) {
    auto a = start;
    auto t0 = Clock::now();
    const backend::OptimizerSummary s = backend::optimize(a, optimizer);
    t_optimizer.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    it_optimizer = s.iterations;
    chi2_optimizer = backend::evaluate_cost(a, optimizer);
    auto b = start;
    t0 = Clock::now();
    const backend::LeastSquaresSummary e = backend::optimize_on_engine(b, backend::Objective::kGeodesic, engine);
    t_engine.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    it_engine = e.iterations;
    chi2_engine = backend::evaluate_cost(b, optimizer);
  }
  const double to = median(t_optimizer), te = median(t_engine);
  std::printf("| %s | %zu | %zu | %.2f | %d | %.10g | %.2f | %d | %.10g | %.2fx |\n", name.c_str(), start.T_world_pose.size(),
              start.edges.size(), 1e3 * to, it_optimizer, chi2_optimizer, 1e3 * te, it_engine, chi2_engine, te / to);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: bench_pose_graph_engine GRAPH.g2o [GRAPH.g2o ...]\n");
    return 2;
  }
  std::printf("| graph | poses | edges | optimiser ms | it | chi2 | engine ms | it | chi2 | engine / optimiser |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (int i = 1; i < argc; ++i) {
    const std::string path = argv[i];
    try {
      const io::GraphFile file = io::read_graph(path, io::GraphReadOptions{});
      const std::string name = std::filesystem::path(path).stem().string();
      if (const auto* g2 = std::get_if<io::PoseGraph2D>(&file.graph)) {
        run(name, *g2, path);
      } else {
        run(name, std::get<io::PoseGraph3D>(file.graph), path);
      }
    } catch (const io::ParseError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  return 0;
}
