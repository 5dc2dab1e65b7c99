// `cairn optimize IN -o OUT`: pose-graph optimisation with a chosen initialisation, solver,
// objective and robust cost (backend/pose_graph_job.hpp); progress per iteration on stderr; a
// JSON report on request. Also `cairn corrupt`, which appends false loop closures to a graph.

#include <cstdio>
#include <optional>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cairn/backend/outliers.hpp"
#include "cairn/backend/pose_graph_job.hpp"
#include "cairn/backend/pose_graph_report.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/optimize_flags.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/file_format.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {
namespace {

// The terminal lines of each stage of the job, as it finishes.
void print_stage(const OptimizeFlags& flags, const backend::PoseGraphJobOptions& job, backend::PoseGraphJobStage stage,
                 const backend::PoseGraphJobSummary& s) {
  using Stage = backend::PoseGraphJobStage;
  if (stage == Stage::kInitialized && !flags.quiet) {
    std::fprintf(stderr, "%zu poses, %zu edges, %s init (%.3f s); %s solver, %s objective, robust %s\n", s.poses, s.edges,
                 std::string(backend::to_string(s.initialization)).c_str(), s.initialization_summary.total_s,
                 std::string(backend::to_string(job.solver.algorithm)).c_str(),
                 std::string(backend::to_string(job.solver.objective)).c_str(), flags.robust.c_str());
    std::fprintf(stderr, "%5s %16s %12s %10s %10s %10s %4s %6s %9s\n", "iter", "cost", "change", "max|grad|", "step",
                 "lambda", "ok", "linsol", "time[s]");
  }
  if (stage == Stage::kSolved && s.gnc) {
    const backend::GncSummary& gnc = *s.gnc;
    std::printf("GNC: %d outer iterations, %d solves, %d inner iterations (%d factorisations), %.3f s: %s; rejected "
                "%zu of %zu loop closures (threshold chi2 %.3f",
                gnc.outer_iterations, gnc.solves, gnc.inner_iterations, gnc.factorizations, gnc.total_s,
                gnc.message.c_str(), gnc.rejected_edges.size(), s.loop_closures, gnc.threshold_chi2);
    if (gnc.short_loop_variance_factor > 0.0) {
      std::printf("; noise variance %.3g x the stated from short loop closures", gnc.short_loop_variance_factor);
    }
    if (gnc.noise_variance_factor > 0.0) {
      std::printf("; %.3g x from the accepted edges%s", gnc.noise_variance_factor,
                  gnc.regraduated ? ", graduated again" : "");
    }
    std::printf("; %d of %d consistent groups and %d edges by their innovation readmitted; %d rejected by their "
                "leave-one-out innovation)\n",
                gnc.groups_readmitted, gnc.groups_tried, gnc.readmitted_by_innovation, gnc.rejected_by_leave_one_out);
    if (gnc.restarted) std::printf("GNC: restarting from the chordal relaxation of the accepted edges lowered the TLS cost\n");
    std::printf("GNC time: graduation %.3f s, reclassification %.3f s, restart %.3f s, groups %.3f s, innovation test "
                "%.3f s\n",
                gnc.graduation_s, gnc.reclassify_s, gnc.restart_s, gnc.groups_s, gnc.innovation_s);
  }
  // Stopped by SIGINT/SIGTERM: the poses of the last accepted step are written, marked interrupted.
  if (stage == Stage::kSolved && s.stopped_during_solve) {
    std::fprintf(stderr, "cairn optimize: interrupted by %s after %d iterations: writing the current estimate\n",
                 interrupt_signal_name(), s.solve.iterations);
  }
  if (stage == Stage::kCertified) {
    if (flags.objective != "chordal") {
      warn("--certify proves optimality for SE-Sync's chordal objective; this solve minimised the geodesic one, "
           "whose minimiser is not the chordal one's (use --objective chordal)");
    }
    if (flags.robust != "none") {
      warn("--certify with a robust cost: the certificate is that of least squares over all edges (the rejected "
           "or down-weighted ones included), so it is reported but the staircase is not climbed");
    }
    for (const auto& level : s.staircase->levels) {
      std::printf("certificate at rank %d (%d iterations, %.3f s, %d factorisations): %s\n", level.rank, level.iterations,
                  level.certificate.time_s, level.certificate.factorizations, level.certificate.message.c_str());
    }
    if (s.staircase->levels.size() > 1) std::printf("staircase (%.3f s): %s\n", s.staircase->time_s, s.staircase->message.c_str());
  }
  if (stage == Stage::kPolished && s.polish_status == backend::PolishStatus::kSkippedNotChordal) {
    warn("--polish-geodesic polishes a chordal solve; this solve minimised the geodesic objective already");
  } else if (stage == Stage::kPolished && s.polish_status == backend::PolishStatus::kSkippedAfterGnc) {
    warn("--polish-geodesic after GNC is not done: the polish would need GNC's final weights");
  } else if (stage == Stage::kPolished && s.polish) {
    std::printf("geodesic polish from the chordal %s: chi2 %.10g -> %.10g in %d iterations (%.3f s): %s\n",
                s.staircase && s.staircase->certified ? "certified optimum" : "solution", s.polish->initial_cost,
                s.polish->final_cost, s.polish->iterations, s.polish->total_s,
                std::string(backend::to_string(s.polish->termination)).c_str());
  }
}

template <class Group>
int run_optimize(const OptimizeFlags& flags, backend::PoseGraphJobOptions job, const io::GraphFile& file,
                 const io::PoseGraphT<Group>& graph, io::GraphFormat out_format) {
  job.solver.should_stop = stop_on_signal();
  if (!flags.quiet) {
    job.solver.progress = [](const backend::IterationSummary& it) {
      // linsol: "chol" = factorised this iteration, "cg N" = N PCG iterations on the last factor.
      const std::string linear_solve = it.factorize_s > 0.0 ? "chol" : "cg " + std::to_string(it.cg_iterations);
      std::fprintf(stderr, "%5d %16.10g %12.4g %10.3g %10.3g %10.3g %4s %6s %9.4f\n", it.iteration, it.cost,
                   it.cost_change, it.gradient_max_norm, it.step_norm, it.lambda, it.step_accepted ? "yes" : "no",
                   linear_solve.c_str(), it.iteration_s);
    };
  }
  job.stage_finished = [&flags, &job](backend::PoseGraphJobStage stage, const backend::PoseGraphJobSummary& s) {
    print_stage(flags, job, stage, s);
  };
  const backend::PoseGraphJobResult<Group> result = backend::run_pose_graph_job(graph, flags.input, job);
  const backend::PoseGraphJobSummary& s = result.summary;
  // A failed solve is a failed command: nothing is written and no existing output is replaced.
  if (!s.is_solution_usable()) {
    std::printf("%s\n", s.solve.brief_report().c_str());
    throw io::ParseError(flags.input, 0, "the solve failed (" + s.solve.message + "); nothing was written");
  }
  // The graph and the report form one set: both are produced before either replaces a file.
  io::OutputFile graph_file(flags.output);
  std::vector<std::string> warnings;
  graph_file.write([&](std::ostream& out) { warnings = io::write_graph(out, io::PoseGraph(result.optimized), out_format); });
  for (const auto& w : warnings) warn(w);

  std::printf("%s\n", s.solve.brief_report().c_str());
  std::printf("time: %.3f s total (initialisation %.3f s, analysis %.3f s, linearisation %.3f s, factorisation %.3f s, solve %.3f s)\n",
              s.solve.total_s + s.initialization_summary.total_s, s.initialization_summary.total_s, s.solve.analyze_s,
              s.solve.linearize_s, s.solve.factorize_s, s.solve.solve_s);
  std::printf("final chi2 (geodesic) %.10g, SE-Sync objective f (chordal) %.10g\n", s.final_chi2_geodesic, s.final_f_chordal);

  std::optional<io::OutputFile> report_file;
  if (!flags.report.empty()) {
    if (!flags.covariance_ids.empty() && !s.covariances) {
      warn("marginal covariances unavailable: J^T J is not positive definite at the solution");
    }
    nlohmann::json j = backend::pose_graph_report_json(s, job);
    j["input"] = flags.input;
    j["output"] = flags.output;
    j["read_warnings"] = file.report.warnings;
    if (s.interrupted) j["interruption"] = {{"signal", interrupt_signal_name()}};
    report_file.emplace(flags.report);
    report_file->write([&](std::ostream& out) { out << io::json_text(j); });
  }
  graph_file.commit();
  if (report_file) report_file->commit();
  std::printf("wrote %s%s%s\n", io::output_display_name(flags.output).c_str(),
              flags.report.empty() ? "" : (" and " + io::output_display_name(flags.report)).c_str(),
              s.interrupted ? " (interrupted: the estimate so far)" : "");
  if (s.interrupted) return interrupted_exit_status();
  return 0;
}

int optimize_command(const OptimizeFlags& flags) {
  check_optimize_flags(flags);
  const backend::PoseGraphJobOptions job = optimize_job_options(flags);
  if (std::string problems; !job.is_valid(&problems)) throw io::ParseError("cairn optimize", 0, problems);
  if (io::is_standard_output(flags.output) && !flags.report.empty() && io::is_standard_output(flags.report)) {
    throw io::ParseError(flags.report, 0, "the graph already goes to standard output: give --report a file");
  }
  io::check_distinct_outputs({{"--output", flags.output}, {"--report", flags.report}});
  claim_standard_output(flags.output);
  claim_standard_output(flags.report);
  io::GraphReadOptions options = flags.graph.options();
  if (!flags.format.empty()) {
    const auto format = io::graph_format_from_name(flags.format);
    if (!format) throw io::ParseError(flags.input, 0, "--format must be g2o or toro, found '" + flags.format + "'");
    options.format = format;
  }
  // SE-Sync's objective reads only the diagonal blocks: keep the matrices as written.
  if (flags.objective == "chordal" && !flags.graph.strict) options.information_policy = io::InformationPolicy::kKeep;
  const io::GraphFile file = io::read_graph(flags.input, options);
  for (const auto& w : file.report.warnings) warn(w);
  const auto out_format = io::format_from_extension(flags.output);
  io::GraphFormat graph_format = io::GraphFormat::kG2o;
  if (out_format == io::FileFormat::kToro) graph_format = io::GraphFormat::kToro;
  else if (out_format && out_format != io::FileFormat::kG2o) {
    throw io::ParseError(flags.output, 0, "the output of optimize is a pose graph: expected .g2o or .graph");
  }
  if (const auto* g2 = std::get_if<io::PoseGraph2D>(&file.graph)) return run_optimize(flags, job, file, *g2, graph_format);
  return run_optimize(flags, job, file, std::get<io::PoseGraph3D>(file.graph), graph_format);
}

struct CorruptFlags {
  std::string input;
  std::string output;
  int outliers = 0;
  std::uint64_t seed = 1;
  double extent_m = 10.0;
  GraphReadFlags graph;
};

int corrupt_command(const CorruptFlags& flags) {
  claim_standard_output(flags.output);
  const io::GraphFile file = io::read_graph(flags.input, flags.graph.options());
  for (const auto& w : file.report.warnings) warn(w);
  backend::OutlierOptions options;
  options.count = flags.outliers;
  options.seed = flags.seed;
  options.translation_extent_m = flags.extent_m;
  io::PoseGraph graph = file.graph;
  const std::string problems = std::visit([&](const auto& g) { return backend::outlier_request_problems(g, options); }, graph);
  if (!problems.empty()) throw io::ParseError(flags.input, 0, problems);
  std::visit([&](auto& g) { backend::add_false_loop_closures(g, options); }, graph);
  const auto out_format = io::format_from_extension(flags.output) == io::FileFormat::kToro ? io::GraphFormat::kToro
                                                                                              : io::GraphFormat::kG2o;
  for (const auto& w : io::write_graph(flags.output, graph, out_format)) warn(w);
  std::printf("wrote %s: %d false loop closures appended (seed %llu)\n", io::output_display_name(flags.output).c_str(), flags.outliers,
              static_cast<unsigned long long>(flags.seed));
  return 0;
}

}  // namespace

Runner register_corrupt(CLI::App& app) {
  auto flags = std::make_shared<CorruptFlags>();
  app.add_option("IN", flags->input, "Pose graph (.g2o, .graph)")->required();
  app.add_option("-o,--output", flags->output, "Corrupted graph")->required();
  app.add_option("--outliers", flags->outliers, "Number of false loop closures to append")
      ->required()
      ->check(checks::count_or_zero(2000000000));
  app.add_option("--seed", flags->seed, "Random seed")->capture_default_str();
  app.add_option("--extent", flags->extent_m, "False translations uniform in [-extent, extent] m per axis")
      ->check(checks::positive())
      ->capture_default_str();
  flags->graph.add_to(app);
  return [flags]() { return corrupt_command(*flags); };
}

Runner register_optimize(CLI::App& app) {
  auto flags = std::make_shared<OptimizeFlags>();
  add_optimize_flags(app, *flags);
  return [flags]() { return optimize_command(*flags); };
}

}  // namespace cairn::cli
