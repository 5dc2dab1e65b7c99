// `cairn optimize IN -o OUT`: pose-graph optimisation with a chosen initialisation, solver,
// objective and robust cost; progress per iteration on stderr; a JSON report on request.

#include <cmath>
#include <cstdio>
#include <optional>
#include <iostream>
#include <nlohmann/json.hpp>

#include "cairn/backend/certificate.hpp"
#include "cairn/backend/covariance.hpp"
#include "cairn/backend/gnc.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/backend/outliers.hpp"
#include "cairn/backend/staircase.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/file_format.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {
namespace {

struct OptimizeFlags {
  std::string input;
  std::string output;
  std::string format;
  std::string init = "auto";
  std::string solver = "lm";
  std::string objective = "geodesic";
  std::string robust = "none";
  double robust_scale = 1.0;
  double gnc_threshold = 0.0;
  int gnc_inner_iterations = 15;
  double gnc_mu_factor = 1.4;
  double gnc_final_factor = backend::GncOptions{}.final_threshold_factor;
  std::vector<std::int64_t> covariance_ids;
  int threads = 0;
  int max_iterations = 100;
  double initial_radius = backend::OptimizerOptions{}.initial_trust_region_radius;
  bool exact_steps = false;
  bool gauss_newton_hessian = false;
  bool certify = false;
  bool polish_geodesic = false;
  double certify_tolerance = backend::CertificateOptions{}.eigenvalue_tolerance;
  std::string report;
  bool quiet = false;
  GraphReadFlags graph;
  const CLI::App* command = nullptr;  // which flags were given
};

// Flags that would do nothing with the others given are refused before any work.
void check_combinations(const OptimizeFlags& f) {
  auto given = [&](const std::string& name) { return f.command != nullptr && f.command->count(name) > 0; };
  if (!f.covariance_ids.empty() && f.report.empty()) {
    throw UsageError("--covariance writes marginal covariances into the report: add --report FILE");
  }
  if (f.robust != "gnc") {
    for (const std::string name : {"--gnc-threshold", "--gnc-mu-factor", "--gnc-final-factor", "--gnc-inner-iterations"}) {
      if (given(name)) throw UsageError(name + " tunes --robust gnc, and this run uses --robust " + f.robust);
    }
  }
  if ((f.robust == "none" || f.robust == "gnc") && given("--robust-scale")) {
    throw UsageError("--robust-scale is the scale of a kernel (huber, cauchy, geman-mcclure), and --robust " + f.robust +
                     " has none");
  }
  if (f.exact_steps && f.solver != "lm") {
    throw UsageError("--exact-steps concerns Levenberg-Marquardt's steps on an earlier factorisation, and --solver " +
                     f.solver + " factorises every step already");
  }
  if (f.gauss_newton_hessian && f.objective != "chordal") {
    throw UsageError("--gauss-newton-hessian concerns --objective chordal only (the geodesic objective always uses J^T J)");
  }
  if (given("--certify-tolerance") && !f.certify) throw UsageError("--certify-tolerance needs --certify");
}

nlohmann::json summary_json(const backend::OptimizerSummary& s) {
  nlohmann::json j;
  j["termination"] = backend::to_string(s.termination);
  j["message"] = s.message;
  j["initial_cost"] = s.initial_cost;
  j["final_cost"] = s.final_cost;
  j["iterations"] = s.iterations;
  j["successful_iterations"] = s.successful_iterations;
  j["free_poses"] = s.free_poses;
  j["edges"] = s.edges;
  j["factor_nonzeros"] = s.factor_nonzeros;
  j["time_s"] = {{"total", s.total_s},   {"analyze", s.analyze_s}, {"linearize", s.linearize_s},
                 {"factorize", s.factorize_s}, {"solve", s.solve_s}};
  nlohmann::json log = nlohmann::json::array();
  for (const auto& it : s.iteration_log) {
    log.push_back({{"iteration", it.iteration},
                   {"cost", it.cost},
                   {"cost_change", it.cost_change},
                   {"gradient_max_norm", it.gradient_max_norm},
                   {"step_norm", it.step_norm},
                   {"relative_decrease", it.relative_decrease},
                   {"lambda_or_radius", it.lambda},
                   {"accepted", it.step_accepted},
                   {"cg_iterations", it.cg_iterations},
                   {"linearize_s", it.linearize_s},
                   {"factorize_s", it.factorize_s},
                   {"solve_s", it.solve_s},
                   {"iteration_s", it.iteration_s}});
  }
  j["iteration_log"] = log;
  return j;
}

template <class Group>
int run_optimize(const OptimizeFlags& flags, const io::GraphFile& file, const io::PoseGraphT<Group>& graph,
                 io::GraphFormat out_format) {
  // --threads holds for CHOLMOD's BLAS in every stage (solve, GNC, certificate, staircase).
  const backend::ScopedBlasThreads blas(flags.threads);
  backend::PoseGraphProblem<Group> problem = backend::make_problem(graph, flags.input);

  backend::Initialization init = backend::Initialization::kFile;
  if (flags.init == "auto" && flags.robust == "gnc") {
    init = backend::Initialization::kOdometry;  // no loop closure, right or wrong, bends the start
  } else if (flags.init == "auto") {
    init = problem.has_initial_guess ? backend::Initialization::kFile : backend::Initialization::kChordal;
  } else if (flags.init == "odometry") {
    init = backend::Initialization::kOdometry;
  } else if (flags.init == "chordal") {
    init = backend::Initialization::kChordal;
  } else if (!problem.has_initial_guess) {
    throw io::ParseError(flags.input, 0, "--init file needs VERTEX lines, and the file has none: use --init chordal or odometry");
  }
  backend::InitializationSummary init_summary;
  if (init == backend::Initialization::kOdometry) init_summary = backend::initialize_odometry(problem);
  if (init == backend::Initialization::kChordal) init_summary = backend::initialize_chordal(problem);

  backend::OptimizerOptions options;
  options.algorithm = flags.solver == "gn"       ? backend::Algorithm::kGaussNewton
                      : flags.solver == "dogleg" ? backend::Algorithm::kDogleg
                                                 : backend::Algorithm::kLevenbergMarquardt;
  options.objective = flags.objective == "chordal" ? backend::Objective::kChordal : backend::Objective::kGeodesic;
  options.kernel = flags.robust == "huber"            ? backend::RobustKernel::kHuber
                   : flags.robust == "cauchy"         ? backend::RobustKernel::kCauchy
                   : flags.robust == "geman-mcclure" ? backend::RobustKernel::kGemanMcClure
                                                      : backend::RobustKernel::kNone;
  options.kernel_scale = flags.robust_scale;
  options.threads = flags.threads;
  options.max_iterations = flags.max_iterations;
  options.initial_trust_region_radius = flags.initial_radius;
  options.reuse_factorization = !flags.exact_steps;
  options.should_stop = stop_on_signal();
  options.exact_chordal_hessian = !flags.gauss_newton_hessian;
  std::string invalid;
  if (!options.is_valid(&invalid)) throw io::ParseError("cairn optimize", 0, invalid);
  if (!flags.quiet) {
    std::fprintf(stderr, "%zu poses, %zu edges, %s init (%.3f s); %s solver, %s objective, robust %s\n",
                 problem.ids.size(), problem.edges.size(), std::string(backend::to_string(init)).c_str(),
                 init_summary.total_s, std::string(backend::to_string(options.algorithm)).c_str(),
                 std::string(backend::to_string(options.objective)).c_str(), flags.robust.c_str());
    std::fprintf(stderr, "%5s %16s %12s %10s %10s %10s %4s %6s %9s\n", "iter", "cost", "change", "max|grad|", "step",
                 "lambda", "ok", "linsol", "time[s]");
    options.progress = [](const backend::IterationSummary& it) {
      // linsol: "chol" = factorised this iteration, "cg N" = N PCG iterations on the last factor.
      const std::string linear_solve = it.factorize_s > 0.0 ? "chol" : "cg " + std::to_string(it.cg_iterations);
      std::fprintf(stderr, "%5d %16.10g %12.4g %10.3g %10.3g %10.3g %4s %6s %9.4f\n", it.iteration, it.cost,
                   it.cost_change, it.gradient_max_norm, it.step_norm, it.lambda, it.step_accepted ? "yes" : "no",
                   linear_solve.c_str(), it.iteration_s);
    };
  }
  const double initial_cost = backend::evaluate_cost(problem, options);
  if (!std::isfinite(initial_cost)) {
    const long long e = backend::first_nonfinite_edge(problem, options);
    if (e >= 0) {
      const auto& edge = problem.edges[static_cast<std::size_t>(e)];
      throw io::ParseError(flags.input, edge.line,
                           "the cost of the edge from pose " + std::to_string(problem.ids[static_cast<std::size_t>(edge.i)]) +
                               " to pose " + std::to_string(problem.ids[static_cast<std::size_t>(edge.j)]) +
                               " is not finite at the starting poses (" + std::string(backend::to_string(init)) +
                               " initialisation): a measurement or pose too large to evaluate; nothing was written");
    }
    throw io::ParseError(flags.input, 0, "the starting cost is not finite; nothing was written");
  }
  // --covariance names poses of this graph: checked before the solve, not after it.
  for (const auto id : flags.covariance_ids) {
    if (problem.index_of(id) < 0) throw io::ParseError(flags.input, 0, "--covariance: pose " + std::to_string(id) + " is not in the graph");
  }
  backend::OptimizerSummary summary;
  backend::GncSummary gnc;
  const bool use_gnc = flags.robust == "gnc";
  if (use_gnc) {
    backend::GncOptions gnc_options;
    gnc_options.inner = options;
    gnc_options.inner.progress = nullptr;
    gnc_options.inlier_threshold_chi2 = flags.gnc_threshold;
    gnc_options.iterations_per_outer = flags.gnc_inner_iterations;
    gnc_options.mu_factor = flags.gnc_mu_factor;
    gnc_options.final_threshold_factor = flags.gnc_final_factor;
    gnc = backend::optimize_gnc(problem, gnc_options);
    summary = gnc.final_solve;
    std::size_t loop_closures = 0;
    for (const auto& e : problem.edges) loop_closures += e.kind == backend::EdgeKind::kLoopClosure;
    std::printf("GNC: %d outer iterations, %d solves, %d inner iterations (%d factorisations), %.3f s: %s; rejected "
                "%zu of %zu loop closures (threshold chi2 %.3f",
                gnc.outer_iterations, gnc.solves, gnc.inner_iterations, gnc.factorizations, gnc.total_s,
                gnc.message.c_str(), gnc.rejected_edges.size(), loop_closures, gnc.threshold_chi2);
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
  } else {
    summary = backend::optimize(problem, options);
  }

  // Stopped by SIGINT/SIGTERM (between iterations, or before the first): the poses of the last
  // accepted step are a complete, consistent graph; it is written and marked interrupted.
  const bool stopped = interrupted() || summary.termination == backend::TerminationType::kInterrupted ||
                       (use_gnc && gnc.interrupted);
  if (stopped) {
    std::fprintf(stderr, "cairn optimize: interrupted by %s after %d iterations: writing the current estimate\n",
                 interrupt_signal_name(), summary.iterations);
  }
  // The certificate, and the Riemannian staircase when it fails (which may replace the poses by
  // a better, certified set): before the graph is written.
  std::optional<backend::StaircaseSummary> staircase;
  if (flags.certify && !stopped) {
    if (options.objective != backend::Objective::kChordal) {
      warn("--certify proves optimality for SE-Sync's chordal objective; this solve minimised the geodesic one, "
           "whose minimiser is not the chordal one's (use --objective chordal)");
    }
    backend::StaircaseOptions staircase_options;
    staircase_options.certificate.eigenvalue_tolerance = flags.certify_tolerance;
    staircase_options.polish = options;
    staircase_options.polish.progress = nullptr;
    // The certificate speaks of least squares over every edge: it may say whether a plain
    // chordal solve is optimal, but must not replace a robust one (GNC, a kernel) by the
    // least-squares optimum of all edges, outliers included.
    const bool robust = use_gnc || options.kernel != backend::RobustKernel::kNone;
    if (robust) {
      warn("--certify with a robust cost: the certificate is that of least squares over all edges (the rejected "
           "or down-weighted ones included), so it is reported but the staircase is not climbed");
    }
    staircase_options.climb = options.objective == backend::Objective::kChordal && !robust;
    staircase = backend::riemannian_staircase(problem, staircase_options);
    for (const auto& level : staircase->levels) {
      std::printf("certificate at rank %d (%d iterations, %.3f s, %d factorisations): %s\n", level.rank, level.iterations,
                  level.certificate.time_s, level.certificate.factorizations, level.certificate.message.c_str());
    }
    if (staircase->levels.size() > 1) std::printf("staircase (%.3f s): %s\n", staircase->time_s, staircase->message.c_str());
  }
  // The geodesic objective (g2o's chi2) from the chordal optimum (SE-Sync's certified start):
  // a polish reported as such, since the certificate speaks of the chordal point before it.
  std::optional<backend::OptimizerSummary> polish;
  if (flags.polish_geodesic && !stopped && !interrupted()) {
    if (options.objective != backend::Objective::kChordal) {
      warn("--polish-geodesic polishes a chordal solve; this solve minimised the geodesic objective already");
    } else if (use_gnc) {
      warn("--polish-geodesic after GNC is not done: the polish would need GNC's final weights");
    } else {
      backend::OptimizerOptions geodesic_options = options;
      geodesic_options.objective = backend::Objective::kGeodesic;
      geodesic_options.progress = nullptr;
      polish = backend::optimize(problem, geodesic_options);
      std::printf("geodesic polish from the chordal %s: chi2 %.10g -> %.10g in %d iterations (%.3f s): %s\n",
                  staircase && staircase->certified ? "certified optimum" : "solution", polish->initial_cost,
                  polish->final_cost, polish->iterations, polish->total_s, std::string(to_string(polish->termination)).c_str());
    }
  }
  // A signal during the certificate, the staircase or the polish: the poses are those of the
  // last accepted step.
  const bool stopped_after = stopped || interrupted();
  // A failed solve is a failed command: nothing is written and no existing output is replaced.
  if (!summary.is_solution_usable() && !stopped_after) {
    std::printf("%s\n", summary.brief_report().c_str());
    throw io::ParseError(flags.input, 0, "the solve failed (" + summary.message + "); nothing was written");
  }
  const auto optimized = backend::to_graph(problem, graph);
  // The graph and the report form one set: both are produced before either replaces a file.
  io::OutputFile graph_file(flags.output);
  std::vector<std::string> warnings;
  graph_file.write([&](std::ostream& out) { warnings = io::write_graph(out, io::PoseGraph(optimized), out_format); });
  for (const auto& w : warnings) warn(w);

  backend::OptimizerOptions geodesic = options;
  geodesic.objective = backend::Objective::kGeodesic;
  geodesic.kernel = backend::RobustKernel::kNone;
  backend::OptimizerOptions chordal = geodesic;
  chordal.objective = backend::Objective::kChordal;
  const double final_geodesic = backend::evaluate_cost(problem, geodesic);
  const double final_chordal = backend::evaluate_cost(problem, chordal);

  std::printf("%s\n", summary.brief_report().c_str());
  std::printf("time: %.3f s total (initialisation %.3f s, analysis %.3f s, linearisation %.3f s, factorisation %.3f s, solve %.3f s)\n",
              summary.total_s + init_summary.total_s, init_summary.total_s, summary.analyze_s, summary.linearize_s,
              summary.factorize_s, summary.solve_s);
  std::printf("final chi2 (geodesic) %.10g, SE-Sync objective f (chordal) %.10g\n", final_geodesic, final_chordal);

  std::optional<io::OutputFile> report_file;
  if (!flags.report.empty()) {
    nlohmann::json j;
    j["input"] = flags.input;
    j["output"] = flags.output;
    j["poses"] = problem.ids.size();
    j["edges"] = problem.edges.size();
    j["initialization"] = {{"method", backend::to_string(init)}, {"time_s", init_summary.total_s}};
    j["solver"] = backend::to_string(options.algorithm);
    j["objective"] = backend::to_string(options.objective);
    j["robust"] = flags.robust;
    j["cost_after_initialization"] = initial_cost;
    j["summary"] = summary_json(summary);
    j["final_chi2_geodesic"] = final_geodesic;
    j["final_f_chordal"] = final_chordal;
    j["read_warnings"] = file.report.warnings;
    if (staircase) {
      const backend::CertificateSummary* certificate = &staircase->certificate;
      // JSON has no infinity: an unknown end of the bracket is null.
      auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
      j["certificate"] = {{"certified", certificate->certified},
                          {"f", certificate->f},
                          {"lambda_min_lower", finite_or_null(certificate->lambda_min_lower)},
                          {"lambda_min_upper", finite_or_null(certificate->lambda_min_upper)},
                          {"eigenvalue_tolerance", flags.certify_tolerance},
                          {"suboptimality_bound", finite_or_null(certificate->suboptimality_bound)},
                          {"relative_suboptimality_bound", finite_or_null(certificate->relative_suboptimality_bound)},
                          {"rank", certificate->rank},
                          {"factorizations", certificate->factorizations},
                          {"factor_nonzeros", certificate->factor_nonzeros},
                          {"time_s", certificate->time_s},
                          {"message", certificate->message}};
      nlohmann::json levels = nlohmann::json::array();
      for (const auto& level : staircase->levels) {
        levels.push_back({{"rank", level.rank},
                          {"iterations", level.iterations},
                          {"f", level.f},
                          {"certified", level.certificate.certified},
                          {"lambda_min_lower", finite_or_null(level.certificate.lambda_min_lower)},
                          {"lambda_min_upper", finite_or_null(level.certificate.lambda_min_upper)},
                          {"time_s", level.certificate.time_s}});
      }
      j["staircase"] = {{"levels", levels},
                        {"f_initial", staircase->f_initial},
                        {"f_final", staircase->f_final},
                        {"time_s", staircase->time_s},
                        {"interrupted", staircase->interrupted},
                        {"message", staircase->message}};
    }
    if (polish) {
      j["geodesic_polish"] = summary_json(*polish);
      j["geodesic_polish"]["note"] =
          "g2o's chi2 minimised from the chordal solution; the certificate, if any, is that of the chordal point before it";
    }
    j["interrupted"] = stopped_after;
    if (stopped_after) j["interruption"] = {{"signal", interrupt_signal_name()}};
    if (!flags.covariance_ids.empty()) {
      std::vector<int> poses;
      for (const auto id : flags.covariance_ids) poses.push_back(problem.index_of(id));
      const auto marginals = backend::marginal_covariances(problem, poses);
      if (!marginals) {
        warn("marginal covariances unavailable: J^T J is not positive definite at the solution");
      } else {
        nlohmann::json covariances = nlohmann::json::array();
        for (std::size_t k = 0; k < poses.size(); ++k) {
          const auto& C = marginals->covariance[k];
          std::vector<double> row_major;
          for (int r = 0; r < C.rows(); ++r) {
            for (int c = 0; c < C.cols(); ++c) row_major.push_back(C(r, c));
          }
          covariances.push_back({{"id", flags.covariance_ids[k]}, {"covariance_row_major", row_major}});
        }
        j["marginal_covariances"] = {{"tangent", "right perturbation T exp(delta), translation first"},
                                     {"poses", covariances}};
      }
    }
    if (use_gnc) {
      nlohmann::json rejected = nlohmann::json::array();
      for (const std::size_t e : gnc.rejected_edges) {
        const auto& edge = problem.edges[e];
        rejected.push_back({{"from", problem.ids[static_cast<std::size_t>(edge.i)]},
                            {"to", problem.ids[static_cast<std::size_t>(edge.j)]},
                            {"line", edge.line},
                            {"edge_index", e}});
      }
      j["gnc"] = {{"outer_iterations", gnc.outer_iterations}, {"inner_iterations", gnc.inner_iterations},
                  {"factorizations", gnc.factorizations},     {"analyses", gnc.analyses},
                  {"threshold_chi2", gnc.threshold_chi2},     {"final_mu", gnc.final_mu},
                  {"initial_threshold_chi2", gnc.initial_threshold_chi2},
                  {"graduation_threshold_chi2", gnc.graduation_threshold_chi2},
                  {"noise_variance_factor", gnc.noise_variance_factor},
                  {"short_loop_variance_factor", gnc.short_loop_variance_factor},
                  {"regraduated", gnc.regraduated},           {"solves", gnc.solves},
                  {"restarted_from_chordal", gnc.restarted},
                  {"reclassify_rounds", gnc.reclassify_rounds},
                  {"groups_tried", gnc.groups_tried},         {"groups_readmitted", gnc.groups_readmitted},
                  {"readmitted_by_innovation", gnc.readmitted_by_innovation},
                  {"rejected_by_leave_one_out", gnc.rejected_by_leave_one_out},
                  {"tls_cost", gnc.tls_cost},
                  {"message", gnc.message},                   {"time_s", gnc.total_s},
                  {"interrupted", gnc.interrupted},
                  {"stage_time_s",
                   {{"graduation", gnc.graduation_s},
                    {"reclassification", gnc.reclassify_s},
                    {"restart_from_chordal", gnc.restart_s},
                    {"group_readmission", gnc.groups_s},
                    {"innovation_readmission", gnc.innovation_s}}},
                  {"rejected", rejected}};
    }
    report_file.emplace(flags.report);
    report_file->write([&](std::ostream& out) { out << io::json_text(j); });
  }
  graph_file.commit();
  if (report_file) report_file->commit();
  std::printf("wrote %s%s%s\n", io::output_display_name(flags.output).c_str(),
              flags.report.empty() ? "" : (" and " + io::output_display_name(flags.report)).c_str(),
              stopped_after ? " (interrupted: the estimate so far)" : "");
  if (stopped_after) return interrupted_exit_status();
  return 0;
}

int optimize_command(const OptimizeFlags& flags) {
  check_combinations(flags);
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
  if (const auto* g2 = std::get_if<io::PoseGraph2D>(&file.graph)) return run_optimize(flags, file, *g2, graph_format);
  return run_optimize(flags, file, std::get<io::PoseGraph3D>(file.graph), graph_format);
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
  app.add_option("IN", flags->input, "Pose graph (.g2o, .graph)")->required();
  app.add_option("-o,--output", flags->output, "Optimised graph (.g2o or .graph)")->required();
  app.add_option("--format", flags->format, "Input format: g2o or toro (default: detected)");
  app.add_option("--init", flags->init, "Initial guess: file (VERTEX lines), odometry (spanning tree, odometry edges "
                                        "first), chordal (relaxation); auto = odometry with --robust gnc, else file "
                                        "if present, else chordal")
      ->check(CLI::IsMember({"auto", "file", "odometry", "chordal"}))
      ->capture_default_str();
  app.add_option("--solver", flags->solver, "lm (Levenberg-Marquardt), gn (Gauss-Newton), dogleg (Powell)")
      ->check(CLI::IsMember({"lm", "gn", "dogleg"}))
      ->capture_default_str();
  app.add_option("--objective", flags->objective,
                 "geodesic (chi2 of log-map residuals, as g2o/GTSAM/Ceres) or chordal (SE-Sync's f)")
      ->check(CLI::IsMember({"geodesic", "chordal"}))
      ->capture_default_str();
  app.add_option("--robust", flags->robust,
                 "Robust cost: none; huber, cauchy, geman-mcclure (kernel on every edge); gnc (graduated "
                 "non-convexity with truncated least squares on loop closures, odometry trusted; rejected "
                 "edges are listed in the report)")
      ->check(CLI::IsMember({"none", "huber", "cauchy", "geman-mcclure", "gnc"}))
      ->capture_default_str();
  app.add_option("--robust-scale", flags->robust_scale, "Kernel scale in standard deviations")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_option("--gnc-threshold", flags->gnc_threshold,
                 "GNC inlier threshold on the whitened squared residual, fixed; 0 = adaptive (chi-square 0.99 quantile "
                 "first, then 4x that quantile in the noise variance estimated from the accepted edges)")
      ->check(checks::non_negative())
      ->capture_default_str();
  app.add_option("--gnc-mu-factor", flags->gnc_mu_factor,
                 "GNC: growth of the non-convexity parameter mu per outer iteration (> 1; smaller is slower and "
                 "follows the minimiser more closely)")
      ->check(checks::above(1.0, 1e9));
  app.add_option("--gnc-final-factor", flags->gnc_final_factor,
                 "GNC, adaptive threshold: the stages after the graduation use this many times its threshold; smaller "
                 "misses more true loop closures and keeps fewer false ones (1.5 kept none in the seeds tried, but "
                 "rejects true ones on clean graphs; docs/backend.md)")
      ->check(checks::in_range(1.0, 1e9))
      ->capture_default_str();
  app.add_option("--gnc-inner-iterations", flags->gnc_inner_iterations,
                 "GNC: solver iterations between two weight updates")
      ->check(checks::count())
      ->capture_default_str();
  app.add_option("--threads", flags->threads, "Threads for linearisation (0 = all cores)")
      ->transform(checks::threads())
      ->capture_default_str();
  app.add_option("--max-iterations", flags->max_iterations, "Iteration limit")
      ->check(checks::count())
      ->capture_default_str();
  app.add_option("--initial-radius", flags->initial_radius,
                 "Initial trust-region radius (LM: damping 1/radius; default 1e16 = an undamped, Gauss-Newton "
                 "first step; Ceres' default is 1e4)")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_flag("--exact-steps", flags->exact_steps,
               "LM: factorise every iteration instead of solving by PCG on the last factorisation");
  app.add_flag("--gauss-newton-hessian", flags->gauss_newton_hessian,
               "Chordal objective: Gauss-Newton's J^T J instead of the exact Hessian J^T J + S (converges only "
               "linearly there; for comparison)");
  app.add_flag("--certify", flags->certify,
               "After the solve, the dual certificate of SE-Sync's chordal problem (Rosen et al. 2019) and, when it "
               "fails, the Riemannian staircase: certified "
               "globally optimal or not, lambda_min and a suboptimality bound (docs/backend.md)");
  app.add_flag("--polish-geodesic", flags->polish_geodesic,
               "After a chordal solve (and --certify), minimise the geodesic objective (g2o's chi2) from its solution; "
               "reported as a polish ('geodesic_polish' in the report): the certificate is that of the chordal point");
  app.add_option("--certify-tolerance", flags->certify_tolerance,
                 "Certified when lambda_min(S) >= -this (absolute; SE-Sync's min_eig_num_tol)")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_option("--report", flags->report, "Write a JSON report (summary, per-iteration log, timings)");
  app.add_option("--covariance", flags->covariance_ids,
                 "Pose ids whose marginal covariance goes into the report (comma separated)")
      ->delimiter(',');
  app.add_flag("-q,--quiet", flags->quiet, "No per-iteration progress");
  flags->graph.add_to(app);
  flags->command = &app;
  return [flags]() { return optimize_command(*flags); };
}

}  // namespace cairn::cli
