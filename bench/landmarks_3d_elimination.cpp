// 3D landmark graph SLAM: Schur elimination of the landmarks against one joint AMD
// factorisation (backend/landmark_graph_3d.hpp), on two kinds of 3D landmark worlds whose size
// grows with the route (sim/landmark_world_3d.hpp, landmarks in a 24 m wide ring around a
// circular route, a pose every 0.5 m, density constant):
//   camera-like: 3D point observations (stereo / RGB-D), 60-degree viewing cone, 15 m range:
//                each landmark is seen from a short stretch of the route;
//   omni:        range-bearing-elevation in every direction, 12 m range: each landmark is
//                seen from every pose within 12 m (about 50 poses).
// Both solvers start from dead reckoning and run LM to convergence. Printed per case: total
// time, iterations, time per iteration, the share of the time spent building and solving the
// damped system (Schur complement or joint matrix, factorisation, back-substitution; the rest is
// linearisation and cost evaluation), the size of the factorised system and the non-zeros of
// its Cholesky factor, and the final cost (equal for both, or the table says so).
//
//   cmake -S . -B build-bench -DCAIRN_BUILD_BENCH=ON && cmake --build build-bench --target bench_landmarks_3d_elimination
//   ./build-bench/bench/bench_landmarks_3d_elimination [max_poses]   # markdown table on stdout

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>

#include "cairn/sim/landmark_world_3d_graph.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using cairn::backend::LandmarkElimination;

struct Result {
  double seconds = 0.0;
  cairn::backend::LandmarkGraphSummary summary;
};

Result solve(const cairn::backend::LandmarkGraph3D& start, LandmarkElimination elimination) {
  cairn::backend::LandmarkGraph3D graph = start;
  cairn::backend::LandmarkGraph3DOptions options;
  options.elimination = elimination;
  const auto t0 = Clock::now();
  Result r;
  r.summary = cairn::backend::optimize(graph, options);
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  const int max_poses = argc > 1 ? std::atoi(argv[1]) : 2000;
  if (max_poses < 100) {
    std::fprintf(stderr, "usage: %s [max_poses >= 100]\n", argv[0]);
    return 2;
  }
  std::printf("| world | poses | landmarks | observations | elimination | s | it | s/it | of which solve | factorised | factor nnz | final cost |\n");
  std::printf("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|\n");
  for (const bool camera : {true, false}) {
    for (int poses = 250; poses <= max_poses; poses *= 2) {
      cairn::sim::LandmarkWorld3DOptions o;
      o.poses = poses;
      o.laps = 1;
      o.circle_radius_m = 0.5 * poses / (2.0 * std::numbers::pi);
      o.ring_half_width_m = 12.0;
      o.landmarks = 2 * poses;  // 4 per metre of route
      o.climb_m = 2.0;
      if (camera) {
        o.sensor = cairn::sim::LandmarkSensor3D::kPoint;
        o.field_of_view_rad = std::numbers::pi / 3.0;
        o.max_range_m = 15.0;
      } else {
        o.sensor = cairn::sim::LandmarkSensor3D::kRangeBearingElevation;
        o.max_range_m = 12.0;
      }
      const cairn::sim::LandmarkWorld3D world = cairn::sim::simulate_landmark_world_3d(o, 1);
      const cairn::sim::WorldGraph3D built = cairn::sim::graph_from_world(world);
      if (const std::string problem = built.graph.check(); !problem.empty()) {
        std::fprintf(stderr, "bench_landmarks_3d_elimination: %s\n", problem.c_str());
        return 1;
      }
      for (const LandmarkElimination elimination : {LandmarkElimination::kSchur, LandmarkElimination::kJoint}) {
        const Result r = solve(built.graph, elimination);
        std::printf("| %s | %d | %zu | %zu | %s | %.3f | %d | %.4f | %.0f%% | %zu | %zu | %.6g |\n", camera ? "camera-like" : "omni",
                    poses, built.graph.landmarks.size(), built.graph.observations.size(),
                    elimination == LandmarkElimination::kSchur ? "Schur" : "joint", r.seconds, r.summary.iterations,
                    r.seconds / std::max(1, r.summary.iterations), 100.0 * r.summary.time_solve_s / r.seconds,
                    r.summary.factorised_variables,
                    r.summary.factor_nonzeros, r.summary.final_cost);
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
