// cairn's pose-graph back end against Ceres (Debian's libceres-dev 2.1) on the same graphs, from
// the same chordal initial guess, with the same stopping rule, in one run on one machine.
//
// Each solver runs in its own forked process so its peak resident memory (ru_maxrss) is its own.
// Ceres gets the formulation of its examples (ceres-solver examples/slam/pose_graph_2d and
// pose_graph_3d: residual R_a^T (p_b - p_a) - p_ab and the angle difference (2D) or twice the
// vector part of the quaternion error (3D), whitened by the square-root information, automatic
// derivatives, EigenQuaternionManifold), with one change: the translation error is rotated into
// the measured frame, the frame g2o's information matrices refer to. The examples leave it in
// frame a, which on graphs with anisotropic, correlated information (CSAIL, MIT, manhattan)
// minimises a different objective: its optimum scored 38548 against 40.55 in g2o's chi2 on CSAIL.
// SPARSE_NORMAL_CHOLESKY over SuiteSparse, one thread.
// cairn: Levenberg-Marquardt on the log-map residual, CHOLMOD, one thread, chordal
// initialisation included in its time, its default options (undamped start, PCG on the last
// factorisation). Both stop on Ceres' default tolerances (function 1e-6, gradient 1e-10,
// parameter 1e-8, 50 iterations). The final chi2 of both results is evaluated with the same
// function (cairn's geodesic cost). Ceres runs twice: with its default initial trust-region
// radius (1e4), as its users run it; with CHOLMOD's OpenMP regions serialised as cairn runs them;
// and with that and cairn's initial radius (1e16, an undamped start), so the gains from the
// threading, from the damping choice and from the implementation can be told apart.
//
// Every solve is repeated (at least 5 times, until 2 s have passed, at most 200) in its child
// process and the median time is reported: a single cold run mostly measures page faults and
// thread start-up on the small graphs, and the medians of 25 sub-millisecond runs still moved by
// 20 % from one run of this program to the next (tinyGrid3D). Times are printed in ms. Peak memory comes from another child that solves once.
//
// Usage: bench_pose_graph_vs_ceres [--no-reuse-factorization] GRAPH.g2o [GRAPH.g2o ...]

#include <ceres/ceres.h>
#include <omp.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>
#include <cstdio>
#include <filesystem>
#include <string>

#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

using namespace cairn;
using Clock = std::chrono::steady_clock;

struct RunResult {
  double seconds = 0.0;  // median over the repetitions
  int repetitions = 0;
  int factorizations = 0;  // cairn: numeric factorisations
  int iterations = 0;
  double chi2 = 0.0;
  double factor_share = 0.0;  // cairn: share of time spent in numeric factorisation
  long peak_kb = 0;
};

bool g_reuse_factorization = true;

backend::OptimizerOptions cairn_options() {
  backend::OptimizerOptions options;
  options.reuse_factorization = g_reuse_factorization;
  options.function_tolerance = 1e-6;
  options.gradient_tolerance = 1e-10;
  options.parameter_tolerance = 1e-8;
  options.max_iterations = 50;
  options.threads = 1;
  return options;
}

// --- Ceres formulation (after ceres-solver examples/slam) --------------------------------------
struct Error2D {
  Error2D(const core::SE2& measured, const Eigen::Matrix3d& sqrt_information)
      : p_(measured.translation()), theta_(measured.angle()), sqrt_information_(sqrt_information) {}
  template <typename T>
  bool operator()(const T* a, const T* b, T* residual) const {
    using std::cos;
    using std::sin;
    const T c = cos(a[2]);
    const T s = sin(a[2]);
    const T dx = b[0] - a[0];
    const T dy = b[1] - a[1];
    // The example's error R_a^T (p_b - p_a) - p_ab, rotated into the measured frame b by
    // R_ab^T: the frame g2o's information matrices refer to (g2o EdgeSE2::computeError).
    const T ex = c * dx + s * dy - T(p_.x());
    const T ey = -s * dx + c * dy - T(p_.y());
    const double cm = std::cos(theta_);
    const double sm = std::sin(theta_);
    Eigen::Matrix<T, 3, 1> r;
    r[0] = T(cm) * ex + T(sm) * ey;
    r[1] = T(-sm) * ex + T(cm) * ey;
    T angle = b[2] - a[2] - T(theta_);
    // Wrap to (-pi, pi] as the example's NormalizeAngle does.
    const T two_pi(2.0 * M_PI);
    angle = angle - two_pi * ceres::floor((angle + T(M_PI)) / two_pi);
    r[2] = angle;
    Eigen::Map<Eigen::Matrix<T, 3, 1>> out(residual);
    out = sqrt_information_.cast<T>() * r;
    return true;
  }
  Eigen::Vector2d p_;
  double theta_;
  Eigen::Matrix3d sqrt_information_;
};

struct Error3D {
  Error3D(const core::SE3& measured, const Eigen::Matrix<double, 6, 6>& sqrt_information)
      : p_(measured.translation()), q_(measured.unit_quaternion()), sqrt_information_(sqrt_information) {}
  template <typename T>
  bool operator()(const T* pa, const T* qa, const T* pb, const T* qb, T* residual) const {
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_a(pa), p_b(pb);
    const Eigen::Map<const Eigen::Quaternion<T>> q_a(qa), q_b(qb);
    const Eigen::Quaternion<T> q_a_inverse = q_a.conjugate();
    const Eigen::Quaternion<T> q_ab = q_a_inverse * q_b;
    const Eigen::Matrix<T, 3, 1> p_ab = q_a_inverse * (p_b - p_a);
    // The example's errors expressed in the measured frame, as g2o's EdgeSE3 error
    // (Z^-1 T_ab: translation R_Z^T (p_ab - p_Z), rotation q_Z^-1 q_ab), the frame its
    // information matrices refer to.
    const Eigen::Quaternion<T> q_measured_inverse = q_.conjugate().cast<T>();
    const Eigen::Quaternion<T> delta = q_measured_inverse * q_ab;
    Eigen::Matrix<T, 6, 1> r;
    r.template head<3>() = q_measured_inverse * (p_ab - p_.cast<T>());
    r.template tail<3>() = T(2.0) * delta.vec();
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = sqrt_information_.cast<T>() * r;
    return true;
  }
  Eigen::Vector3d p_;
  Eigen::Quaterniond q_;
  Eigen::Matrix<double, 6, 6> sqrt_information_;
};

double g_ceres_radius = 1e4;  // Ceres' default initial_trust_region_radius
// Ceres with CHOLMOD's OpenMP regions serialised, as cairn's SparseCholesky runs them (see
// src/cairn/backend/sparse_cholesky.cpp): the same threading for both, so that this gain of
// cairn's can be told apart from the rest.
bool g_ceres_serial_openmp = false;

ceres::Solver::Options ceres_options() {
  ceres::Solver::Options options;
  options.initial_trust_region_radius = g_ceres_radius;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  options.num_threads = 1;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-6;
  options.gradient_tolerance = 1e-10;
  options.parameter_tolerance = 1e-8;
  return options;
}

RunResult run_ceres(backend::Problem2D problem) {
  std::vector<std::array<double, 3>> x(problem.T_world_pose.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const auto& T = problem.T_world_pose[k];
    x[k] = {T.x(), T.y(), T.angle()};
  }
  const auto start = Clock::now();
  ceres::Problem ceres_problem;
  for (const auto& e : problem.edges) {
    ceres_problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Error2D, 3, 3, 3>(new Error2D(e.T_i_j, e.sqrt_information)),
                                   nullptr, x[static_cast<std::size_t>(e.i)].data(), x[static_cast<std::size_t>(e.j)].data());
  }
  for (std::size_t k = 0; k < x.size(); ++k) {
    if (problem.fixed[k]) ceres_problem.SetParameterBlockConstant(x[k].data());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(ceres_options(), &ceres_problem, &summary);
  RunResult result;
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  if (summary.termination_type == ceres::FAILURE) result.chi2 = std::nan("");
  for (std::size_t k = 0; k < x.size(); ++k) problem.T_world_pose[k] = core::SE2(x[k][0], x[k][1], x[k][2]);
  if (!std::isnan(result.chi2)) result.chi2 = backend::evaluate_cost(problem, cairn_options());
  return result;
}

RunResult run_ceres(backend::Problem3D problem) {
  std::vector<Eigen::Vector3d> p(problem.T_world_pose.size());
  std::vector<Eigen::Quaterniond> q(problem.T_world_pose.size());
  for (std::size_t k = 0; k < p.size(); ++k) {
    p[k] = problem.T_world_pose[k].translation();
    q[k] = problem.T_world_pose[k].unit_quaternion();
  }
  const auto start = Clock::now();
  ceres::Problem ceres_problem;
  ceres::Manifold* quaternion_manifold = new ceres::EigenQuaternionManifold;
  for (const auto& e : problem.edges) {
    const auto i = static_cast<std::size_t>(e.i);
    const auto j = static_cast<std::size_t>(e.j);
    ceres_problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<Error3D, 6, 3, 4, 3, 4>(new Error3D(e.T_i_j, e.sqrt_information)), nullptr,
        p[i].data(), q[i].coeffs().data(), p[j].data(), q[j].coeffs().data());
    ceres_problem.SetManifold(q[i].coeffs().data(), quaternion_manifold);
    ceres_problem.SetManifold(q[j].coeffs().data(), quaternion_manifold);
  }
  for (std::size_t k = 0; k < p.size(); ++k) {
    if (problem.fixed[k]) {
      ceres_problem.SetParameterBlockConstant(p[k].data());
      ceres_problem.SetParameterBlockConstant(q[k].coeffs().data());
    }
  }
  ceres::Solver::Summary summary;
  ceres::Solve(ceres_options(), &ceres_problem, &summary);
  RunResult result;
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;
  if (summary.termination_type == ceres::FAILURE) result.chi2 = std::nan("");
  for (std::size_t k = 0; k < p.size(); ++k) problem.T_world_pose[k] = core::SE3(q[k], p[k]);
  if (!std::isnan(result.chi2)) result.chi2 = backend::evaluate_cost(problem, cairn_options());
  return result;
}

template <class Problem>
RunResult run_cairn(Problem problem, double init_seconds) {
  const auto start = Clock::now();
  const backend::OptimizerSummary summary = backend::optimize(problem, cairn_options());
  RunResult result;
  result.seconds = std::chrono::duration<double>(Clock::now() - start).count() + init_seconds;
  result.iterations = summary.iterations;
  result.chi2 = summary.final_cost;
  result.factor_share = summary.factorize_s / result.seconds;
  for (const auto& it : summary.iteration_log) result.factorizations += it.factorize_s > 0.0 ? 1 : 0;
  return result;
}

// Runs `solve` (returning a RunResult with its time) repeatedly: the median time; the rest (and
// the factorisation share) from the last run, every run being the same computation

template <class Solve>
RunResult repeated(Solve solve) {
  std::vector<double> times;
  RunResult last;
  double total = 0.0;
  while (times.size() < 5 || (total < 2.0 && times.size() < 200)) {
    last = solve();
    times.push_back(last.seconds);
    total += last.seconds;
  }
  std::sort(times.begin(), times.end());
  last.seconds = times[times.size() / 2];
  last.repetitions = static_cast<int>(times.size());
  return last;
}

// Runs `work` in a child process; returns its result and peak RSS.
template <class Work>
RunResult in_child(Work work) {
  int fds[2];
  if (pipe(fds) != 0) std::abort();
  const pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    // One thread means one for CHOLMOD's BLAS too, for every solver: cairn's optimiser limits
    // OpenBLAS to its `threads` (ScopedBlasThreads), Ceres does not, so the child does it for both.
    backend::set_blas_threads(1);
    const RunResult r = work();
    if (write(fds[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) _exit(1);
    _exit(0);
  }
  close(fds[1]);
  RunResult r;
  if (read(fds[0], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) r.seconds = -1.0;
  close(fds[0]);
  int status = 0;
  rusage usage{};
  wait4(pid, &status, 0, &usage);
  r.peak_kb = usage.ru_maxrss;
  return r;
}

template <class Graph>
void compare(const std::string& name, const Graph& graph) {
  // Everything that touches CHOLMOD/BLAS (the chordal initialisation included) runs inside the
  // children: a BLAS thread pool created before fork() deadlocks the child.
  auto initialised = [&](double* init_seconds) {
    auto problem = backend::make_problem(graph, name);
    const auto init_start = Clock::now();
    backend::initialize_chordal(problem);
    *init_seconds = std::chrono::duration<double>(Clock::now() - init_start).count();
    return problem;
  };
  const RunResult start = in_child([&] {
    double seconds = 0.0;
    const auto problem = initialised(&seconds);
    RunResult r;
    r.chi2 = backend::evaluate_cost(problem, cairn_options());
    r.iterations = static_cast<int>(problem.ids.size());
    return r;
  });
  // Time: the median of repeated solves in one child. Memory: the peak RSS of a child that
  // solves once (repetitions fragment the heap and would inflate it).
  auto timed_and_measured = [&](auto solve) {
    RunResult timed = in_child([&] { return repeated(solve); });
    timed.peak_kb = in_child(solve).peak_kb;
    return timed;
  };
  const RunResult c = timed_and_measured([&] {
    double seconds = 0.0;
    const auto problem = initialised(&seconds);
    return run_cairn(problem, seconds);
  });
  auto ceres_with = [&](double radius, bool serial_openmp) {
    g_ceres_radius = radius;
    g_ceres_serial_openmp = serial_openmp;
    return timed_and_measured([&] {
      if (g_ceres_serial_openmp) omp_set_max_active_levels(0);  // in the child, before CHOLMOD runs
      double seconds = 0.0;
      return run_ceres(initialised(&seconds));
    });
  };
  const RunResult r = ceres_with(1e4, false);  // as Ceres' users run it
  const RunResult s = ceres_with(1e4, true);   // + cairn's threading
  const RunResult u = ceres_with(1e16, true);  // + cairn's undamped start
  std::printf("| %-28s | %6d | %12.6g | %8.4g | %3d | %2d | %12.6g | %6.1f | %4.0f%% | %8.4g | %3d | %12.6g | %6.1f | %5.1fx | %8.4g | %5.1fx | %8.4g | %3d | %12.6g | %5.1fx |\n",
              name.c_str(), start.iterations, start.chi2, 1e3 * c.seconds, c.iterations, c.factorizations, c.chi2,
              c.peak_kb / 1024.0, 100.0 * c.factor_share, 1e3 * r.seconds, r.iterations, r.chi2, r.peak_kb / 1024.0,
              r.seconds / c.seconds, 1e3 * s.seconds, s.seconds / c.seconds, 1e3 * u.seconds, u.iterations, u.chi2,
              u.seconds / c.seconds);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  int first = 1;
  if (argc > 1 && std::string(argv[1]) == "--no-reuse-factorization") {
    g_reuse_factorization = false;  // cairn's OptimizerOptions::reuse_factorization
    first = 2;
  }
  if (argc <= first) {
    std::fprintf(stderr, "usage: %s [--no-reuse-factorization] GRAPH.g2o [GRAPH.g2o ...]\n", argv[0]);
    return 2;
  }
  std::printf("| graph | poses | chi2 at chordal start | cairn ms (incl. init) | it | fact | cairn chi2 | cairn MiB | factorisation share | Ceres ms | it | Ceres chi2 | Ceres MiB | Ceres/cairn time | Ceres serial-OpenMP ms | Ceres serial-OpenMP/cairn | Ceres serial-OpenMP r=1e16 ms | it | chi2 | Ceres serial-OpenMP r=1e16/cairn |\n");
  std::printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  for (int k = first; k < argc; ++k) {
    try {
      const io::GraphFile file = io::read_graph(argv[k]);
      const std::string name = std::filesystem::path(argv[k]).filename().string();
      std::visit([&](const auto& graph) { compare(name, graph); }, file.graph);
    } catch (const io::ParseError& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
  }
  return 0;
}
