#include "cairn/cli/optimize_flags.hpp"

#include "cairn/cli/flag_checks.hpp"

namespace cairn::cli {

void check_optimize_flags(const OptimizeFlags& f) {
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

backend::PoseGraphJobOptions optimize_job_options(const OptimizeFlags& flags) {
  backend::PoseGraphJobOptions job;
  if (flags.init == "file") job.initialization = backend::Initialization::kFile;
  if (flags.init == "odometry") job.initialization = backend::Initialization::kOdometry;
  if (flags.init == "chordal") job.initialization = backend::Initialization::kChordal;
  backend::OptimizerOptions& options = job.solver;
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
  options.exact_chordal_hessian = !flags.gauss_newton_hessian;
  job.gnc = flags.robust == "gnc";
  job.gnc_options.inlier_threshold_chi2 = flags.gnc_threshold;
  job.gnc_options.iterations_per_outer = flags.gnc_inner_iterations;
  job.gnc_options.mu_factor = flags.gnc_mu_factor;
  job.gnc_options.final_threshold_factor = flags.gnc_final_factor;
  job.certify = flags.certify;
  job.certificate.eigenvalue_tolerance = flags.certify_tolerance;
  job.polish_geodesic = flags.polish_geodesic;
  job.covariance_ids = flags.covariance_ids;
  return job;
}

void add_optimize_flags(CLI::App& app, OptimizeFlags& flags) {
  app.add_option("IN", flags.input, "Pose graph (.g2o, .graph)")->required();
  app.add_option("-o,--output", flags.output, "Optimised graph (.g2o or .graph)")->required();
  app.add_option("--format", flags.format, "Input format: g2o or toro (default: detected)");
  app.add_option("--init", flags.init, "Initial guess: file (VERTEX lines), odometry (spanning tree, odometry edges "
                                       "first), chordal (relaxation); auto = odometry with --robust gnc, else file "
                                       "if present, else chordal")
      ->check(CLI::IsMember({"auto", "file", "odometry", "chordal"}))
      ->capture_default_str();
  app.add_option("--solver", flags.solver, "lm (Levenberg-Marquardt), gn (Gauss-Newton), dogleg (Powell)")
      ->check(CLI::IsMember({"lm", "gn", "dogleg"}))
      ->capture_default_str();
  app.add_option("--objective", flags.objective,
                 "geodesic (chi2 of log-map residuals, as g2o/GTSAM/Ceres) or chordal (SE-Sync's f)")
      ->check(CLI::IsMember({"geodesic", "chordal"}))
      ->capture_default_str();
  app.add_option("--robust", flags.robust,
                 "Robust cost: none; huber, cauchy, geman-mcclure (kernel on every edge); gnc (graduated "
                 "non-convexity with truncated least squares on loop closures, odometry trusted; rejected "
                 "edges are listed in the report)")
      ->check(CLI::IsMember({"none", "huber", "cauchy", "geman-mcclure", "gnc"}))
      ->capture_default_str();
  app.add_option("--robust-scale", flags.robust_scale, "Kernel scale in standard deviations")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_option("--gnc-threshold", flags.gnc_threshold,
                 "GNC inlier threshold on the whitened squared residual, fixed; 0 = adaptive (chi-square 0.99 quantile "
                 "first, then 4x that quantile in the noise variance estimated from the accepted edges)")
      ->check(checks::non_negative())
      ->capture_default_str();
  app.add_option("--gnc-mu-factor", flags.gnc_mu_factor,
                 "GNC: growth of the non-convexity parameter mu per outer iteration (> 1; smaller is slower and "
                 "follows the minimiser more closely)")
      ->check(checks::above(1.0, 1e9));
  app.add_option("--gnc-final-factor", flags.gnc_final_factor,
                 "GNC, adaptive threshold: the stages after the graduation use this many times its threshold; smaller "
                 "misses more true loop closures and keeps fewer false ones (1.5 kept none in the seeds tried, but "
                 "rejects true ones on clean graphs; docs/backend.md)")
      ->check(checks::in_range(1.0, 1e9))
      ->capture_default_str();
  app.add_option("--gnc-inner-iterations", flags.gnc_inner_iterations,
                 "GNC: solver iterations between two weight updates")
      ->check(checks::count())
      ->capture_default_str();
  app.add_option("--threads", flags.threads, "Threads for linearisation (0 = all cores)")
      ->transform(checks::threads())
      ->capture_default_str();
  app.add_option("--max-iterations", flags.max_iterations, "Iteration limit")
      ->check(checks::count())
      ->capture_default_str();
  app.add_option("--initial-radius", flags.initial_radius,
                 "Initial trust-region radius (LM: damping 1/radius; default 1e16 = an undamped, Gauss-Newton "
                 "first step; Ceres' default is 1e4)")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_flag("--exact-steps", flags.exact_steps,
               "LM: factorise every iteration instead of solving by PCG on the last factorisation");
  app.add_flag("--gauss-newton-hessian", flags.gauss_newton_hessian,
               "Chordal objective: Gauss-Newton's J^T J instead of the exact Hessian J^T J + S (converges only "
               "linearly there; for comparison)");
  app.add_flag("--certify", flags.certify,
               "After the solve, the dual certificate of SE-Sync's chordal problem (Rosen et al. 2019) and, when it "
               "fails, the Riemannian staircase: certified "
               "globally optimal or not, lambda_min and a suboptimality bound (docs/backend.md)");
  app.add_flag("--polish-geodesic", flags.polish_geodesic,
               "After a chordal solve (and --certify), minimise the geodesic objective (g2o's chi2) from its solution; "
               "reported as a polish ('geodesic_polish' in the report): the certificate is that of the chordal point");
  app.add_option("--certify-tolerance", flags.certify_tolerance,
                 "Certified when lambda_min(S) >= -this (absolute; SE-Sync's min_eig_num_tol)")
      ->check(checks::positive())
      ->capture_default_str();
  app.add_option("--report", flags.report, "Write a JSON report (summary, per-iteration log, timings)");
  app.add_option("--covariance", flags.covariance_ids,
                 "Pose ids whose marginal covariance goes into the report (comma separated)")
      ->delimiter(',');
  app.add_flag("-q,--quiet", flags.quiet, "No per-iteration progress");
  flags.graph.add_to(app);
  flags.command = &app;
}

}  // namespace cairn::cli
