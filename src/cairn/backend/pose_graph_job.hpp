#pragma once
/// \file
/// One pose-graph optimisation from a graph file's contents to its optimised graph, as a short
/// list of stages (pose_graph_job.cpp, run_pose_graph_job):
///   initialise (file, odometry spanning tree or chordal relaxation) -> solve (least squares,
///   a robust kernel, or GNC over the loop closures) -> certify (SE-Sync's certificate and, when
///   it fails, the Riemannian staircase) -> polish (the geodesic objective from the chordal
///   solution) -> final costs and marginal covariances.
/// Options are validated before work (PoseGraphJobOptions::is_valid, every problem at once); the
/// result is a PoseGraphJobSummary (what each stage did, whether the solution is usable) and the
/// optimised graph. The library prints nothing: a caller follows the stages through
/// `stage_finished` and the solver's `progress`, and pose_graph_report.hpp turns the summary into
/// the report JSON. `cairn optimize` is this job with flags.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/backend/certificate.hpp"
#include "cairn/backend/gnc.hpp"
#include "cairn/backend/initialization.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/staircase.hpp"
#include "cairn/io/pose_graph.hpp"

namespace cairn::backend {

struct PoseGraphJobSummary;

/// The stages after which PoseGraphJobOptions::stage_finished is called.
enum class PoseGraphJobStage {
  kInitialized,  ///< the starting poses are set (sizes and initialisation known)
  kSolved,       ///< the solve (or GNC) ended, perhaps interrupted
  kCertified,    ///< the certificate / staircase ran (only with `certify`, not after an interruption)
  kPolished,     ///< the geodesic polish was considered (only with `polish_geodesic`, not after an
                 ///< interruption): run, or skipped with its reason in `polish`
};

/// What became of the requested geodesic polish.
enum class PolishStatus {
  kNotRequested,
  kSkippedInterrupted,   ///< a stop request came first
  kSkippedNotChordal,    ///< the solve minimised the geodesic objective already
  kSkippedAfterGnc,      ///< the polish would need GNC's final weights
  kDone,
};

struct PoseGraphJobOptions {
  /// The starting poses; nullopt = automatic: odometry with `gnc` (no loop closure, right or
  /// wrong, bends the start), else the file's VERTEX poses when it has them, else chordal.
  /// kFile on a file without VERTEX lines is an input error (io::ParseError).
  std::optional<Initialization> initialization;
  /// The solve: algorithm, objective, robust kernel and its scale, iteration limit, initial
  /// radius, factorisation reuse, exact chordal Hessian, threads (also CHOLMOD's BLAS threads in
  /// every stage), should_stop (also polled between the stages) and progress (of the main
  /// solve only). Defaults: OptimizerOptions'.
  OptimizerOptions solver;
  /// Graduated non-convexity with truncated least squares on the loop closures (gnc.hpp) instead
  /// of a plain solve; `solver.kernel` must then be kNone.
  bool gnc = false;
  /// GNC's own settings; `gnc_options.inner` is ignored: the inner solves use `solver` (without
  /// its progress callback).
  GncOptions gnc_options;
  /// After the solve, SE-Sync's certificate (certificate.hpp) and, for a plain least-squares
  /// chordal solve whose certificate fails, the Riemannian staircase (staircase.hpp), which may
  /// replace the poses by certified ones. With a robust cost or the geodesic objective the
  /// certificate is only reported.
  bool certify = false;
  /// The certificate's tolerances (eigenvalue_tolerance: certified when lambda_min(S) >= -it).
  CertificateOptions certificate;
  /// After a chordal least-squares solve (and the certificate), minimise the geodesic objective
  /// (g2o's chi2) from its solution. Skipped, with the reason in the summary, after a geodesic
  /// solve or GNC.
  bool polish_geodesic = false;
  /// Ids of the poses whose marginal covariance (covariance.hpp) is computed at the solution;
  /// each must be a pose of the graph (io::ParseError before the solve otherwise).
  std::vector<std::int64_t> covariance_ids;
  /// Called after each stage that ran (PoseGraphJobStage), with the summary so far; for
  /// progress output. May be empty.
  std::function<void(PoseGraphJobStage, const PoseGraphJobSummary&)> stage_finished;

  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

/// "none", "huber", "cauchy", "geman-mcclure" (the kernel) or "gnc".
std::string_view robust_cost_name(const PoseGraphJobOptions& options);

/// A loop closure GNC rejected, as the file names it.
struct RejectedEdge {
  std::int64_t from = 0;
  std::int64_t to = 0;
  std::size_t line = 0;        ///< line in the file (0 if none)
  std::size_t edge_index = 0;  ///< index among the graph's edges
};

/// The marginal covariance of one pose in the tangent space of the right perturbation
/// T exp(delta), translation first (covariance.hpp), row by row.
struct PoseCovariance {
  std::int64_t id = 0;
  std::vector<double> covariance_row_major;
};

struct PoseGraphJobSummary {
  std::size_t poses = 0;
  std::size_t edges = 0;
  std::size_t loop_closures = 0;  ///< edges of EdgeKind::kLoopClosure
  Initialization initialization = Initialization::kFile;  ///< the method used (automatic resolved)
  InitializationSummary initialization_summary;
  /// Cost of the starting poses under the solver's objective and kernel.
  double cost_after_initialization = 0.0;
  /// The solve; with GNC, its final least-squares solve over the accepted edges.
  OptimizerSummary solve;
  /// With GNC: its summary and the loop closures it rejected.
  std::optional<GncSummary> gnc;
  std::vector<RejectedEdge> rejected_edges;
  /// A stop request ended the solve (or GNC), or came before it ended: no certificate, no polish.
  bool stopped_during_solve = false;
  /// The certificate and staircase, when `certify` and not stopped during the solve.
  std::optional<StaircaseSummary> staircase;
  PolishStatus polish_status = PolishStatus::kNotRequested;
  /// The geodesic polish, when polish_status is kDone.
  std::optional<OptimizerSummary> polish;
  /// A stop request came at any point before the final costs: the poses are those of the last
  /// accepted step, a complete estimate.
  bool interrupted = false;
  /// Final costs of the poses without kernel or weights: geodesic (g2o's chi2) and chordal
  /// (SE-Sync's f). Set only when the solution is usable.
  double final_chi2_geodesic = 0.0;
  double final_f_chordal = 0.0;
  /// The requested marginal covariances, in covariance_ids order; nullopt when none were
  /// requested, when J^T J is not positive definite at the solution (the caller may warn:
  /// requested but absent), or when the solution is not usable.
  std::optional<std::vector<PoseCovariance>> covariances;

  /// False when the solve failed (and was not interrupted): there is no estimate to write, and
  /// the final costs and covariances were not computed.
  bool is_solution_usable() const { return interrupted || solve.is_solution_usable(); }
};

template <class Group>
struct PoseGraphJobResult {
  PoseGraphJobSummary summary;
  /// The graph with its optimised poses (backend::to_graph); empty when the solution is not usable.
  io::PoseGraphT<Group> optimized;
};

/// Runs the job on `graph` (read from `path`, which error messages name). Preconditions:
/// options.is_valid(). Throws io::ParseError for input the job cannot use: a graph
/// make_problem refuses, kFile initialisation without VERTEX lines, a starting cost that is not
/// finite (naming the edge and its line), a covariance id not in the graph.
template <class Group>
PoseGraphJobResult<Group> run_pose_graph_job(const io::PoseGraphT<Group>& graph, const std::string& path,
                                             const PoseGraphJobOptions& options);

}  // namespace cairn::backend
