#pragma once
/// \file
/// The landmark SLAM pipeline: EKF-SLAM (cairn::filter) or graph SLAM
/// (backend::LandmarkGraph2D) on the same odometry and range-bearing observations, with known or
/// unknown data association, scored against ground truth (ATE, landmark error, NEES).
/// See docs/landmark-slam.md.
///
/// Steps are the distinct observation times (plus the first odometry time); the motion between
/// two steps is the dead-reckoning increment u = T_odom_a^-1 T_odom_b with the covariance of
/// OdometryNoiseModel.
///
/// Unknown association (nn, jcbb): observations are associated in the EKF (individual gate, then
/// NN or JCBB). An unpaired observation becomes a tentative landmark; it enters the map only
/// after `confirmations_to_create` unpaired observations (from distinct steps) within
/// `candidate_match_distance_m` of each other (world frame, at the current pose estimate) within
/// `candidate_lifetime_s`;
/// candidates that expire are counted as rejected. Graph SLAM with unknown association uses the
/// associations the EKF front end made (the graph itself does not re-associate).

#include <functional>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/backend/landmark_graph.hpp"
#include "cairn/filter/data_association.hpp"
#include "cairn/filter/ekf_slam.hpp"
#include "cairn/landmarks/landmark_run.hpp"

namespace cairn::landmarks {

enum class Method { kEkf, kGraph };
enum class Association { kKnown, kNearestNeighbour, kJcbb };

std::string_view to_string(Method method);
std::string_view to_string(Association association);
std::optional<Method> method_from_name(std::string_view name);            ///< "ekf", "graph"
std::optional<Association> association_from_name(std::string_view name);  ///< "known", "nn", "jcbb"

/// Covariance of an odometry increment u = (dx, dy, dtheta) over distance d = |(dx, dy)|: the
/// simulator's white-noise model (docs/simulation.md, "Wheel odometry") without its biases:
///   diag(sf^2 d, sl^2 d, syr^2 |dtheta| + sym^2 d) * inflation + floor^2.
/// The simulator also has a 1% scale error, a 0.5% yaw scale error and slips, which this model
/// does not know about: `inflation` > 1 is the usual (crude) remedy.
struct OdometryNoiseModel {
  double forward_sigma_m_per_sqrt_m = 0.02;
  double lateral_sigma_m_per_sqrt_m = 0.005;
  double yaw_sigma_rad_per_sqrt_rad = 0.02;
  double yaw_sigma_rad_per_sqrt_m = 0.008;
  /// Multiplies every variance (>= 1 in practice; > 0).
  double inflation = 1.0;
  /// Standard deviation added to every axis so a standstill is not a zero covariance (m or rad, > 0).
  double floor_sigma = 1e-4;

  Matrix3 covariance(const Vector3& u) const;
  bool is_valid(std::string* why) const;
};

struct LandmarkSlamOptions {
  Method method = Method::kEkf;
  Association association = Association::kKnown;
  OdometryNoiseModel odometry;
  /// Range / bearing noise (defaults: the simulator's sensor, 0.05 m and 0.01 rad).
  filter::EkfSlamOptions sensor;
  /// Gates and JCBB limits (default gate probability 0.99).
  filter::AssociationOptions gating;
  /// Unknown association: unpaired observations (at most one per step) needed to create a
  /// landmark (>= 1). A real landmark in view is seen at nearly every step (detection 0.95 at
  /// 10 Hz in the simulator); uniform clutter almost never lands 5 times on one spot in 1 s.
  int confirmations_to_create = 5;
  /// Unknown association: unpaired observations this close (world frame, metres) support the
  /// same tentative landmark (> 0).
  double candidate_match_distance_m = 0.5;
  /// Unknown association: a tentative landmark not confirmed within this long is dropped, seconds (> 0).
  double candidate_lifetime_s = 1.0;
  /// Graph SLAM's Levenberg-Marquardt settings.
  backend::LandmarkGraphOptions graph;
  /// Graph SLAM: number of prefixes of the run (evenly spaced, the last one the whole run) solved
  /// to measure NEES over time at the prefix's last pose (>= 1). The EKF reports NEES at the same steps.
  int nees_checkpoints = 8;
  /// Graph SLAM: also solve the growing graph (warm-started) every this many steps between the
  /// checkpoints, so that new poses and landmarks are placed from a recent optimum instead of
  /// from a long stretch of dead reckoning (>= 0; 0 = only at the checkpoints). The default,
  /// 100 steps (10 s at the simulator's 10 Hz), removes the wrong minima that solving only at
  /// 8 checkpoints reached with very large heading noise (test PeriodicGraphSolves*).
  int graph_solve_every_steps = 100;
  /// Polled once per step (not a setting of the estimate): true ends the run after the step
  /// before; the result is that of the run up to there (graph SLAM: solved once more on the
  /// graph built so far) and LandmarkSlamReport::interrupted says so. The CLI stops on
  /// SIGINT/SIGTERM this way. May be empty.
  std::function<bool()> should_stop;

  /// Every problem, "; "-separated.
  bool is_valid(std::string* why) const;
};

/// How the observations were used. With known association every valid observation is
/// "correct" (it names its landmark). With unknown association each estimated landmark stands
/// for the true landmark nearest to its final estimate (within 1 m; none: "from spurious"), and
/// a pairing is correct when the observation came from that true landmark.
struct AssociationCounts {
  std::size_t observations = 0;
  std::size_t spurious_observations = 0;     ///< marked kSpuriousId in the input (injected clutter)
  std::size_t rejected_invalid = 0;          ///< non-finite, range too short
  std::size_t paired_correct = 0;            ///< paired with a landmark made from the same true landmark
  std::size_t paired_wrong = 0;              ///< paired with another landmark (includes spurious ones paired)
  std::size_t spurious_paired = 0;           ///< of paired_wrong: clutter accepted as a landmark observation
  std::size_t spurious_rejected = 0;         ///< clutter left unpaired and never confirmed as a landmark
  std::size_t true_unpaired = 0;             ///< real observations left unpaired (new landmark, candidates)
  std::size_t landmarks_created = 0;
  std::size_t landmarks_from_spurious = 0;   ///< created from clutter
  std::size_t landmarks_duplicated = 0;      ///< a second (third...) landmark for the same true landmark
  std::size_t candidates_expired = 0;        ///< tentative landmarks dropped
  std::size_t jcbb_truncated_searches = 0;
  std::size_t jcbb_nodes = 0;
};

/// NEES at one step (NaN where unavailable).
struct NeesPoint {
  std::size_t step = 0;
  double time_s = 0.0;
  /// Pose (x, y, theta) NEES: chi^2 with 3 dof if consistent.
  double pose_nees = 0.0;
  /// Mean over the landmarks with a true position of their 2-dof NEES.
  double landmark_nees_mean = 0.0;
  std::size_t landmarks_evaluated = 0;
};

struct LandmarkEstimate {
  /// The true landmark id this estimate stands for, for scoring only (known association: the id;
  /// unknown: see AssociationCounts), or kSpuriousId.
  std::int64_t id = 0;
  Vector2 p_world = Vector2::Zero();
  Matrix2 covariance = Matrix2::Zero();
  std::size_t observations = 0;
};

struct LandmarkSlamReport {
  std::string method;
  std::string association;
  std::string source;
  std::size_t steps = 0;        ///< steps processed (all of the run unless interrupted)
  std::size_t steps_in_run = 0;
  bool interrupted = false;     ///< LandmarkSlamOptions::should_stop ended it early
  std::size_t landmarks = 0;
  /// Position error of the trajectory against ground truth at matching times, no alignment
  /// (both in the world frame); EKF: the filtered estimate at each step; graph: the smoothed one.
  /// NaN without ground truth.
  double ate_rmse_m = 0.0;
  double ate_max_m = 0.0;
  std::size_t ate_poses = 0;
  double final_position_error_m = 0.0;
  double final_heading_error_rad = 0.0;
  /// RMS position error of the final map's landmarks against the true map (by id).
  double landmark_rmse_m = 0.0;
  /// NEES at the checkpoints (see LandmarkSlamOptions::nees_checkpoints).
  std::vector<NeesPoint> nees;
  /// EKF only: mean pose NEES over every step with ground truth (NaN for graph).
  double mean_pose_nees_all_steps = 0.0;
  AssociationCounts association_counts;
  filter::EkfSlamCounters ekf_counters;
  /// Graph only: the final solve.
  backend::LandmarkGraphSummary graph_summary;
  /// Graph only: solves of the growing graph (checkpoints + graph_solve_every_steps ones).
  std::size_t graph_solves = 0;
  /// Wall time: whole run, EKF steps (mean / max per step), graph solves (all of them, and
  /// the final one alone), seconds.
  double total_time_s = 0.0;
  double ekf_time_s = 0.0;
  double ekf_mean_step_s = 0.0;
  double ekf_max_step_s = 0.0;
  double graph_time_s = 0.0;
  double graph_final_solve_s = 0.0;
};

struct LandmarkSlamResult {
  /// T_world_body at each step.
  std::vector<TimedPose> trajectory;
  std::vector<LandmarkEstimate> landmarks;
  LandmarkSlamReport report;
};

/// Runs the method on `run`. Precondition: options.is_valid(). Expected failures (a graph that
/// does not converge) are reported in report.graph_summary, never thrown.
LandmarkSlamResult run_landmark_slam(const LandmarkRun& run, const LandmarkSlamOptions& options);

}  // namespace cairn::landmarks
