#pragma once
/// \file
/// EKF-SLAM: one joint Gaussian over the robot pose and every landmark (Smith, Self & Cheeseman
/// 1990, "Estimating uncertain spatial relationships in robotics"; the stochastic map of their
/// 1986 report; Dissanayake et al. 2001 for the landmark form used here).
///
/// State x = (x, y, theta, p_0x, p_0y, p_1x, p_1y, ...): T_world_body as a vector, then the
/// landmarks in the world frame in the order they were added. Covariance P is dense, so every
/// update costs O(n^2) in the state size n: the scaling that made graph SLAM take over.
///
/// * predict(): x <- f(x, u), P_pp <- F P_pp F^T + G Q G^T, P_pm <- F P_pm (only the pose rows
///   change: O(n)).
/// * update(): the EKF update with the Joseph form P <- (I - K H) P (I - K H)^T + K R K^T
///   (Bucy & Joseph 1968; Bar-Shalom et al. 2001, Sec. 5.2), evaluated in O(n^2) using that
///   H has only five non-zero columns.
/// * add_landmark(): state augmentation from the first observation, p = g(x_pose, z), with the
///   full cross-covariance P_lx = G_p P_px and P_ll = G_p P_pp G_p^T + G_z R G_z^T
///   (Dissanayake et al. 2001; Thrun et al. 2005, Ch. 10).
///
/// Bad observations (non-finite, range <= min_range_m, unknown landmark index) are refused and
/// counted (EkfSlamCounters); the state is untouched.

#include <cstddef>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "cairn/filter/range_bearing.hpp"

namespace cairn::filter {

struct EkfSlamOptions {
  /// Range noise standard deviation, metres (> 0). Default: the simulator's landmark sensor.
  double range_sigma_m = 0.05;
  /// Bearing noise standard deviation, radians (> 0). Default: the simulator's landmark sensor.
  double bearing_sigma_rad = 0.01;
  /// Observations with a range at or below this are refused (the bearing is meaningless), metres.
  double min_range_m = 1e-3;

  /// Every problem at once, "; "-separated, in `why`.
  bool is_valid(std::string* why) const;
  /// diag(range_sigma_m^2, bearing_sigma_rad^2).
  Matrix2 measurement_covariance() const;
};

struct EkfSlamCounters {
  std::size_t predictions = 0;
  std::size_t updates = 0;
  std::size_t landmarks_added = 0;
  /// Observations refused: non-finite or too short range, unknown landmark index.
  std::size_t rejected_invalid = 0;
};

/// The predicted observation of one landmark, with its Jacobians and innovation covariance
/// S = H P H^T + R.
struct PredictedObservation {
  Vector2 z = Vector2::Zero();
  Matrix23 J_z_pose = Matrix23::Zero();
  Matrix2 J_z_landmark = Matrix2::Zero();
  Matrix2 S = Matrix2::Identity();
};

class EkfSlam {
 public:
  /// Starts with no landmarks at `initial_pose` (T_world_body) with `initial_covariance`
  /// (zero: the pose defines the world frame). Precondition: options.is_valid().
  EkfSlam(const PoseVector& initial_pose, const Matrix3& initial_covariance, const EkfSlamOptions& options = {});

  /// Restores a filter from a full state (pose, then landmarks) and its covariance, e.g. a saved
  /// run or a benchmark's synthetic map. Precondition: state.size() == 3 + 2 k, covariance square
  /// of the same size and symmetric positive semi-definite.
  static EkfSlam from_state(const Eigen::VectorXd& state, const Eigen::MatrixXd& covariance,
                            const EkfSlamOptions& options = {});

  /// Motion by `u` (body frame, see range_bearing.hpp) with covariance `Q` (3x3 over u).
  void predict(const PoseVector& u, const Matrix3& Q);

  /// Update with observation `z` = (range, bearing) of landmark `landmark`. False (counted,
  /// state unchanged) when z is invalid or the index is out of range.
  bool update(std::size_t landmark, const Vector2& z);

  /// Adds a landmark initialised from observation `z`; its index, or nullopt (counted) when z is
  /// invalid.
  std::optional<std::size_t> add_landmark(const Vector2& z);

  /// Whether z is finite with range above min_range_m.
  bool is_valid_observation(const Vector2& z) const;

  std::size_t landmark_count() const { return landmark_count_; }
  PoseVector pose() const { return x_.head<3>(); }
  Matrix3 pose_covariance() const { return P_.topLeftCorner<3, 3>(); }
  Vector2 landmark(std::size_t i) const;
  Matrix2 landmark_covariance(std::size_t i) const;
  /// Cross-covariance block between the pose (rows) and landmark i.
  Matrix23 landmark_pose_covariance(std::size_t i) const;
  /// Cross-covariance block between landmarks i (rows) and j.
  Matrix2 landmark_landmark_covariance(std::size_t i, std::size_t j) const;
  const Eigen::VectorXd& state() const { return x_; }
  const Eigen::MatrixXd& covariance() const { return P_; }
  const EkfSlamCounters& counters() const { return counters_; }
  const EkfSlamOptions& options() const { return options_; }
  Matrix2 measurement_covariance() const { return R_; }

  /// The predicted observation of landmark i from the current mean, with S = H P H^T + R.
  /// Precondition: i < landmark_count() and the landmark is not at the robot's position.
  PredictedObservation predict_observation(std::size_t i) const;
  /// Squared Mahalanobis distance of `z` to landmark i's prediction (individual compatibility).
  double mahalanobis_squared(std::size_t i, const Vector2& z) const;

 private:
  static Eigen::Index landmark_offset(std::size_t i) { return 3 + 2 * static_cast<Eigen::Index>(i); }

  EkfSlamOptions options_;
  Matrix2 R_;
  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  std::size_t landmark_count_ = 0;
  EkfSlamCounters counters_;
};

}  // namespace cairn::filter
