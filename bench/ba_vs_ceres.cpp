// cairn's bundle adjustment (backend/least_squares.hpp) against Ceres (Debian's libceres-dev 2.1)
// on BAL problems: same file, same start, same stopping rule, same thread count, in one run.
//
// Ceres gets the formulation and the solver settings of its examples/bundle_adjuster.cc: the
// Snavely reprojection error with automatic derivatives (AutoDiffCostFunction<2, 9, 3>, angle-axis
// camera, all parameters additive), points eliminated first (ParameterBlockOrdering: points in
// group 0, cameras in group 1), Levenberg-Marquardt, SUITE_SPARSE; SPARSE_SCHUR, or
// ITERATIVE_SCHUR with SCHUR_JACOBI, eta 1e-2 and at least 5 CG iterations per solve
// (bundle_adjuster's --eta default and its min_linear_solver_iterations). Both solvers stop on
// Ceres' default tolerances (function 1e-6, gradient 1e-10, parameter 1e-8; the function
// tolerance can be set with --function-tolerance) or after --max-iterations (50 by default). bundle_adjuster also rescales the scene first; neither does
// here (the cost and the steps are the same either way, up to rounding).
//
// Every solver runs in its own forked child (peak resident memory ru_maxrss is its own, the
// problem read in the child too) and repeats the solve from the same start `--repeat` times
// (default 3); the median time is reported. The final cost of both is evaluated with the same
// function (cairn's evaluate_cost, 1/2 sum of squared residuals).
//
// Usage: bench_ba_vs_ceres [--threads N] [--max-iterations N] [--function-tolerance F] [--repeat N]
//                          FILE [FILE ...]
// Prints a Markdown table row per (file, solver).

#include <ceres/ceres.h>
#include <ceres/rotation.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "cairn/backend/bundle_adjustment.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/io/bal.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

using namespace cairn;
using Clock = std::chrono::steady_clock;

int g_threads = 1;
int g_max_iterations = 50;
int g_repeat = 3;
double g_function_tolerance = 1e-6;

struct RunResult {
  double seconds = 0.0;  // median solve time
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int cg_iterations = 0;
  long peak_kb = 0;
  char termination[48] = {};
};

// BAL's camera model (Agarwal et al. 2010), templated for Ceres' automatic differentiation.
struct SnavelyError {
  SnavelyError(double x, double y) : observed_x(x), observed_y(y) {}
  template <typename T>
  bool operator()(const T* const camera, const T* const point, T* residuals) const {
    T P[3];
    ceres::AngleAxisRotatePoint(camera, point, P);
    P[0] += camera[3];
    P[1] += camera[4];
    P[2] += camera[5];
    const T px = -P[0] / P[2];
    const T py = -P[1] / P[2];
    const T r2 = px * px + py * py;
    const T distortion = T(1.0) + r2 * (camera[7] + camera[8] * r2);
    residuals[0] = camera[6] * distortion * px - observed_x;
    residuals[1] = camera[6] * distortion * py - observed_y;
    return true;
  }
  double observed_x;
  double observed_y;
};

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

RunResult run_cairn(const std::string& path, backend::LinearSolverType type) {
  const io::BalProblem original = io::read_bal(path);
  RunResult result;
  std::vector<double> times;
  for (int r = 0; r < g_repeat; ++r) {
    io::BalProblem problem = original;
    backend::BundleAdjustmentOptions options;
    options.solver.linear_solver = type;
    options.solver.threads = g_threads;
    options.solver.max_iterations = g_max_iterations;
    options.solver.function_tolerance = g_function_tolerance;
    options.solver.cg_tolerance = 1e-2;
    options.solver.min_cg_iterations = 5;
    const auto start = Clock::now();
    const backend::LeastSquaresSummary summary = backend::bundle_adjust(problem, options);
    times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    result.iterations = summary.iterations;
    result.cg_iterations = summary.cg_iterations;
    result.initial_cost = summary.initial_cost;
    backend::BundleAdjustmentOptions plain;
    backend::LeastSquaresProblem check = backend::make_bundle_adjustment_problem(problem, plain);
    result.final_cost = backend::evaluate_cost(check);
    std::snprintf(result.termination, sizeof(result.termination), "%s",
                  std::string(backend::to_string(summary.termination)).c_str());
  }
  result.seconds = median(times);
  return result;
}

RunResult run_ceres(const std::string& path, ceres::LinearSolverType type) {
  const io::BalProblem original = io::read_bal(path);
  RunResult result;
  std::vector<double> times;
  for (int r = 0; r < g_repeat; ++r) {
    io::BalProblem problem = original;
    ceres::Problem ceres_problem;
    for (const io::BalObservation& o : problem.observations) {
      ceres_problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<SnavelyError, 2, 9, 3>(new SnavelyError(o.x, o.y)), nullptr,
          problem.camera(o.camera), problem.point(o.point));
    }
    ceres::Solver::Options options;
    options.linear_solver_type = type;
    options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
    options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    if (type == ceres::ITERATIVE_SCHUR) {
      options.preconditioner_type = ceres::SCHUR_JACOBI;
      options.min_linear_solver_iterations = 5;
    }
    options.eta = 1e-2;
    options.num_threads = g_threads;
    options.max_num_iterations = g_max_iterations;
    options.function_tolerance = g_function_tolerance;
    options.gradient_tolerance = 1e-10;
    options.parameter_tolerance = 1e-8;
    options.minimizer_progress_to_stdout = false;
    options.logging_type = ceres::SILENT;
    auto* ordering = new ceres::ParameterBlockOrdering;
    for (int p = 0; p < problem.num_points; ++p) ordering->AddElementToGroup(problem.point(p), 0);
    for (int c = 0; c < problem.num_cameras; ++c) ordering->AddElementToGroup(problem.camera(c), 1);
    options.linear_solver_ordering.reset(ordering);
    ceres::Solver::Summary summary;
    const auto start = Clock::now();
    ceres::Solve(options, &ceres_problem, &summary);
    times.push_back(std::chrono::duration<double>(Clock::now() - start).count());
    // Ceres counts its iteration 0 (the initial evaluation) in iterations.size().
    result.iterations = static_cast<int>(summary.iterations.size()) - 1;
    result.initial_cost = summary.initial_cost;
    result.cg_iterations = 0;
    for (const auto& it : summary.iterations) result.cg_iterations += it.linear_solver_iterations;
    backend::BundleAdjustmentOptions plain;
    backend::LeastSquaresProblem check = backend::make_bundle_adjustment_problem(problem, plain);
    result.final_cost = backend::evaluate_cost(check);
    std::snprintf(result.termination, sizeof(result.termination), "%s",
                  ceres::TerminationTypeToString(summary.termination_type));
  }
  result.seconds = median(times);
  return result;
}

template <class Fn>
RunResult in_child(Fn fn) {
  std::fflush(stdout);
  int pipe_fds[2];
  if (pipe(pipe_fds) != 0) return {};
  const pid_t pid = fork();
  if (pid == 0) {
    close(pipe_fds[0]);
    RunResult result = fn();
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    result.peak_kb = usage.ru_maxrss;
    const ssize_t written = write(pipe_fds[1], &result, sizeof(result));
    _exit(written == static_cast<ssize_t>(sizeof(result)) ? 0 : 1);
  }
  close(pipe_fds[1]);
  RunResult result;
  const ssize_t got = read(pipe_fds[0], &result, sizeof(result));
  close(pipe_fds[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (got != static_cast<ssize_t>(sizeof(result)) || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::fprintf(stderr, "child failed\n");
    return {};
  }
  return result;
}

void print_row(const std::string& name, const char* solver, const RunResult& r, double reference_s,
               double reference_cost) {
  std::printf("| %s | %s | %d | %.3f | %d | %d | %.8e | %.8e | %+.1e | %.1f | %s | %s |\n", name.c_str(), solver,
              g_threads, r.seconds, r.iterations, r.cg_iterations, r.initial_cost, r.final_cost,
              (r.final_cost - reference_cost) / reference_cost, r.peak_kb / 1024.0,
              reference_s > 0 ? (std::to_string(reference_s / r.seconds).substr(0, 4) + "x").c_str() : "-",
              r.termination);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--threads" && i + 1 < argc) {
      g_threads = std::atoi(argv[++i]);
    } else if (arg == "--max-iterations" && i + 1 < argc) {
      g_max_iterations = std::atoi(argv[++i]);
    } else if (arg == "--function-tolerance" && i + 1 < argc) {
      g_function_tolerance = std::atof(argv[++i]);
    } else if (arg == "--repeat" && i + 1 < argc) {
      g_repeat = std::max(1, std::atoi(argv[++i]));
    } else {
      files.push_back(arg);
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: bench_ba_vs_ceres [--threads N] [--max-iterations N] [--function-tolerance F] "
                         "[--repeat N] FILE...\n");
    return 2;
  }
  // CHOLMOD's BLAS (OpenBLAS) gets the same threads in both solvers.
  backend::set_blas_threads(g_threads);
  std::printf("| problem | solver | threads | time s (median of %d) | iterations | CG iterations | initial cost | "
              "final cost | vs Ceres cost | peak MiB | Ceres time / this | termination |\n",
              g_repeat);
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const std::string& path : files) {
    try {
      (void)io::read_bal(path);
    } catch (const io::ParseError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
    const std::string name = std::filesystem::path(path).filename().string();
    const RunResult ceres_sparse = in_child([&] { return run_ceres(path, ceres::SPARSE_SCHUR); });
    const RunResult cairn_sparse = in_child([&] { return run_cairn(path, backend::LinearSolverType::kSparseSchur); });
    const RunResult ceres_iterative = in_child([&] { return run_ceres(path, ceres::ITERATIVE_SCHUR); });
    const RunResult cairn_iterative =
        in_child([&] { return run_cairn(path, backend::LinearSolverType::kIterativeSchur); });
    print_row(name, "Ceres SPARSE_SCHUR", ceres_sparse, 0.0, ceres_sparse.final_cost);
    print_row(name, "cairn sparse_schur", cairn_sparse, ceres_sparse.seconds, ceres_sparse.final_cost);
    print_row(name, "Ceres ITERATIVE_SCHUR", ceres_iterative, 0.0, ceres_iterative.final_cost);
    print_row(name, "cairn iterative_schur", cairn_iterative, ceres_iterative.seconds, ceres_iterative.final_cost);
  }
  return 0;
}
