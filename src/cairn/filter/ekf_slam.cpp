#include "cairn/filter/ekf_slam.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "cairn/core/assert.hpp"
#include "cairn/core/so2.hpp"

namespace cairn::filter {

bool EkfSlamOptions::is_valid(std::string* why) const {
  std::vector<std::string> problems;
  if (!(range_sigma_m > 0.0 && std::isfinite(range_sigma_m))) problems.emplace_back("range_sigma_m must be > 0");
  if (!(bearing_sigma_rad > 0.0 && std::isfinite(bearing_sigma_rad))) {
    problems.emplace_back("bearing_sigma_rad must be > 0");
  }
  if (!(min_range_m >= 0.0 && std::isfinite(min_range_m))) problems.emplace_back("min_range_m must be >= 0");
  if (why != nullptr) {
    why->clear();
    for (const auto& p : problems) *why += (why->empty() ? "" : "; ") + p;
  }
  return problems.empty();
}

Matrix2 EkfSlamOptions::measurement_covariance() const {
  Matrix2 R = Matrix2::Zero();
  R(0, 0) = range_sigma_m * range_sigma_m;
  R(1, 1) = bearing_sigma_rad * bearing_sigma_rad;
  return R;
}

EkfSlam::EkfSlam(const PoseVector& initial_pose, const Matrix3& initial_covariance,
                 const EkfSlamOptions& options)
    : options_(options), R_(options.measurement_covariance()), x_(initial_pose), P_(initial_covariance) {
  CAIRN_ASSERT(options.is_valid(nullptr), "EkfSlam: invalid options (check EkfSlamOptions::is_valid first)");
  x_(2) = core::wrap_angle(x_(2));
}

EkfSlam EkfSlam::from_state(const Eigen::VectorXd& state, const Eigen::MatrixXd& covariance,
                            const EkfSlamOptions& options) {
  CAIRN_ASSERT(state.size() >= 3 && state.size() % 2 == 1, "EkfSlam::from_state: the state must be a pose and 2D landmarks");
  CAIRN_ASSERT(covariance.rows() == state.size() && covariance.cols() == state.size(),
               "EkfSlam::from_state: the covariance must be square and match the state");
  EkfSlam ekf(PoseVector(state.head<3>()), Matrix3(covariance.topLeftCorner<3, 3>()), options);
  ekf.x_ = state;
  ekf.x_(2) = core::wrap_angle(ekf.x_(2));
  ekf.P_ = covariance;
  ekf.landmark_count_ = static_cast<std::size_t>((state.size() - 3) / 2);
  return ekf;
}

bool EkfSlam::is_valid_observation(const Vector2& z) const {
  return std::isfinite(z.x()) && std::isfinite(z.y()) && z.x() > options_.min_range_m;
}

Vector2 EkfSlam::landmark(std::size_t i) const { return x_.segment<2>(landmark_offset(i)); }

Matrix2 EkfSlam::landmark_covariance(std::size_t i) const {
  return P_.block<2, 2>(landmark_offset(i), landmark_offset(i));
}

Matrix23 EkfSlam::landmark_pose_covariance(std::size_t i) const { return P_.block<2, 3>(landmark_offset(i), 0); }

Matrix2 EkfSlam::landmark_landmark_covariance(std::size_t i, std::size_t j) const {
  return P_.block<2, 2>(landmark_offset(i), landmark_offset(j));
}

void EkfSlam::predict(const PoseVector& u, const Matrix3& Q) {
  Matrix3 F;
  Matrix3 G;
  x_.head<3>() = compose(x_.head<3>(), u, &F, &G);
  const Eigen::Index n = x_.size();
  // Only the pose rows and columns change (Thrun et al. 2005, Table 10.1).
  P_.topLeftCorner<3, 3>() = F * P_.topLeftCorner<3, 3>() * F.transpose() + G * Q * G.transpose();
  if (n > 3) {
    P_.topRightCorner(3, n - 3) = F * P_.topRightCorner(3, n - 3);
    P_.bottomLeftCorner(n - 3, 3) = P_.topRightCorner(3, n - 3).transpose();
  }
  ++counters_.predictions;
}

PredictedObservation EkfSlam::predict_observation(std::size_t i) const {
  CAIRN_ASSERT(i < landmark_count_, "EkfSlam::predict_observation: landmark index out of range");
  PredictedObservation out;
  out.z = range_bearing(x_.head<3>(), landmark(i), &out.J_z_pose, &out.J_z_landmark);
  const Eigen::Index l = landmark_offset(i);
  const Matrix3 P_pp = P_.topLeftCorner<3, 3>();
  const Matrix23 P_lp = P_.block<2, 3>(l, 0);
  const Matrix2 P_ll = P_.block<2, 2>(l, l);
  const Matrix2 cross = out.J_z_pose * P_lp.transpose() * out.J_z_landmark.transpose();
  out.S = out.J_z_pose * P_pp * out.J_z_pose.transpose() + cross + cross.transpose() +
          out.J_z_landmark * P_ll * out.J_z_landmark.transpose() + R_;
  return out;
}

double EkfSlam::mahalanobis_squared(std::size_t i, const Vector2& z) const {
  const PredictedObservation prediction = predict_observation(i);
  const Vector2 nu = innovation(z, prediction.z);
  return nu.dot(prediction.S.ldlt().solve(nu));
}

bool EkfSlam::update(std::size_t i, const Vector2& z) {
  if (i >= landmark_count_ || !is_valid_observation(z)) {
    ++counters_.rejected_invalid;
    return false;
  }
  const Eigen::Index l = landmark_offset(i);
  if ((landmark(i) - x_.head<2>()).norm() <= options_.min_range_m) {
    // The prediction is singular (the robot stands on the landmark's estimate).
    ++counters_.rejected_invalid;
    return false;
  }
  const PredictedObservation prediction = predict_observation(i);
  const std::array<Eigen::Index, 5> columns = {0, 1, 2, l, l + 1};
  Eigen::Matrix<double, 2, 5> H;
  H << prediction.J_z_pose, prediction.J_z_landmark;
  const Eigen::Index n = x_.size();

  // P H^T uses only the five columns of P that H touches: O(n).
  Eigen::Matrix<double, Eigen::Dynamic, 5> P_cols(n, 5);
  for (int c = 0; c < 5; ++c) P_cols.col(c) = P_.col(columns[static_cast<std::size_t>(c)]);
  const Eigen::Matrix<double, Eigen::Dynamic, 2> PHt = P_cols * H.transpose();
  const Matrix2 S = prediction.S;
  const Eigen::Matrix<double, Eigen::Dynamic, 2> K = PHt * S.inverse();
  const Vector2 nu = innovation(z, prediction.z);

  x_ += K * nu;
  x_(2) = core::wrap_angle(x_(2));

  // Joseph form, P <- (I - K H) P (I - K H)^T + K R K^T, in O(n^2):
  //   A = (I - K H) P = P - K (P H^T)^T;  A (I - K H)^T = A - (A H^T) K^T.
  P_.noalias() -= K * PHt.transpose();
  Eigen::Matrix<double, Eigen::Dynamic, 5> A_cols(n, 5);
  for (int c = 0; c < 5; ++c) A_cols.col(c) = P_.col(columns[static_cast<std::size_t>(c)]);
  const Eigen::Matrix<double, Eigen::Dynamic, 2> AHt = A_cols * H.transpose();
  P_.noalias() -= AHt * K.transpose();
  P_.noalias() += K * R_ * K.transpose();
  // Symmetrise in place (no n x n temporary: at thousands of landmarks one would cost more than
  // the update), in 64 x 64 tiles for the cache.
  constexpr Eigen::Index kTile = 64;
  for (Eigen::Index j0 = 0; j0 < n; j0 += kTile) {
    for (Eigen::Index i0 = j0; i0 < n; i0 += kTile) {
      const Eigen::Index jn = std::min(kTile, n - j0);
      const Eigen::Index in = std::min(kTile, n - i0);
      for (Eigen::Index col = j0; col < j0 + jn; ++col) {
        for (Eigen::Index row = std::max(i0, col + 1); row < i0 + in; ++row) {
          const double mean = 0.5 * (P_(row, col) + P_(col, row));
          P_(row, col) = mean;
          P_(col, row) = mean;
        }
      }
    }
  }
  ++counters_.updates;
  return true;
}

std::optional<std::size_t> EkfSlam::add_landmark(const Vector2& z) {
  if (!is_valid_observation(z)) {
    ++counters_.rejected_invalid;
    return std::nullopt;
  }
  Matrix23 G_p;
  Matrix2 G_z;
  const Vector2 p = landmark_from_range_bearing(x_.head<3>(), z, &G_p, &G_z);
  const Eigen::Index n = x_.size();
  x_.conservativeResize(n + 2);
  x_.tail<2>() = p;
  Eigen::MatrixXd P_new(n + 2, n + 2);
  P_new.topLeftCorner(n, n) = P_;
  // Cross-covariance with everything already in the state: G_p P_p,x (Dissanayake et al. 2001).
  const Eigen::MatrixXd P_lx = G_p * P_.topRows(3);
  P_new.bottomLeftCorner(2, n) = P_lx;
  P_new.topRightCorner(n, 2) = P_lx.transpose();
  P_new.bottomRightCorner<2, 2>() =
      G_p * P_.topLeftCorner<3, 3>() * G_p.transpose() + G_z * R_ * G_z.transpose();
  P_ = std::move(P_new);
  ++counters_.landmarks_added;
  return landmark_count_++;
}

}  // namespace cairn::filter
