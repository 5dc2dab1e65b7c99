// The simulated IMU (sim/imu.hpp) against closed forms and its own noise model's statistics; the
// planar ground truth's kinematics (sim/planar_kinematics.hpp) integrated by an independent
// strapdown integrator; the tunnel spin (sim/spin_stop.hpp, scenario tunnel-spin-3d).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <numbers>
#include <vector>

#include "cairn/core/so3.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/sim/planar_kinematics.hpp"
#include "cairn/sim/scenario.hpp"
#include "cairn/sim/spin_stop.hpp"

namespace cairn::sim {
namespace {

constexpr double kG = inertial::kStandardGravity;

ImuSimulationOptions noise_free(double rate_hz) {
  ImuSimulationOptions o;
  o.rate_hz = rate_hz;
  o.noise = inertial::ImuNoise{0.0, 0.0, 0.0, 0.0};
  o.initial_bias = inertial::ImuBias{};
  o.gyro_saturation_rad_s = 0.0;
  o.accel_saturation_mps2 = 0.0;
  return o;
}

/// A helix (radius 3 m, 0.5 rad/s, climbing 0.4 m/s) whose yaw follows the tangent while roll and
/// pitch oscillate: R_world_body = Rz(psi) Ry(theta) Rx(phi). Closed forms for every derivative.
struct Helix {
  static constexpr double kRadius = 3.0, kRate = 0.5, kClimb = 0.4, kRoll = 0.3, kPitch = 0.2;
  static double psi(double t) { return kRate * t + std::numbers::pi / 2; }
  static double phi(double t) { return kRoll * std::sin(2.0 * t); }
  static double theta(double t) { return kPitch * std::sin(3.0 * t); }
  static Vector3 position(double t) {
    return {kRadius * std::cos(kRate * t), kRadius * std::sin(kRate * t), kClimb * t};
  }
  static Matrix3 rotation(double t) {
    return (Eigen::AngleAxisd(psi(t), Vector3::UnitZ()) * Eigen::AngleAxisd(theta(t), Vector3::UnitY()) *
            Eigen::AngleAxisd(phi(t), Vector3::UnitX()))
        .toRotationMatrix();
  }
  static BodyKinematics at(double t) {
    BodyKinematics k;
    k.T_world_body = core::SE3(Quaternion(rotation(t)), position(t));
    const double w = kRate;
    k.v_world_mps = Vector3(-kRadius * w * std::sin(w * t), kRadius * w * std::cos(w * t), kClimb);
    k.a_world_mps2 = Vector3(-kRadius * w * w * std::cos(w * t), -kRadius * w * w * std::sin(w * t), 0.0);
    // Body rates of ZYX Euler angles (e.g. Diebel, "Representing attitude", 2006, eq. 290 family).
    const double dphi = 2.0 * kRoll * std::cos(2.0 * t);
    const double dtheta = 3.0 * kPitch * std::cos(3.0 * t);
    const double dpsi = w;
    const double sf = std::sin(phi(t)), cf = std::cos(phi(t)), st = std::sin(theta(t)), ct = std::cos(theta(t));
    k.omega_body_rad_s = Vector3(dphi - dpsi * st, dtheta * cf + dpsi * ct * sf, -dtheta * sf + dpsi * ct * cf);
    return k;
  }
};

TEST(SimulatedImu, NoiseFreeReadingsEqualTheHelixDerivativesAtSampleTimes) {
  const SimulatedImu imu = simulate_imu(&Helix::at, 1.0, 11.0, noise_free(200.0));
  ASSERT_EQ(imu.samples.size(), 2001u);
  ASSERT_EQ(imu.truth.size(), imu.samples.size());
  double worst_gyro = 0.0, worst_accel = 0.0;
  for (std::size_t k = 0; k < imu.samples.size(); k += 7) {
    const double t = 1.0 + 0.005 * static_cast<double>(k);
    EXPECT_EQ(imu.samples[k].stamp.nanoseconds(), 1'000'000'000LL + 5'000'000LL * static_cast<long long>(k));
    // Independent of the closed forms above: central differences of the pose.
    const double h = 1e-4;
    const Matrix3 R = Helix::rotation(t);
    const Matrix3 dR = (Helix::rotation(t + h) - Helix::rotation(t - h)) / (2.0 * h);
    const Matrix3 Omega = R.transpose() * dR;  // skew(omega_body)
    const Vector3 gyro(Omega(2, 1), Omega(0, 2), Omega(1, 0));
    const Vector3 a_world = (Helix::position(t + h) - 2.0 * Helix::position(t) + Helix::position(t - h)) / (h * h);
    const Vector3 accel = R.transpose() * (a_world + Vector3(0.0, 0.0, kG));
    worst_gyro = std::max(worst_gyro, (imu.samples[k].gyro_rad_s - gyro).norm());
    worst_accel = std::max(worst_accel, (imu.samples[k].accel_mps2 - accel).norm());
    EXPECT_LT((imu.truth[k].state.T_world_body.translation() - Helix::position(t)).norm(), 1e-12);
    EXPECT_EQ(imu.truth[k].bias.gyro_rad_s, Vector3::Zero());
    EXPECT_EQ(imu.truth[k].stamp, imu.samples[k].stamp);
  }
  EXPECT_LT(worst_gyro, 1e-7);
  EXPECT_LT(worst_accel, 1e-5);  // the second difference's rounding: ~1e-16 / h^2
}

TEST(SimulatedImu, WhiteNoiseHasTheDiscreteSigmaOfItsDensity) {
  ImuSimulationOptions o = noise_free(200.0);
  o.noise.gyro_noise_density = 1.6968e-4;
  o.noise.accel_noise_density = 2.0e-3;
  const auto rest = [](double) { return BodyKinematics{}; };
  const SimulatedImu imu = simulate_imu(rest, 0.0, 100.0, o);  // 20001 samples x 3 axes
  double gyro_sum2 = 0.0, accel_sum2 = 0.0, gyro_sum = 0.0;
  for (const auto& s : imu.samples) {
    gyro_sum += s.gyro_rad_s.sum();
    gyro_sum2 += s.gyro_rad_s.squaredNorm();
    accel_sum2 += (s.accel_mps2 - Vector3(0.0, 0.0, kG)).squaredNorm();  // at rest: +g up
  }
  const double n = 3.0 * static_cast<double>(imu.samples.size());
  const double gyro_sigma = std::sqrt(gyro_sum2 / n);
  const double accel_sigma = std::sqrt(accel_sum2 / n);
  // sigma_d = density * sqrt(rate); a sample std of n draws has relative standard error 1/sqrt(2n)
  // = 0.29 %: allow 5 of them.
  const double tolerance = 5.0 / std::sqrt(2.0 * n);
  EXPECT_NEAR(gyro_sigma / (1.6968e-4 * std::sqrt(200.0)), 1.0, tolerance);
  EXPECT_NEAR(accel_sigma / (2.0e-3 * std::sqrt(200.0)), 1.0, tolerance);
  EXPECT_NEAR(gyro_sum / n, 0.0, 5.0 * 1.6968e-4 * std::sqrt(200.0) / std::sqrt(n));
}

TEST(SimulatedImu, BiasRandomWalkGrowsAsItsDensityAndInitialBiasesHaveTheirSigma) {
  ImuSimulationOptions o = noise_free(200.0);
  o.noise.gyro_random_walk = 1.9393e-5;
  o.noise.accel_random_walk = 3.0e-3;
  o.initial_bias.reset();
  o.initial_gyro_bias_sigma_rad_s = 0.04;
  o.initial_accel_bias_sigma_mps2 = 0.1;
  const auto rest = [](double) { return BodyKinematics{}; };
  constexpr int kRuns = 1000;
  double var_gyro_1s = 0.0, var_gyro_2s = 0.0, var_accel_2s = 0.0, initial_gyro = 0.0, initial_accel = 0.0;
  for (int run = 0; run < kRuns; ++run) {
    o.seed = static_cast<std::uint64_t>(run) + 100;
    const SimulatedImu imu = simulate_imu(rest, 0.0, 2.0, o);  // samples 0..400
    const inertial::ImuBias& b0 = imu.truth[0].bias;
    var_gyro_1s += (imu.truth[200].bias.gyro_rad_s - b0.gyro_rad_s).squaredNorm();
    var_gyro_2s += (imu.truth[400].bias.gyro_rad_s - b0.gyro_rad_s).squaredNorm();
    var_accel_2s += (imu.truth[400].bias.accel_mps2 - b0.accel_mps2).squaredNorm();
    initial_gyro += b0.gyro_rad_s.squaredNorm();
    initial_accel += b0.accel_mps2.squaredNorm();
    // The reading carries the bias of its instant (the noise is off).
    ASSERT_LT((imu.samples[250].gyro_rad_s - imu.truth[250].bias.gyro_rad_s).norm(), 1e-15);
  }
  const double n = 3.0 * kRuns;
  // Var(b(T) - b(0)) = random_walk^2 T per axis; a variance from n values has relative standard
  // error sqrt(2 / n) = 2.6 %: allow 4 of them.
  const double tolerance = 4.0 * std::sqrt(2.0 / n);
  EXPECT_NEAR(var_gyro_1s / n / (1.9393e-5 * 1.9393e-5 * 1.0), 1.0, tolerance);
  EXPECT_NEAR(var_gyro_2s / n / (1.9393e-5 * 1.9393e-5 * 2.0), 1.0, tolerance);
  EXPECT_NEAR(var_accel_2s / n / (3.0e-3 * 3.0e-3 * 2.0), 1.0, tolerance);
  EXPECT_NEAR(initial_gyro / n / (0.04 * 0.04), 1.0, tolerance);
  EXPECT_NEAR(initial_accel / n / (0.1 * 0.1), 1.0, tolerance);
}

TEST(SimulatedImu, SaturationClipsEachAxis) {
  ImuSimulationOptions o = noise_free(100.0);
  o.gyro_saturation_rad_s = 10.0;
  o.accel_saturation_mps2 = 16.0 * kG;
  const auto spin = [](double) {
    BodyKinematics k;
    k.omega_body_rad_s = Vector3(1.0, -25.0, 12.0);
    k.a_world_mps2 = Vector3(200.0, -3.0, 0.0);
    return k;
  };
  const SimulatedImu imu = simulate_imu(spin, 0.0, 0.1, o);
  for (const auto& s : imu.samples) {
    EXPECT_EQ(s.gyro_rad_s, Vector3(1.0, -10.0, 10.0));
    EXPECT_EQ(s.accel_mps2, Vector3(16.0 * kG, -3.0, kG));
  }
}

TEST(SimulatedImu, TimeOffsetShiftsTheStampsNotTheReadingsNorTheTruth) {
  ImuSimulationOptions o = imu_preset("consumer-mems").value();
  const SimulatedImu plain = simulate_imu(&Helix::at, 0.0, 3.0, o);
  o.time_offset_s = 0.0123;
  const SimulatedImu shifted = simulate_imu(&Helix::at, 0.0, 3.0, o);
  ASSERT_EQ(plain.samples.size(), shifted.samples.size());
  for (std::size_t k = 0; k < plain.samples.size(); ++k) {
    EXPECT_EQ(shifted.samples[k].stamp.nanoseconds(), plain.samples[k].stamp.nanoseconds() + 12'300'000);
    EXPECT_EQ(shifted.samples[k].gyro_rad_s, plain.samples[k].gyro_rad_s);
    EXPECT_EQ(shifted.truth[k].stamp, plain.truth[k].stamp);
    EXPECT_EQ(shifted.truth[k].stamp.nanoseconds(), 5'000'000LL * static_cast<long long>(k));
  }
}

TEST(SimulatedImu, PresetsAreValidAndOptionsAreChecked) {
  for (const auto& name : imu_preset_names()) {
    std::string why;
    EXPECT_TRUE(imu_preset(name)->is_valid(&why)) << name << ": " << why;
  }
  EXPECT_NEAR(imu_preset("adis16448")->gyro_saturation_rad_s, 17.453292519943, 1e-9);  // 1000 deg/s
  EXPECT_FALSE(imu_preset("mpu"));
  ImuSimulationOptions bad;
  bad.rate_hz = 0.0;
  bad.noise.gyro_noise_density = -1.0;
  bad.time_offset_s = std::nan("");
  std::string why;
  EXPECT_FALSE(bad.is_valid(&why));
  EXPECT_NE(why.find("rate_hz"), std::string::npos) << why;
  EXPECT_NE(why.find("gyro_noise_density"), std::string::npos) << why;
  EXPECT_NE(why.find("time_offset_s"), std::string::npos) << why;
}

/// Strapdown integration of IMU samples, a Simpson step over each pair of sample intervals
/// (k, k+1, k+2 at times 0, h/2, h): rotation R(s) = R_k Exp(integral of omega) with the
/// quadratic through the three gyro readings (exact while the rotation axis is fixed, as it is
/// for a planar robot), then v += h/6 (a0 + 4 a_mid + a1) and p += h v + h^2/6 (a0 + 2 a_mid) with
/// a = R f + g (both exact for a quadratic a). Independent of planar_kinematics' Hermite form.
/// Returns the largest position and heading error against the trajectory's samples.
std::pair<double, double> integrate_against(const std::vector<TrajectorySample>& truth, const SimulatedImu& imu,
                                            std::size_t imu_per_sample) {
  const Vector3 g(0.0, 0.0, -kG);
  Matrix3 R = imu.truth[0].state.T_world_body.rotation_matrix();
  Vector3 p = imu.truth[0].state.T_world_body.translation();
  Vector3 v = imu.truth[0].state.v_world_mps;
  double worst_m = 0.0, worst_rad = 0.0;
  for (std::size_t k = 0; k + 2 < imu.samples.size(); k += 2) {
    const double h = static_cast<double>(imu.samples[k + 2].stamp.nanoseconds() - imu.samples[k].stamp.nanoseconds()) * 1e-9;
    const Vector3& w0 = imu.samples[k].gyro_rad_s;
    const Vector3& wm = imu.samples[k + 1].gyro_rad_s;
    const Vector3& w1 = imu.samples[k + 2].gyro_rad_s;
    const Matrix3 R_mid = R * core::SO3::exp(h / 24.0 * (5.0 * w0 + 8.0 * wm - w1)).matrix();
    const Matrix3 R_next = R * core::SO3::exp(h / 6.0 * (w0 + 4.0 * wm + w1)).matrix();
    const Vector3 a0 = R * imu.samples[k].accel_mps2 + g;
    const Vector3 am = R_mid * imu.samples[k + 1].accel_mps2 + g;
    const Vector3 a1 = R_next * imu.samples[k + 2].accel_mps2 + g;
    p += h * v + h * h / 6.0 * (a0 + 2.0 * am);
    v += h / 6.0 * (a0 + 4.0 * am + a1);
    R = R_next;
    if ((k + 2) % imu_per_sample == 0) {
      const TrajectorySample& s = truth[(k + 2) / imu_per_sample];
      worst_m = std::max(worst_m, (p.head<2>() - s.T_world_body.translation()).norm() + std::abs(p.z()));
      const double yaw = std::atan2(R(1, 0), R(0, 0));
      worst_rad = std::max(worst_rad, std::abs(core::wrap_angle(yaw - s.T_world_body.angle())));
    }
  }
  return {worst_m, worst_rad};
}

TEST(PlanarKinematics, IntegratedImuReproducesTheStreetLoopsTrajectory) {
  const Scenario scenario = *make_scenario("street-3d-loops");
  const WorldWithRoute world = build_world(scenario);
  const std::vector<TrajectorySample> truth =
      generate_trajectory(world.route, scenario.effective_trajectory(), world.closed_route, world.start_heading_rad);
  const PlanarKinematics kinematics(truth);
  // At the samples: the samples' own pose and velocity along the heading (a unicycle).
  for (std::size_t k = 0; k < truth.size(); k += 97) {
    const BodyKinematics b = kinematics(truth[k].stamp.seconds());
    EXPECT_LT((b.T_world_body.translation().head<2>() - truth[k].T_world_body.translation()).norm(), 1e-12);
    const double theta = truth[k].T_world_body.angle();
    EXPECT_LT((b.v_world_mps.head<2>() - truth[k].speed_mps * Vector2(std::cos(theta), std::sin(theta))).norm(), 1e-12);
    EXPECT_NEAR(b.omega_body_rad_s.z(), truth[k].yaw_rate_rad_s, 1e-12);
  }
  // 2 kHz readings: Simpson steps of 1 ms.
  const SimulatedImu imu = simulate_imu(std::ref(kinematics), truth.front().stamp.seconds(),
                                        truth.back().stamp.seconds(), noise_free(2000.0));
  ASSERT_EQ(imu.samples.size(), 20 * (truth.size() - 1) + 1);
  const auto [worst_m, worst_rad] = integrate_against(truth, imu, 20);
  // 75.7 s, 369 m, up to 6 m/s with a U-turn on the spot: measured 5.0e-5 m and 3.5e-7 rad.
  EXPECT_LT(worst_m, 1e-3) << "position error of the integrated IMU";
  EXPECT_LT(worst_rad, 1e-5) << "heading error of the integrated IMU";
  std::printf("street-3d-loops, 1 ms Simpson strapdown: worst position error %.3g m, heading %.3g rad\n", worst_m, worst_rad);
}

TEST(TunnelSpin, OneFullTurnInUnderASecondAtMoreThan360DegreesPerSecondIsTrackedByTheImu) {
  Scenario scenario = *make_scenario("tunnel-spin-3d");
  scenario.lidar3d.columns = 4;  // the spin is about the trajectory and the IMU
  std::string why;
  ASSERT_TRUE(scenario.is_valid(&why)) << why;
  const SimulationResult result = simulate(scenario, 1);
  ASSERT_TRUE(result.spin.has_value());
  const SpinEvent& spin = *result.spin;
  EXPECT_LE(spin.end_time_s - spin.start_time_s, 1.0);
  EXPECT_GE(spin.angle_rad, 2.0 * std::numbers::pi - 1e-12);
  // Measured from the truth: rate >= 360 deg/s on samples, the heading turned by integrating it.
  double peak = 0.0, turned = 0.0;
  for (std::size_t k = spin.first_sample; k <= spin.last_sample; ++k) {
    peak = std::max(peak, result.truth[k].yaw_rate_rad_s);
    if (k > spin.first_sample) turned += core::wrap_angle(result.truth[k].T_world_body.angle() - result.truth[k - 1].T_world_body.angle());
    EXPECT_EQ(result.truth[k].T_world_body.translation(), spin.position_world);
  }
  EXPECT_GE(peak, 2.0 * std::numbers::pi);
  EXPECT_NEAR(turned, 2.0 * std::numbers::pi, 1e-9);
  // In the tunnel, out of LiDAR range of both portals (60 m; the tunnel is 150 m long).
  EXPECT_GT(spin.position_world.x(), scenario.lidar3d.max_range_m);
  EXPECT_LT(spin.position_world.x(), scenario.tunnel.length_m - scenario.lidar3d.max_range_m);
  // The IMU (ADIS16448 preset, +-1000 deg/s) sees the spin unclipped.
  double gyro_peak = 0.0;
  for (const auto& s : result.imu.samples) gyro_peak = std::max(gyro_peak, s.gyro_rad_s.z());
  EXPECT_GT(gyro_peak, 2.0 * std::numbers::pi);
  EXPECT_LT(gyro_peak, scenario.imu.gyro_saturation_rad_s);
  ASSERT_EQ(result.imu.samples.size(), (result.truth.size() - 1) * 2 + 1);  // 200 Hz over 10 ms samples
  // The rest of the route is tunnel-3d's: same start, same end, at rest at both.
  EXPECT_EQ(result.truth.front().T_world_body.translation(), Vector2(-scenario.tunnel.approach_m, 0.0));
  EXPECT_NEAR(result.truth.back().T_world_body.x(), scenario.tunnel.length_m + scenario.tunnel.approach_m, 1e-9);

  // The noise-free IMU integrated through the spin reproduces the whole run.
  const SimulatedImu imu = simulate_imu(PlanarKinematics(result.truth), result.truth.front().stamp.seconds(),
                                        result.truth.back().stamp.seconds(), noise_free(2000.0));
  const auto [worst_m, worst_rad] = integrate_against(result.truth, imu, 20);
  EXPECT_LT(worst_m, 1e-3);  // measured 1.8e-8 m and 8e-9 rad
  EXPECT_LT(worst_rad, 1e-5);
  std::printf("tunnel-spin-3d, 1 ms Simpson strapdown: worst position error %.3g m, heading %.3g rad; spin %.3f s, peak %.2f rad/s\n",
              worst_m, worst_rad, spin.end_time_s - spin.start_time_s, peak);
}

}  // namespace
}  // namespace cairn::sim
