#pragma once
/// \file
/// The Freiburg relations metric (Kuemmerle et al., "On measuring the accuracy of SLAM
/// algorithms", Autonomous Robots 27(4), 2009), as the benchmark's evaluator metricEvaluator
/// computes it (read in GitHub shiftlab-nanodrone/slam-metric-evaluator, metricEvaluator.cpp:
/// calcSlamRelationPoint, calcRelation, calcErrors):
///
///  - A relations file lists reference relative motions, one per line:
///    `t_i t_j x y z roll pitch yaw` = the pose at t_j seen from the pose at t_i (metres,
///    radians; 2D logs have z = roll = pitch = 0). Blank lines and '#' comments are skipped.
///  - For each relation time the estimated pose with the NEAREST timestamp is used (the first
///    on a tie); it must lie within max_time_difference_s (the evaluator's
///    g_MaxTimeRelationToSlam = 0.1 s). The evaluator then corrects far poses with odometry
///    or warns and goes on; cairn fails instead (kMissingPoses), naming the relations.
///  - The estimate is planar, as the evaluator reads it: each pose becomes (x, y, yaw) and
///    delta_ij = T(x_i)^-1 T(x_j) with T(x, y, yaw) a rotation about z.
///  - Error of one relation: the difference of (x, y, z, roll, pitch, yaw) of the estimated and
///    the reference relation, angles wrapped into (-pi, pi];
///      translational error = sqrt(dx^2 + dy^2 + dz^2) [m]
///      rotational error    = sqrt(droll^2 + dpitch^2 + dyaw^2) [rad] (= |wrap(dyaw)| in 2D)
///    (the evaluator's weights {1,1,1,0,0,0} and {0,0,0,1,1,1}).
///  - Reported as Hess et al. (ICRA 2016, Table II) report it: mean and standard deviation of
///    the absolute errors (m, deg) and of the squared errors (m^2, deg^2) over all relations.
///
/// Standard deviation: the population one (divide by N), as evo's. The evaluator's
/// Statistics class (statistics.h) is not in the mirror we read, so whether it divides by N
/// or N - 1 is unconfirmed; for ACES (N = 1279) the two differ by a factor 1.0004.

#include <cstddef>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/core/time.hpp"
#include "cairn/eval/status.hpp"
#include "cairn/eval/matrix_trajectory.hpp"
#include "cairn/io/carmen_log.hpp"

namespace cairn::eval {

struct Relation {
  core::Timestamp from;
  core::Timestamp to;
  /// x, y, z as written; rotation from roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)).
  Vector3 translation_m = Vector3::Zero();
  Vector3 roll_pitch_yaw_rad = Vector3::Zero();
  /// 1-based line in the relations file.
  std::size_t line = 0;
};

/// Reads a relations file. Throws io::ParseError naming file and line on a line without
/// exactly 8 numbers, a non-finite number, an unreadable time, or a file without relations.
std::vector<Relation> read_relations(const std::string& path);

/// The estimate in a (corrected) CARMEN log, as the evaluator reads it: one planar pose per
/// laser record, its T_odom_laser as a rotation about z and a translation in x, y, stamped with
/// its ipc_timestamp (the relations' times name these records). Throws io::ParseError naming
/// `path` (the log's file) and the record's line when a laser time does not follow the previous
/// one, and when the log has no laser record.
MatrixTrajectory relations_estimate_from_carmen(const io::CarmenLog& log, const std::string& path);

struct RelationsOptions {
  /// Largest |t_pose - t_relation| for the nearest estimated pose, seconds, >= 0.
  /// Default 0.1 s (the evaluator's g_MaxTimeRelationToSlam).
  double max_time_difference_s = 0.1;
};

/// Mean and (population) standard deviation.
struct MeanStd {
  double mean = 0;
  double std = 0;
  double min = 0;
  double max = 0;
};

struct RelationsResult {
  Outcome outcome;
  /// Per relation, in file order.
  std::vector<double> translation_errors_m;
  std::vector<double> rotation_errors_rad;
  /// Estimated pose indices used for each relation's two ends.
  std::vector<std::size_t> from_indices;
  std::vector<std::size_t> to_indices;
  /// Hess et al. 2016 Table II's four rows.
  MeanStd translation_absolute_m;
  MeanStd translation_squared_m2;
  MeanStd rotation_absolute_deg;
  MeanStd rotation_squared_deg2;
};

/// The metric above. Fails with kEmpty (no relations, no poses), kMissingStamps (estimate
/// without stamps), kUnsortedStamps, kNotFinite, kInvalidOptions, or kMissingPoses (a relation
/// time without a pose within the tolerance: the message counts them and names the first).
RelationsResult evaluate_relations(const std::vector<Relation>& relations, const MatrixTrajectory& estimate,
                                   const RelationsOptions& options = {});

}  // namespace cairn::eval
