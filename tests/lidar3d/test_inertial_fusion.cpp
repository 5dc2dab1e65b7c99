// LidarInertialFusion (lidar3d/inertial_fusion.hpp) on hand-made measurements: a sensor standing
// still (the IMU reads gravity and a known gyro bias, noiselessly), with registrations that agree
// with it, then one that the IMU contradicts. The expected values are the construction's: the
// sensor does not move.

#include <gtest/gtest.h>

#include "cairn/lidar3d/inertial_fusion.hpp"

namespace cairn::lidar3d {
namespace {

constexpr double kRateHz = 200.0;

void add_still_imu(LidarInertialFusion& fusion, double seconds, const Vector3& gyro_bias) {
  for (int k = 0; k <= static_cast<int>(seconds * kRateHz); ++k) {
    inertial::ImuSample s;
    s.stamp = core::Timestamp::from_seconds(k / kRateHz);
    s.gyro_rad_s = gyro_bias;
    s.accel_mps2 = Vector3(0.0, 0.0, inertial::kStandardGravity);
    fusion.add_imu(s);
  }
}

OdometryScanResult registration_at(double time_s, const core::SE3& T_world_lidar) {
  OdometryScanResult r;
  r.time_s = time_s;
  r.registered_time_s = time_s;
  r.T_world_registered = T_world_lidar;
  r.T_world_sensor = T_world_lidar;
  r.health = Health::kOk;
  r.registration.correspondences = 1000;
  r.registration.source_points = 1000;
  return r;
}

// The first state at the first scan: its prediction is the pose the registration then confirms;
// ten scans later a registration 1 m and 10 deg from the still sensor contradicts the IMU, and the
// scans before it did not.
TEST(LidarInertialFusion, ARegistrationTheStillImuContradictsIsFlagged) {
  const Vector3 gyro_bias(0.002, -0.001, 0.003);
  LidarInertialFusion fusion{InertialFusionOptions{}};
  add_still_imu(fusion, 6.0, gyro_bias);
  core::SE3 T_world_lidar;
  for (int k = 0; k < 12; ++k) {
    const double t = 2.5 + 0.1 * k;
    const std::optional<MotionPrior> prior = fusion.predict_sweep(t - 0.1, t + 0.1);
    ASSERT_TRUE(prior.has_value()) << k;
    if (k == 0) T_world_lidar = prior->at(t);  // the initialisation's pose: where the world starts
    const bool wrong = k == 11;
    const core::SE3 registered = wrong ? T_world_lidar * core::SE3(core::SO3::exp(Vector3(0.0, 0.0, 10.0 * M_PI / 180.0)),
                                                                   Vector3(1.0, 0.0, 0.0))
                                       : T_world_lidar;
    const InertialScanState state = fusion.fuse(registration_at(t, registered), registered);
    if (k == 0) continue;  // the first scan starts the window: nothing to compare with
    EXPECT_TRUE(state.lidar_used) << k;
    EXPECT_GE(state.imu_lidar_chi2, 0.0) << k;
    EXPECT_EQ(state.contradicts_imu, wrong) << k << ": chi2 " << state.imu_lidar_chi2;
    if (!wrong) {
      // Standing still: the fused pose stays where it started, the velocity near zero.
      EXPECT_LT((state.T_world_lidar.translation() - T_world_lidar.translation()).norm(), 1e-3) << k;
      EXPECT_LT(state.state.v_world_mps.norm(), 1e-2) << k;
    }
  }
  ASSERT_TRUE(fusion.initialized());
  EXPECT_TRUE(fusion.initialization().still) << fusion.initialization().message;
  // Static initialisation from noiseless samples: the gyro bias exactly.
  EXPECT_NEAR((fusion.initialization().statics.gyro_bias_rad_s - gyro_bias).norm(), 0.0, 1e-9);
}

}  // namespace
}  // namespace cairn::lidar3d
