// `cairn ba FILE [-o OUT] [--report R.json]`: bundle adjustment of a BAL problem on the
// least-squares engine (backend/bundle_adjustment.hpp, docs/backend.md).

#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "cairn/backend/bundle_adjustment.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/io/bal.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {
namespace {

struct BaFlags {
  std::string input;
  std::string output;
  std::string report;
  std::string linear_solver = "sparse_schur";
  std::string loss = "none";
  double loss_scale_px = 1.0;
  int max_iterations = 50;
  double function_tolerance = 1e-6;
  int threads = 0;
  bool quiet = false;
};

backend::LinearSolverType solver_from_name(const std::string& name) {
  if (name == "sparse_normal_cholesky") return backend::LinearSolverType::kSparseNormalCholesky;
  if (name == "iterative_schur") return backend::LinearSolverType::kIterativeSchur;
  return backend::LinearSolverType::kSparseSchur;
}

backend::RobustKernel kernel_from_name(const std::string& name) {
  if (name == "huber") return backend::RobustKernel::kHuber;
  if (name == "cauchy") return backend::RobustKernel::kCauchy;
  return backend::RobustKernel::kNone;
}

nlohmann::json summary_json(const backend::LeastSquaresSummary& s, const io::BalProblem& problem,
                            std::size_t behind_at_start) {
  nlohmann::json iterations = nlohmann::json::array();
  for (const auto& it : s.iteration_log) {
    iterations.push_back({{"iteration", it.iteration},
                          {"cost", it.cost},
                          {"cost_change", it.cost_change},
                          {"gradient_max_norm", it.gradient_max_norm},
                          {"step_norm", it.step_norm},
                          {"relative_decrease", it.relative_decrease},
                          {"trust_region_radius", it.trust_region_radius},
                          {"cg_iterations", it.cg_iterations},
                          {"accepted", it.step_accepted},
                          {"time_s", it.iteration_s}});
  }
  return {{"cameras", problem.num_cameras},
          {"points", problem.num_points},
          {"observations", problem.observations.size()},
          {"observations_behind_camera_at_start", behind_at_start},
          {"linear_solver", std::string(backend::to_string(s.linear_solver))},
          {"threads", s.threads},
          {"termination", std::string(backend::to_string(s.termination))},
          {"message", s.message},
          {"interrupted", s.termination == backend::LeastSquaresTermination::kInterrupted},
          {"initial_cost", s.initial_cost},
          {"final_cost", s.final_cost},
          {"cost_convention", "1/2 sum of squared reprojection errors (px^2), as Ceres"},
          {"iterations", s.iterations},
          {"successful_iterations", s.successful_iterations},
          {"cg_iterations", s.cg_iterations},
          {"factorizations", s.factorizations},
          {"reused_factorizations", s.reused_factorizations},
          {"reduced_size", s.reduced_size},
          {"factor_nonzeros", s.factor_nonzeros},
          {"time_s",
           {{"jacobian_evaluation", s.jacobian_s},
            {"residual_evaluation", s.residual_s},
            {"linear_system", s.linear_system_s},
            {"linear_solve", s.linear_solve_s},
            {"analysis", s.analyze_s},
            {"total", s.total_s}}},
          {"iteration_log", iterations}};
}

int ba_command(const BaFlags& flags) {
  if (!flags.output.empty() && !flags.report.empty() && io::is_standard_output(flags.output) &&
      io::is_standard_output(flags.report)) {
    throw io::ParseError(flags.report, 0, "the problem already goes to standard output: give --report a file");
  }
  io::check_distinct_outputs({{"--output", flags.output}, {"--report", flags.report}});
  claim_standard_output(flags.output);
  claim_standard_output(flags.report);
  io::BalProblem problem = io::read_bal(flags.input);
  const std::string input_name = flags.input == "-" ? "standard input" : flags.input;
  if (const long long k = io::first_observation_in_camera_plane(problem); k >= 0) {
    const io::BalObservation& o = problem.observations[static_cast<std::size_t>(k)];
    throw io::ParseError(input_name, 0,
                         "observation " + std::to_string(k + 1) + " (camera " + std::to_string(o.camera) + ", point " +
                             std::to_string(o.point) +
                             "): the point lies in the camera's plane (P_z = 0), where BAL's projection is undefined");
  }
  const std::size_t behind = io::count_points_behind_camera(problem);
  std::printf("%s: %d cameras, %d points, %zu observations", input_name.c_str(),
              problem.num_cameras, problem.num_points, problem.observations.size());
  if (behind > 0) std::printf(" (%zu with the point behind its camera: kept, as the BAL model defines them)", behind);
  std::printf("\n");

  backend::BundleAdjustmentOptions options;
  options.solver.linear_solver = solver_from_name(flags.linear_solver);
  options.solver.max_iterations = flags.max_iterations;
  options.solver.function_tolerance = flags.function_tolerance;
  options.solver.threads = flags.threads;
  options.solver.should_stop = stop_on_signal();
  options.kernel = kernel_from_name(flags.loss);
  options.kernel_scale_px = flags.loss_scale_px;
  if (!flags.quiet) {
    options.solver.progress = [](const backend::LeastSquaresIteration& it) {
      std::fprintf(stderr, "  iter %3d  cost %.6e  |g| %.2e  step %.2e  radius %.2e  %s%s  %.3f s\n", it.iteration,
                   it.cost, it.gradient_max_norm, it.step_norm, it.trust_region_radius,
                   it.step_accepted ? "accepted" : "rejected",
                   it.cg_iterations > 0 ? (" cg " + std::to_string(it.cg_iterations)).c_str() : "", it.iteration_s);
    };
  }
  std::string why;
  if (!options.solver.is_valid(&why)) throw std::invalid_argument("invalid options: " + why);
  const backend::LeastSquaresSummary summary = backend::bundle_adjust(problem, options);
  std::printf("%s\n", summary.brief_report().c_str());
  std::printf("time: jacobians %.3f s, residuals %.3f s, linear system %.3f s, solve %.3f s, total %.3f s (%d threads)\n",
              summary.jacobian_s, summary.residual_s, summary.linear_system_s, summary.linear_solve_s, summary.total_s,
              summary.threads);
  const bool interrupted = summary.termination == backend::LeastSquaresTermination::kInterrupted;
  // A failed solve is a failed command: nothing is written and no existing output is replaced.
  if (!summary.is_solution_usable() && !interrupted) {
    std::fprintf(stderr, "cairn: error: %s: bundle adjustment failed: %s; nothing was written\n", input_name.c_str(),
                 summary.message.c_str());
    return 1;
  }
  // The refined problem and the report are one result: both are produced before either
  // replaces a file.
  const nlohmann::json j = flags.report.empty() ? nlohmann::json() : summary_json(summary, problem, behind);
  io::write_outputs({{flags.output, [&](std::ostream& out) { io::write_bal(out, problem); }},
                     {flags.report, [&](std::ostream& out) { out << io::json_text(j); }}});
  if (!flags.output.empty() || !flags.report.empty()) {
    std::string written;
    for (const std::string* path : {&flags.output, &flags.report}) {
      if (!path->empty()) written += (written.empty() ? "" : " and ") + io::output_display_name(*path);
    }
    std::printf("wrote %s%s\n", written.c_str(), interrupted ? " (interrupted: the estimate so far)" : "");
  }
  if (interrupted) return interrupted_exit_status();
  return 0;
}

}  // namespace

Runner register_ba(CLI::App& app) {
  auto flags = std::make_shared<BaFlags>();
  app.add_option("IN", flags->input, "BAL problem (.txt, .txt.bz2, .txt.gz; - = standard input)")->required();
  app.add_option("-o,--output", flags->output, "Refined problem in the BAL format (- = standard output)");
  app.add_option("--report", flags->report, "JSON report: costs, iterations, per-phase times");
  app.add_option("--linear-solver", flags->linear_solver,
                 "sparse_schur (points eliminated, CHOLMOD), iterative_schur (PCG with Schur-Jacobi), "
                 "sparse_normal_cholesky (no elimination)")
      ->check(CLI::IsMember({"sparse_schur", "iterative_schur", "sparse_normal_cholesky"}))
      ->capture_default_str();
  app.add_option("--loss", flags->loss, "Robust kernel on the reprojection error: none, huber, cauchy")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}))
      ->capture_default_str();
  app.add_option("--loss-scale", flags->loss_scale_px, "Kernel scale in pixels")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_option("--max-iterations", flags->max_iterations, "LM iterations (Ceres' max_num_iterations)")
      ->check(checks::count())
      ->capture_default_str();
  app.add_option("--function-tolerance", flags->function_tolerance,
                 "Stop when |cost change| / cost falls below this (Ceres' default)")
      ->check(checks::non_negative())
      ->capture_default_str();
  app.add_option("--threads", flags->threads, "Threads (0 = all cores; more than the machine has are clamped)")->transform(checks::threads())->capture_default_str();
  app.add_flag("-q,--quiet", flags->quiet, "No per-iteration lines");
  return [flags]() { return ba_command(*flags); };
}

}  // namespace cairn::cli
