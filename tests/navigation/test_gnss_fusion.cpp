// GnssInertialOdometry in simulation: a planar drive (sim/trajectory, sim/planar_kinematics) with
// the simulated ADIS16448-class IMU (sim/imu), wheel odometry (sim/odometry's WheelOdometry, its
// forward speed) and a 5 Hz GNSS receiver (sim/gnss_receiver) with a 60 s dropout and 5 % outliers
// of 10-50 m. The truth is the simulator's; nothing expected is computed by the code under test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <random>

#include "cairn/core/so3.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/navigation/gnss_inertial_odometry.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/navigation/navigation_factors.hpp"
#include "cairn/navigation/navigation_outputs.hpp"
#include "cairn/sim/gnss_receiver.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/sim/odometry.hpp"
#include "cairn/sim/planar_kinematics.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::navigation {
namespace {

core::SE3 lift(const core::SE2& T) {
  return core::SE3(core::SO3::from_rpy(0.0, 0.0, T.angle()), Vector3(T.translation().x(), T.translation().y(), 0.0));
}

/// Numeric Jacobian of `factor` w.r.t. variable v (pose: se3 plus, else additive) by central differences.
Eigen::MatrixXd numeric_jacobian(const backend::Factor& factor, std::vector<std::vector<double>> values, int v) {
  const backend::Manifold& manifold = v == 0 ? backend::se3_manifold() : backend::euclidean_manifold(3);
  const int n = manifold.tangent_size();
  const int m = factor.residual_size();
  Eigen::MatrixXd J(m, n);
  const double h = 1e-6;
  for (int j = 0; j < n; ++j) {
    Eigen::VectorXd rp(m), rm(m);
    for (const double sign : {1.0, -1.0}) {
      auto shifted = values;
      Eigen::VectorXd delta = Eigen::VectorXd::Zero(n);
      delta[j] = sign * h;
      manifold.plus(values[static_cast<std::size_t>(v)].data(), delta.data(), shifted[static_cast<std::size_t>(v)].data());
      const double* ptrs[2] = {shifted[0].data(), shifted[1].data()};
      factor.evaluate(ptrs, sign > 0 ? rp.data() : rm.data(), nullptr);
    }
    J.col(j) = (rp - rm) / (2.0 * h);
  }
  return J;
}

void expect_jacobians_match(const backend::Factor& factor, std::mt19937& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  const Vector3 phi(normal(rng), normal(rng), normal(rng));
  const core::SE3 T(core::SO3::exp(phi), Vector3(normal(rng), normal(rng), normal(rng)) * 10.0);
  std::vector<std::vector<double>> values(2);
  values[0].resize(7);
  backend::se3_to_values(T, values[0].data());
  values[1] = {3.0 * normal(rng), 3.0 * normal(rng), normal(rng)};
  Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J0;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J1;
  double* jacobians[2] = {J0.data(), J1.data()};
  const double* ptrs[2] = {values[0].data(), values[1].data()};
  Vector3 r;
  ASSERT_TRUE(factor.evaluate(ptrs, r.data(), jacobians));
  EXPECT_LT((Eigen::MatrixXd(J0) - numeric_jacobian(factor, values, 0)).cwiseAbs().maxCoeff(), 1e-5);
  EXPECT_LT((Eigen::MatrixXd(J1) - numeric_jacobian(factor, values, 1)).cwiseAbs().maxCoeff(), 1e-5);
}

TEST(NavigationFactors, AnalyticJacobiansMatchNumericOnes) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const core::SE3 T_imu_vehicle(core::SO3::exp(Vector3(normal(rng), normal(rng), normal(rng))),
                                  Vector3(normal(rng), normal(rng), normal(rng)));
    const WheelVelocityFactor wheel(normal(rng), Vector3(0.05, 0.1, 0.2), Vector3(normal(rng), normal(rng), normal(rng)),
                                    T_imu_vehicle);
    expect_jacobians_match(wheel, rng);
    Matrix3 A = Matrix3::Random();
    const Matrix3 covariance = A * A.transpose() + Matrix3::Identity() * 0.1;
    ShiftedGnssFactor fix(std::make_unique<gnss::GnssPositionFactor>(Vector3(normal(rng), normal(rng), normal(rng)), covariance,
                                                                      Vector3(normal(rng), normal(rng), normal(rng)),
                                                                      core::SE3(core::SO3::exp(Vector3(0, 0, normal(rng))), Vector3::Ones())),
                          0.05 * normal(rng));
    expect_jacobians_match(fix, rng);
  }
}

TEST(NavigationFactors, WheelResidualIsZeroForAVehicleDrivingStraightAhead) {
  // Vehicle 0.5 m ahead of the IMU, rotated 90 deg about z; the IMU yawing at 0.2 rad/s.
  const core::SE3 T_imu_vehicle(core::SO3::from_rpy(0.0, 0.0, M_PI / 2.0), Vector3(0.5, 0.0, 0.0));
  const Vector3 omega(0.0, 0.0, 0.2);
  const core::SE3 T_world_imu(core::SO3::from_rpy(0.0, 0.0, 0.3), Vector3(1.0, 2.0, 0.0));
  // Vehicle forward (its x) is the IMU's y; the IMU's velocity is the vehicle's minus omega x r.
  const Vector3 v_vehicle_imu_frame = Vector3(0.0, 2.0, 0.0);
  const Vector3 v_imu_imu_frame = v_vehicle_imu_frame - omega.cross(Vector3(0.5, 0.0, 0.0));
  const WheelVelocityFactor factor(2.0, Vector3(0.1, 0.1, 0.1), omega, T_imu_vehicle);
  EXPECT_LT((factor.vehicle_velocity(T_world_imu, T_world_imu.so3() * v_imu_imu_frame) - Vector3(2.0, 0.0, 0.0)).norm(), 1e-12);
}

TEST(GnssInertialOdometryOptions, ReportsEveryProblem) {
  GnssInertialOdometryOptions options;
  EXPECT_TRUE(options.is_valid(nullptr));
  options.state_period_s = 0.0;
  options.window_states = 1;
  options.nonholonomic_sigma_mps = -1.0;
  std::string why;
  EXPECT_FALSE(options.is_valid(&why));
  EXPECT_NE(why.find("state_period_s"), std::string::npos);
  EXPECT_NE(why.find("window_states"), std::string::npos);
  EXPECT_NE(why.find("nonholonomic_sigma_mps"), std::string::npos);
  EXPECT_THROW(GnssInertialOdometry{options}, std::invalid_argument);
}

/// The simulated run: truth, IMU, wheel speeds, fixes.
struct SimulatedDrive {
  std::vector<sim::TrajectorySample> truth;
  std::unique_ptr<sim::PlanarKinematics> kinematics;
  sim::SimulatedImu imu;
  std::vector<WheelSpeed> wheels;
  sim::SimulatedGnss gnss;
  core::SE3 T_enu_world;
  double dropout_start_s = 0.0, dropout_end_s = 0.0;
};

constexpr double kRestS = 3.0;     // still before the drive: static initialisation
constexpr double kWheelPeriodS = 0.1;

/// Wheel speeds every 0.1 s from the sensor model of sim/odometry.hpp (its default noise: 1 % scale
/// error, slips), reported with the variance the model gives a step of that length.
std::vector<WheelSpeed> simulate_wheels(const sim::PlanarKinematics& kinematics, double end_s, const sim::OdometryNoise& noise) {
  sim::WheelOdometry sensor(noise, 11);
  std::vector<WheelSpeed> wheels;
  auto planar = [&](double t) {
    const core::SE3 T = kinematics(t).T_world_body;
    return core::SE2(T.translation().x(), T.translation().y(), T.so3().log().z());
  };
  core::SE2 previous = planar(-kRestS);
  for (double t = -kRestS + kWheelPeriodS; t <= end_s + 1e-9; t += kWheelPeriodS) {
    const core::SE2 now = planar(t);
    const core::SE2 measured = sensor.measure(previous.inverse() * now, kWheelPeriodS);
    const double distance = (previous.inverse() * now).translation().norm();
    const double variance = noise.forward_sigma_m_per_sqrt_m * noise.forward_sigma_m_per_sqrt_m * distance /
                            (kWheelPeriodS * kWheelPeriodS);
    wheels.push_back({core::Timestamp::from_seconds(t), measured.translation().x() / kWheelPeriodS, variance});
    previous = now;
  }
  return wheels;
}

SimulatedDrive simulate_drive() {
  SimulatedDrive d;
  sim::TrajectoryOptions trajectory;
  trajectory.laps = 1;
  trajectory.max_speed_mps = 1.0;
  trajectory.corner_radius_m = 4.0;
  trajectory.max_yaw_rate_rad_s = 0.3;
  d.truth = sim::generate_trajectory({{0, 0}, {90, 0}, {90, 50}, {20, 60}, {0, 40}}, trajectory);
  const double end_s = d.truth.back().stamp.seconds();
  d.kinematics = std::make_unique<sim::PlanarKinematics>(d.truth);
  sim::ImuSimulationOptions imu = *sim::imu_preset("adis16448");
  imu.seed = 3;
  d.imu = sim::simulate_imu(*d.kinematics, -kRestS, end_s, imu);
  d.wheels = simulate_wheels(*d.kinematics, end_s, sim::OdometryNoise{});
  sim::GnssReceiverOptions receiver;
  d.T_enu_world = core::SE3(core::SO3::from_rpy(0.0, 0.0, 0.8), Vector3(30.0, -20.0, 2.0));
  receiver.T_enu_world = d.T_enu_world;
  receiver.lever_arm_body_m = Vector3(-0.3, 0.0, 1.2);
  d.dropout_start_s = 150.0;
  d.dropout_end_s = 210.0;
  receiver.dropouts_s = {{d.dropout_start_s, d.dropout_end_s}};
  receiver.outlier_fraction = 0.05;
  receiver.outlier_min_m = 10.0;
  receiver.outlier_max_m = 50.0;
  receiver.seed = 5;
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> poses;
  for (const auto& s : d.truth) {
    stamps.push_back(s.stamp);
    poses.push_back(lift(s.T_world_body));
  }
  d.gnss = sim::simulate_gnss_receiver(stamps, poses, receiver);
  return d;
}

TEST(GnssInertialOdometry, SimulatedDriveWithDropoutAndOutliersStaysWithinOneMetre) {
  const SimulatedDrive drive = simulate_drive();
  GnssInertialOdometryOptions options;
  options.noise = sim::imu_preset("adis16448")->noise;
  options.gnss.lever_arm_body_m = Vector3(-0.3, 0.0, 1.2);
  options.initial_gyro_bias_sigma_rad_s = 0.1;  // the simulator draws N(0, 0.04^2) per axis
  GnssInertialOdometry odometry(options);
  run_in_time_order(odometry, drive.imu.samples, drive.wheels, drive.gnss.fixes);
  const NavigationSummary summary = odometry.summary();
  ASSERT_TRUE(summary.ok()) << summary.message;
  // The truth in the estimator's ENU frame (at the first fix), from the receiver's (at its origin).
  const gnss::LocalFrame receiver_frame(sim::GnssReceiverOptions{}.origin);
  ASSERT_TRUE(summary.enu_origin.has_value());
  const gnss::LocalFrame estimator_frame(*summary.enu_origin);
  double max_error_m = 0.0, max_error_time_s = 0.0, max_dropout_error_m = 0.0, max_before_alignment_m = 0.0;
  for (const NavigationState& s : odometry.states()) {
    const Vector3 truth = estimator_frame.forward(receiver_frame.reverse(
        (drive.T_enu_world * drive.kinematics->operator()(s.time_s).T_world_body).translation()));
    const double error = (s.state.T_world_body.translation() - truth).head<2>().norm();
    if (s.time_s < summary.alignment_time_s) {  // dead reckoning placed by the yaw fit: reported, not bounded
      max_before_alignment_m = std::max(max_before_alignment_m, error);
      continue;
    }
    if (error > max_error_m) {
      max_error_m = error;
      max_error_time_s = s.time_s;
    }
    if (s.time_s >= drive.dropout_start_s && s.time_s <= drive.dropout_end_s) max_dropout_error_m = std::max(max_dropout_error_m, error);
  }
  std::size_t outliers = 0, caught = 0, false_rejections = 0, good = 0;
  const auto& results = odometry.fix_results();
  ASSERT_EQ(results.size(), drive.gnss.fixes.size());
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (drive.gnss.outlier[i]) {
      ++outliers;
      if (results[i].outlier) ++caught;
    } else {
      ++good;
      if (results[i].outlier) ++false_rejections;
    }
  }
  std::printf("states %zu, fixes %zu (used %zu), outliers %zu caught %zu, false rejections %zu of %zu good, "
              "aligned at %.1f s (yaw sigma %.2f deg), max horizontal error %.3f m at %.1f s, in the dropout %.3f m, before the alignment %.3f m, "
              "solve %.2f s (max step %.1f ms)\n",
              summary.states, summary.fixes_received, summary.fixes_used, outliers, caught, false_rejections, good,
              summary.alignment_time_s, summary.alignment.yaw_sigma_rad * 180.0 / M_PI, max_error_m, max_error_time_s,
              max_dropout_error_m, max_before_alignment_m, summary.solve_s, summary.max_step_s * 1e3);
  EXPECT_LT(max_error_m, 1.0);
  EXPECT_GT(outliers, 20u);
  EXPECT_EQ(caught, outliers);
  EXPECT_LE(false_rejections, good / 100);
  // The dropout is reported: one gap of about 60 s.
  bool found = false;
  for (const auto& gap : summary.dropouts) found = found || std::abs(gap.duration_s - 60.0) < 1.0;
  EXPECT_TRUE(found);

  // The outputs: the report lists every fix with its verdict, the CSV one line per state.
  const nlohmann::json report = navigation_report_json(summary, results);
  EXPECT_EQ(report["summary"]["outliers"].get<std::size_t>(), summary.outliers);
  ASSERT_EQ(report["fixes"].size(), results.size());
  EXPECT_EQ(report["fixes"][0]["outlier"].get<bool>(), results[0].outlier);
  const std::string csv = (std::filesystem::temp_directory_path() / "cairn_test_navigation_states.csv").string();
  write_navigation_states_csv(csv, odometry.states());
  std::ifstream in(csv);
  std::size_t lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, odometry.states().size() + 1);
  std::filesystem::remove(csv);
  EXPECT_THROW(write_navigation_states_csv("/nonexistent-dir/x.csv", odometry.states()), io::ParseError);
}

}  // namespace
}  // namespace cairn::navigation
