#include "cairn/backend/pose_graph_job.hpp"

#include <cmath>

#include "cairn/backend/covariance.hpp"
#include "cairn/backend/sparse_cholesky.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::backend {

bool PoseGraphJobOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string invalid;
  if (!solver.is_valid(&invalid)) problems.add(invalid);
  if (gnc) {
    if (solver.kernel != RobustKernel::kNone) problems.add("gnc replaces the robust kernel: solver.kernel must be none");
    if (!(gnc_options.inlier_threshold_chi2 >= 0.0)) problems.add("gnc_options.inlier_threshold_chi2 must be >= 0");
    if (!(gnc_options.mu_factor > 1.0)) problems.add("gnc_options.mu_factor must be > 1");
    if (!(gnc_options.final_threshold_factor >= 1.0)) problems.add("gnc_options.final_threshold_factor must be >= 1");
    if (gnc_options.iterations_per_outer < 1) problems.add("gnc_options.iterations_per_outer must be >= 1");
  }
  if (certify && !certificate.is_valid(&invalid)) {
    // CertificateOptions lists its problems as "a; b; ".
    while (!invalid.empty() && (invalid.back() == ' ' || invalid.back() == ';')) invalid.pop_back();
    problems.add(invalid);
  }
  return problems.report(why);
}

std::string_view robust_cost_name(const PoseGraphJobOptions& options) {
  return options.gnc ? std::string_view("gnc") : to_string(options.solver.kernel);
}

namespace {

bool stop_requested(const PoseGraphJobOptions& options) {
  return options.solver.should_stop && options.solver.should_stop();
}

void finished(const PoseGraphJobOptions& options, PoseGraphJobStage stage, const PoseGraphJobSummary& summary) {
  if (options.stage_finished) options.stage_finished(stage, summary);
}

// Automatic: GNC starts from odometry, which no loop closure, right or wrong, bends.
template <class Group>
Initialization choose_initialization(const PoseGraphProblem<Group>& problem, const std::string& path,
                                     const PoseGraphJobOptions& options) {
  if (!options.initialization) {
    if (options.gnc) return Initialization::kOdometry;
    return problem.has_initial_guess ? Initialization::kFile : Initialization::kChordal;
  }
  if (*options.initialization == Initialization::kFile && !problem.has_initial_guess) {
    throw io::ParseError(path, 0, "--init file needs VERTEX lines, and the file has none: use --init chordal or odometry");
  }
  return *options.initialization;
}

template <class Group>
void initialize(PoseGraphProblem<Group>& problem, const std::string& path, const PoseGraphJobOptions& options,
                PoseGraphJobSummary& summary) {
  summary.poses = problem.ids.size();
  summary.edges = problem.edges.size();
  for (const auto& e : problem.edges) summary.loop_closures += e.kind == EdgeKind::kLoopClosure;
  summary.initialization = choose_initialization(problem, path, options);
  if (summary.initialization == Initialization::kOdometry) summary.initialization_summary = initialize_odometry(problem);
  if (summary.initialization == Initialization::kChordal) summary.initialization_summary = initialize_chordal(problem);
}

// A starting cost that is not finite names its edge; --covariance names poses of this graph:
// both checked before the solve, not after it.
template <class Group>
void check_starting_point(const PoseGraphProblem<Group>& problem, const std::string& path,
                          const PoseGraphJobOptions& options, PoseGraphJobSummary& summary) {
  summary.cost_after_initialization = evaluate_cost(problem, options.solver);
  if (!std::isfinite(summary.cost_after_initialization)) {
    const long long e = first_nonfinite_edge(problem, options.solver);
    if (e >= 0) {
      const auto& edge = problem.edges[static_cast<std::size_t>(e)];
      throw io::ParseError(path, edge.line,
                           "the cost of the edge from pose " + std::to_string(problem.ids[static_cast<std::size_t>(edge.i)]) +
                               " to pose " + std::to_string(problem.ids[static_cast<std::size_t>(edge.j)]) +
                               " is not finite at the starting poses (" + std::string(to_string(summary.initialization)) +
                               " initialisation): a measurement or pose too large to evaluate; nothing was written");
    }
    throw io::ParseError(path, 0, "the starting cost is not finite; nothing was written");
  }
  for (const auto id : options.covariance_ids) {
    if (problem.index_of(id) < 0) throw io::ParseError(path, 0, "--covariance: pose " + std::to_string(id) + " is not in the graph");
  }
}

template <class Group>
void solve(PoseGraphProblem<Group>& problem, const PoseGraphJobOptions& options, PoseGraphJobSummary& summary) {
  if (options.gnc) {
    GncOptions gnc_options = options.gnc_options;
    gnc_options.inner = options.solver;
    gnc_options.inner.progress = nullptr;
    summary.gnc = optimize_gnc(problem, gnc_options);
    summary.solve = summary.gnc->final_solve;
    for (const std::size_t e : summary.gnc->rejected_edges) {
      const auto& edge = problem.edges[e];
      summary.rejected_edges.push_back({problem.ids[static_cast<std::size_t>(edge.i)],
                                        problem.ids[static_cast<std::size_t>(edge.j)], edge.line, e});
    }
  } else {
    summary.solve = optimize(problem, options.solver);
  }
  // Stopped between iterations, or before the first: the poses of the last accepted step are a
  // complete, consistent estimate.
  summary.stopped_during_solve = stop_requested(options) || summary.solve.termination == TerminationType::kInterrupted ||
                                 (summary.gnc && summary.gnc->interrupted);
}

// The certificate speaks of least squares over every edge: it may say whether a plain chordal
// solve is optimal, but must not replace a robust one (GNC, a kernel) by the least-squares
// optimum of all edges, outliers included; nor may it replace a geodesic solve's poses.
template <class Group>
void certify(PoseGraphProblem<Group>& problem, const PoseGraphJobOptions& options, PoseGraphJobSummary& summary) {
  StaircaseOptions staircase_options;
  staircase_options.certificate = options.certificate;
  staircase_options.polish = options.solver;
  staircase_options.polish.progress = nullptr;
  const bool robust = options.gnc || options.solver.kernel != RobustKernel::kNone;
  staircase_options.climb = options.solver.objective == Objective::kChordal && !robust;
  summary.staircase = riemannian_staircase(problem, staircase_options);
}

// The geodesic objective (g2o's chi2) from the chordal optimum (SE-Sync's certified start): a
// polish reported as such, since the certificate speaks of the chordal point before it.
template <class Group>
void polish(PoseGraphProblem<Group>& problem, const PoseGraphJobOptions& options, PoseGraphJobSummary& summary) {
  if (options.solver.objective != Objective::kChordal) {
    summary.polish_status = PolishStatus::kSkippedNotChordal;
  } else if (options.gnc) {
    summary.polish_status = PolishStatus::kSkippedAfterGnc;
  } else {
    OptimizerOptions geodesic_options = options.solver;
    geodesic_options.objective = Objective::kGeodesic;
    geodesic_options.progress = nullptr;
    summary.polish = optimize(problem, geodesic_options);
    summary.polish_status = PolishStatus::kDone;
  }
}

template <class Group>
void final_costs(const PoseGraphProblem<Group>& problem, const PoseGraphJobOptions& options,
                 PoseGraphJobSummary& summary) {
  OptimizerOptions geodesic = options.solver;
  geodesic.objective = Objective::kGeodesic;
  geodesic.kernel = RobustKernel::kNone;
  OptimizerOptions chordal = geodesic;
  chordal.objective = Objective::kChordal;
  summary.final_chi2_geodesic = evaluate_cost(problem, geodesic);
  summary.final_f_chordal = evaluate_cost(problem, chordal);
}

template <class Group>
void marginals(const PoseGraphProblem<Group>& problem, const PoseGraphJobOptions& options, PoseGraphJobSummary& summary) {
  if (options.covariance_ids.empty()) return;
  std::vector<int> poses;
  for (const auto id : options.covariance_ids) poses.push_back(problem.index_of(id));
  const auto marginal = marginal_covariances(problem, poses);
  if (!marginal) return;
  std::vector<PoseCovariance> covariances;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const auto& C = marginal->covariance[k];
    PoseCovariance pose{options.covariance_ids[k], {}};
    for (int r = 0; r < C.rows(); ++r) {
      for (int c = 0; c < C.cols(); ++c) pose.covariance_row_major.push_back(C(r, c));
    }
    covariances.push_back(std::move(pose));
  }
  summary.covariances = std::move(covariances);
}

}  // namespace

template <class Group>
PoseGraphJobResult<Group> run_pose_graph_job(const io::PoseGraphT<Group>& graph, const std::string& path,
                                             const PoseGraphJobOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "run_pose_graph_job: options.is_valid() found problems");
  // The solver's thread count holds for CHOLMOD's BLAS in every stage (solve, GNC, certificate,
  // staircase, covariances).
  const ScopedBlasThreads blas(options.solver.threads);
  PoseGraphJobResult<Group> result;
  PoseGraphJobSummary& summary = result.summary;
  PoseGraphProblem<Group> problem = make_problem(graph, path);
  initialize(problem, path, options, summary);
  finished(options, PoseGraphJobStage::kInitialized, summary);
  check_starting_point(problem, path, options, summary);
  solve(problem, options, summary);
  finished(options, PoseGraphJobStage::kSolved, summary);
  // The certificate, and the staircase when it fails (which may replace the poses by a better,
  // certified set); then the polish.
  if (options.certify && !summary.stopped_during_solve) {
    certify(problem, options, summary);
    finished(options, PoseGraphJobStage::kCertified, summary);
  }
  if (options.polish_geodesic) {
    if (summary.stopped_during_solve || stop_requested(options)) {
      summary.polish_status = PolishStatus::kSkippedInterrupted;
    } else {
      polish(problem, options, summary);
      finished(options, PoseGraphJobStage::kPolished, summary);
    }
  }
  // A stop request during the certificate, the staircase or the polish: the poses are those of
  // the last accepted step.
  summary.interrupted = summary.stopped_during_solve || stop_requested(options);
  if (!summary.is_solution_usable()) return result;
  result.optimized = to_graph(problem, graph);
  final_costs(problem, options, summary);
  marginals(problem, options, summary);
  return result;
}

template PoseGraphJobResult<core::SE2> run_pose_graph_job(const io::PoseGraph2D&, const std::string&,
                                                          const PoseGraphJobOptions&);
template PoseGraphJobResult<core::SE3> run_pose_graph_job(const io::PoseGraph3D&, const std::string&,
                                                          const PoseGraphJobOptions&);

}  // namespace cairn::backend
