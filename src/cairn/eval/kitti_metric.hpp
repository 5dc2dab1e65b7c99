#pragma once
/// \file
/// The KITTI odometry metric, exactly as the official devkit computes it
/// (devkit/cpp/evaluate_odometry.cpp; read in GitHub xiongxoy/xiong-viso, which carries the
/// devkit unmodified in its metric part):
///
///  - trajectoryDistances: D_0 = 0, D_i = D_{i-1} + |p_i - p_{i-1}| over the GROUND TRUTH
///    positions, accumulated in single precision (float), as the devkit does.
///  - calcSequenceErrors: start frames 0, 10, 20, ... (step_size = 10, "every second" at
///    10 Hz); for each start and each length L in {100, ..., 800} m,
///    lastFrameFromSegmentLength: the first frame i >= start with D_i > D_start + L (strictly);
///    none -> that (start, L) is skipped.
///  - pose error E = (P_s^-1 P_l)^-1 (G_s^-1 G_l) with G ground truth, P result.
///    rotationError = acos(clamp(0.5 (tr R(E) - 1), -1, 1)) [rad], translationError = |t(E)|
///    [m], both evaluated in float as the devkit does; each divided by the NOMINAL length L
///    (not the segment's actual path length): r_err [rad/m], t_err [m/m].
///    speed = L / (0.1 s * (l - s + 1)) [m/s].
///  - saveStats: t_err and r_err are the plain means over all segments (float sums), written
///    as m/m and rad/m. The benchmark table shows t_err in % (x 100); we also give r_err in
///    deg/100 m (x 180/pi x 100) and deg/m. (The devkit's own plots multiply by 57.3.)
///  - saveErrorPlots: per nominal length, the mean over segments with |len - L| < 1, written
///    only when at least 3 segments fall in it.
///
/// Poses pair by index (the devkit requires equally long files); with timestamps on both
/// sides they are associated first (association.hpp). Like the devkit, the matrices are used as
/// read (read_kitti_matrices) and inverted as general 4x4 matrices (its Matrix::inv).

#include <cstddef>
#include <vector>

#include "cairn/eval/association.hpp"
#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

struct KittiOptions {
  /// Nominal segment lengths, metres, each > 0. Default: the devkit's 100, 200, ..., 800.
  std::vector<double> lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};
  /// Frames between segment starts, >= 1. Default 10 (devkit step_size).
  std::size_t step_frames = 10;
  /// Time between frames for the speed column, seconds, > 0. Default 0.1 (KITTI's 10 Hz).
  double frame_period_s = 0.1;
  /// Used only when both trajectories have timestamps.
  AssociationOptions association;

  /// True when usable; otherwise false with every problem, "; "-separated, in *why (core/problems.hpp).
  bool is_valid(std::string* why) const;
};

/// One line of the devkit's errors/NN.txt.
struct KittiSegment {
  std::size_t first_frame = 0;
  std::size_t last_frame = 0;
  /// Nominal length L, metres.
  double length_m = 0;
  /// rotationError / L, rad/m (a float value, as the devkit's).
  double rotation_error_rad_per_m = 0;
  /// translationError / L, m/m (a float value).
  double translation_error_m_per_m = 0;
  double speed_m_per_s = 0;
};

/// Mean errors of the segments of one nominal length (the devkit's NN_tl.txt / NN_rl.txt).
struct KittiLengthError {
  double length_m = 0;
  std::size_t segments = 0;
  double translation_error_m_per_m = 0;
  double rotation_error_rad_per_m = 0;
  /// The devkit writes a length only with at least 3 segments.
  bool reported_by_devkit = false;
};

struct KittiResult {
  Outcome outcome;
  Association association;
  /// Paired poses (ground truth, result).
  std::vector<Matrix4> reference;
  std::vector<Matrix4> estimate;
  /// Ground-truth path length at each paired frame (float accumulation), metres.
  std::vector<double> path_length_m;
  std::vector<KittiSegment> segments;
  std::vector<KittiLengthError> per_length;
  /// stats.txt: mean t_err (m/m) and r_err (rad/m) over all segments.
  double translation_error_m_per_m = 0;
  double rotation_error_rad_per_m = 0;

  double translation_error_percent() const { return 100.0 * translation_error_m_per_m; }
  double rotation_error_deg_per_m() const;
  double rotation_error_deg_per_100m() const { return 100.0 * rotation_error_deg_per_m(); }
};

/// calcSequenceErrors on paired poses. Precondition: equal sizes, options valid.
std::vector<KittiSegment> kitti_segments(const std::vector<Matrix4>& ground_truth,
                                         const std::vector<Matrix4>& result, const KittiOptions& options,
                                         std::vector<double>* path_length_m = nullptr);

/// Pairs, computes the segments and the devkit's averages. kNoPairs when the ground truth is
/// shorter than the shortest length (no segment at all).
KittiResult evaluate_kitti(const MatrixTrajectory& ground_truth, const MatrixTrajectory& result,
                           const KittiOptions& options = {});

}  // namespace cairn::eval
