#pragma once
/// \file
/// Graduated Non-Convexity with a truncated-least-squares cost on loop-closure edges (Yang,
/// Antonante, Tzoumas, Carlone, "Graduated Non-Convexity for Robust Spatial Perception: From
/// Non-Minimal Solvers to Global Outlier Rejection", RA-L 2020). Odometry edges are trusted.
///
/// TLS: rho(r^2) = min(r^2, c^2) with r the whitened residual and c^2 the inlier threshold. GNC
/// minimises a sequence of surrogates rho_mu that start convex (mu -> 0) and tend to TLS
/// (mu -> inf), alternating a weighted least-squares solve with the closed-form weight update
/// of eq. (14):
///   w = 1                                   if r^2 <= mu/(mu+1) c^2
///   w = c/|r| sqrt(mu (mu+1)) - mu          if mu/(mu+1) c^2 < r^2 < (mu+1)/mu c^2
///   w = 0                                   if r^2 >= (mu+1)/mu c^2
/// mu starts at c^2 / (2 max r^2 - c^2) (Remark 5) and grows by `mu_factor` until the weights
/// are binary. The paper computes mu_0 at the non-robust least-squares solution; cairn starts
/// by default from the current poses, which the CLI sets from the odometry chain (a spanning
/// tree over odometry edges that no loop closure can bend). Measured on SE-Sync's intel.g2o with
/// 785 random false loop closures (as many as true ones) and threshold 3: from least squares,
/// 207 true loop closures were rejected; from odometry, none, and all 785 false ones were.
/// Edges whose final weight is below 0.5 are rejected.
///
/// Around the graduation (gnc.cpp, docs/backend.md "Robustness"): by default the threshold is
/// measured in the noise estimated from the data (short loop closures before, the accepted
/// edges after the graduation; a second graduation when the first was far too loose); after it,
/// the accepted set is reclassified by TLS at mu = inf, restarted from the chordal relaxation of
/// the accepted edges when that lowers the TLS cost, and rejected loop closures are readmitted
/// as consistent groups or by their innovation (accepted ones rejected by their leave-one-out
/// innovation) when that lowers the TLS cost. The result is least squares on the accepted edges.

#include <cstddef>
#include <vector>

#include "cairn/backend/optimizer.hpp"

namespace cairn::backend {

struct GncOptions {
  /// c^2, the largest whitened squared residual of an inlier, in the units of the stated
  /// information matrices. 0 (default) = adaptive: the 0.99 quantile of chi-square with the
  /// edge's degrees of freedom (11.345 for 3, 16.812 for 6) for a first pass, then
  /// `scaled_threshold_multiplier` times that quantile in units of the noise estimated from the
  /// accepted edges (see `estimate_noise_scale`). > 0 = this threshold, fixed.
  double inlier_threshold_chi2 = 0.0;
  /// With the adaptive threshold: estimate the variance factor of the stated information
  /// (variance of unit weight over the accepted edges after a first pass) and measure the
  /// threshold in it. Measured: intel.g2o's matrices overstate its errors ~50x in variance, so
  /// a false loop closure fits within the 0.99 quantile by bending the map; manhattan's ~1.7x.
  bool estimate_noise_scale = true;
  /// The adaptive threshold is this many times the chi-square 0.99 quantile in estimated noise
  /// units (4 = twice the 99 % radius). Measured on manhattan with as many false loop closures
  /// as true ones: TLS at the 0.99 quantile itself rejects 2.6 % of the true ones (its minimum
  /// trades an edge for c^2 whenever that relaxes its neighbours by more). > 0.
  double scaled_threshold_multiplier = 4.0;
  /// The first graduation's threshold comes from the short loop closures (at most this many
  /// poses apart along an unbroken odometry chain; gnc.cpp) when at least `minimum_short_loops`
  /// of them exist, else from the stated matrices. >= 1.
  int short_loop_window = 50;
  int minimum_short_loops = 20;
  /// After the first graduation the factor is estimated again on the accepted edges; when the
  /// threshold it implies is tighter than the first by more than this ratio, the graduation is
  /// run again from the initial guess with it. > 1.
  double regraduation_ratio = 2.0;
  /// With the adaptive threshold, the reclassification and readmission after the graduation use
  /// this many times the graduation's threshold (with the default multiplier, 16x the chi-square
  /// 0.99 quantile in estimated noise units; readmission by innovation uses readmission_factor
  /// of it). Measured 2026-11-24 (docs/backend.md): 1.5 also keeps out the false loop closures
  /// that readmission_factor does, but rejects true ones on graphs without false loop closures
  /// (49 of sphere_bignoise's, which moves that map 5.9 m; 8 of intel's 785). >= 1.
  double final_threshold_factor = 4.0;
  /// Growth of mu per outer iteration (the paper uses 1.4). > 1.
  double mu_factor = 1.4;
  /// Outer iterations at most, per graduation. >= 1.
  int max_outer_iterations = 100;
  /// Stop when sum w (1 - w) over loop closures is below this (weights binary). > 0.
  double binary_tolerance = 1e-6;
  /// Start from the non-robust least-squares solution (the paper's choice) instead of the
  /// current poses. Default false: see the file comment.
  bool start_from_least_squares = false;
  /// Iterations of each weighted solve between two weight updates (GNC only needs to track the
  /// minimiser as mu grows); the solves after the graduation use inner.max_iterations. >= 1.
  int iterations_per_outer = 15;
  /// Relative cost change that ends a weighted solve of the graduation early (Ceres' default
  /// function tolerance; the larger of this and inner.function_tolerance is used). The weights
  /// change after every such solve, so converging it further only burns iterations: with
  /// inner.function_tolerance's 1e-12 the solves ran 13 of at most 15 iterations per weight
  /// update on average, and city10000's graduation took 317 of GNC's 352 s (docs/backend.md).
  /// The solves after the graduation use inner.function_tolerance. >= 0.
  double graduation_function_tolerance = 1e-6;
  /// During the graduation, loop closures whose weight is below this fraction of the weight a
  /// loop closure at the threshold has (eq. 14 at r^2 = c^2) enter the gradient but not H
  /// (OptimizerOptions::coupling_weight_floor): the weighted problem stays the paper's, but
  /// far-off false loop closures no longer fill the factor in while their weights fade. city10000 with 10,688 false loop closures: graduation 291 s
  /// without, 18 s with, the same edges rejected (docs/backend.md). 0 = off. >= 0.
  double negligible_weight = 0.01;
  /// Start each weighted solve of the graduation with the damping the previous one ended with
  /// (instead of inner.initial_trust_region_radius).
  bool carry_damping = true;
  /// Rounds of reclassification (accept exactly the loop closures with r^2 <= c^2, solve again)
  /// after the graduation; it stops earlier when the accepted set is stable. >= 0.
  int max_reclassify_rounds = 10;
  /// After the first reclassification, restart from the chordal relaxation of the accepted
  /// edges and keep the result when its TLS cost is lower (gnc.cpp, restart_from_chordal): it
  /// undoes stretches the graduation folded while false loop closures still pulled on them.
  bool restart_from_chordal = true;
  /// Rejected loop closures whose ends lie within this many poses of each other's and that are
  /// pairwise consistent are tried back in as a group (see gnc.cpp); 0 = off. >= 0.
  int group_window = 50;
  /// After the groups, readmit rejected loop closures whose innovation test passes (d^2 <= c^2,
  /// see gnc.cpp), then reclassify; repeated while it readmits any (at most
  /// max_reclassify_rounds times).
  bool readmit_by_innovation = true;
  /// With the adaptive threshold, a rejected loop closure is readmitted by its innovation only
  /// when d^2 <= this times c^2 (with a fixed threshold, c^2 itself):
  /// the graduation rejected it, so it needs stronger evidence to come back than an accepted
  /// edge needs to stay ("miss a loop rather than accept a wrong one"). 0.375 = 1.5x the
  /// graduation's threshold under the default final_threshold_factor. Measured 2026-11-24
  /// (docs/backend.md): with 1, random false loop closures that bend a weakly held part of the
  /// map stayed on intel seeds 4 and 5 and manhattan seeds 4 and 8 (0.47-3.5 m RMS); with
  /// 0.375 they stay out, at the price of 1 of intel's 785 true loop closures there and 4 on
  /// the uncorrupted intel (2.1 cm RMS). (0, 1].
  double readmission_factor = 0.375;
  /// With readmit_by_innovation: also reject accepted loop closures whose leave-one-out
  /// innovation exceeds the threshold (gnc.cpp, readmit_by_innovation).
  bool reject_by_leave_one_out = true;
  /// Also apply TLS to odometry edges (consecutive ids). Default: odometry is trusted.
  bool robust_odometry = false;
  /// Inner weighted least-squares solves (objective, algorithm, tolerances, threads, progress).
  OptimizerOptions inner;
  /// Replaces inner.reuse_max_cg_iterations in the weighted solves: 0 = the flop-derived budget
  /// (8-30 PCG iterations). While outliers still weigh, they fill the factor in and a
  /// factorisation costs many triangular solves: with the plain solver's 6, GNC on corrupted
  /// sphere2500 factorised 56 times instead of 32 (21.1 s instead of 16.3 s; manhattan equal
  /// within noise; measured 2026-11-24 with negligible_weight on, docs/backend.md).
  int reuse_max_cg_iterations = 0;
  /// Replaces inner.reuse_step_fraction in the weighted solves: 1 = PCG is tried whenever a
  /// factorisation exists. The solves start warm, from the last weights' minimum, so even their
  /// first step leaves the factor a good preconditioner: with the plain solver's 0.25, GNC on
  /// corrupted manhattan took 16.6 s instead of 9.7 s and on sphere2500 19.4 s instead of
  /// 15.5 s (2026-11-24).
  double reuse_step_fraction = 1.0;
};

struct GncSummary {
  int outer_iterations = 0;
  double final_mu = 0.0;
  /// True when the (last) graduation ended with binary weights.
  bool graduation_converged = false;
  /// Threshold of the first graduation, of the last one, and of the result (the stages after
  /// the graduation); they differ when adaptive.
  double initial_threshold_chi2 = 0.0;
  double graduation_threshold_chi2 = 0.0;
  double threshold_chi2 = 0.0;
  /// Estimated variance factor of the stated information: from the short loop closures before
  /// the graduation, and from the accepted edges after it (0 = not estimated).
  double short_loop_variance_factor = 0.0;
  double noise_variance_factor = 0.0;
  /// A second graduation from the initial guess ran (the adaptive threshold was tighter).
  bool regraduated = false;
  /// The restart from the chordal relaxation of the accepted edges lowered the TLS cost.
  bool restarted = false;
  int reclassify_rounds = 0;
  int groups_tried = 0;
  int groups_readmitted = 0;
  int readmitted_by_innovation = 0;
  int rejected_by_leave_one_out = 0;  ///< accepted loop closures the leave-one-out test rejected
  /// Truncated-least-squares cost of the result at threshold_chi2.
  double tls_cost = 0.0;
  /// Final weight per edge (1 = inlier, 0 = rejected), in problem.edges order.
  std::vector<double> weights;
  /// Indices into problem.edges of the rejected edges.
  std::vector<std::size_t> rejected_edges;
  /// Least-squares summary of the final solve over the accepted edges.
  OptimizerSummary final_solve;
  int inner_iterations = 0;
  /// Weighted least-squares solves, numeric factorisations and symbolic analyses in all.
  int solves = 0;
  int factorizations = 0;
  int analyses = 0;
  /// Where the time went: the graduation(s) (with the initial least-squares solve, if any),
  /// the reclassifications, the restart from the chordal relaxation (its reclassification
  /// included), the readmission of groups and the readmission by innovation (its
  /// reclassifications included); total_s also holds the short-loop estimate and bookkeeping.
  double graduation_s = 0.0;
  double reclassify_s = 0.0;
  double restart_s = 0.0;
  double groups_s = 0.0;
  double innovation_s = 0.0;
  double total_s = 0.0;
  /// GncOptions::inner.should_stop stopped it: the stages after the one running were skipped.
  bool interrupted = false;
  std::string message;
};

template <class Group>
GncSummary optimize_gnc(PoseGraphProblem<Group>& problem, const GncOptions& options);

/// 0.99 quantile of chi-square with `dof` degrees of freedom, for dof 1..12 (table values).
double chi2_quantile_99(int dof);

}  // namespace cairn::backend
