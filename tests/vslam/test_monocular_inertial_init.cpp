// Issue 40's monocular-inertial initialisation in simulation: a camera with an IMU flies down the
// synthetic textured corridor on a smooth closed-form path; cairn's monocular visual SLAM maps it
// (scale unknown), the simulator's IMU (EuRoC's ADIS16448 noise and drawn biases) gives the
// readings, and inertial::initialize_inertial (Campos et al., ICRA 2020) on the first seconds of
// keyframes must recover the metric scale (issue 40: within 2 %), gravity's direction and the gyro
// bias. The truth of the scale and of gravity in the map's frame comes from a Sim(3) Umeyama fit of
// the keyframes to the true camera positions, not from the code under test.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "cairn/eval/alignment.hpp"
#include "cairn/inertial/inertial_initialization.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "inertial_flight.hpp"
#include "synthetic_world.hpp"

namespace cairn::vslam {
namespace {

using test::StereoCamera;
using test::SyntheticWorld;
using Vector3 = Eigen::Vector3d;

constexpr double kPi = test::kFlightPi;
using test::camera_in_render_world;
const Eigen::Matrix3d kR_render_imu = test::R_render_imu();
const core::SE3 kT_body_camera = test::T_body_camera();
sim::BodyKinematics kinematics(double t) {
  return test::kinematics_of([](double s) { return camera_in_render_world(s); }, t);
}

TEST(MonocularInertialInitialisation, RecoversTheMetricScaleOnTheSyntheticCorridor) {
  SyntheticWorld world;
  world.add_corridor_z(Vector3(-1.0, -1.0, -1.0), Vector3(1.0, 1.3, 22.0), 101);
  const StereoCamera camera;
  VisualSlamOptions options;
  options.loop_closure = false;
  VisualSlam slam(camera.calibration(), io::SequenceKind::kMonocular, options);
  constexpr double kDuration = 4.0, kFrameRate = 20.0;
  std::size_t tracked = 0;
  for (int k = 0; k <= static_cast<int>(kDuration * kFrameRate); ++k) {
    const double t = k / kFrameRate;
    tracked += slam.add_monocular(core::Timestamp::from_seconds(t), world.render(camera_in_render_world(t), camera)).tracked ? 1 : 0;
  }
  const std::vector<core::SE3> all = slam.keyframe_poses();
  const std::vector<core::Timestamp> times = slam.keyframe_times();
  ASSERT_GE(all.size(), 5u) << tracked << " frames tracked";
  // The truth in the map's frame: Sim(3) of the keyframes' camera centres onto the true ones.
  Eigen::MatrixXd map_positions(3, static_cast<Eigen::Index>(all.size())), true_positions(3, map_positions.cols());
  for (std::size_t k = 0; k < all.size(); ++k) {
    map_positions.col(static_cast<Eigen::Index>(k)) = all[k].translation();
    true_positions.col(static_cast<Eigen::Index>(k)) = camera_in_render_world(times[k].seconds()).translation();
  }
  const eval::UmeyamaResult fit = eval::umeyama(map_positions, true_positions, true);
  ASSERT_TRUE(fit.outcome.ok()) << fit.outcome.message;
  const Vector3 gravity_render = kR_render_imu * Vector3(0.0, 0.0, -inertial::kStandardGravity);
  const Vector3 gravity_map_truth = fit.R.transpose() * gravity_render;
  // ORB-SLAM3 initialises the IMU after 2 s of keyframes and refines it later: both here, the
  // keyframes as the map holds them at the end of the run, three IMU noise seeds.
  for (const double window_s : {2.0, 1e9}) {
    std::vector<core::SE3> keyframes;
    std::vector<core::Timestamp> stamps;
    for (std::size_t k = 0; k < all.size() && times[k].seconds() <= times.front().seconds() + window_s; ++k) {
      keyframes.push_back(all[k]);
      stamps.push_back(times[k]);
    }
    for (const std::uint64_t seed : {7, 8, 9}) {
      sim::ImuSimulationOptions imu = *sim::imu_preset("adis16448");
      imu.seed = seed;
      const sim::SimulatedImu simulated = sim::simulate_imu(kinematics, 0.0, kDuration + 0.1, imu);
      const inertial::InertialInitialization init =
          inertial::initialize_inertial(stamps, keyframes, kT_body_camera.inverse(), simulated.samples, imu.noise);
      ASSERT_TRUE(init.ok) << init.why;
      const double gravity_deg =
          std::atan2(init.gravity_world.cross(gravity_map_truth).norm(), init.gravity_world.dot(gravity_map_truth)) * 180.0 / kPi;
      const double scale_error = std::abs(init.scale / fit.scale - 1.0);
      const double gyro_error = (init.bias.gyro_rad_s - simulated.initial_bias.gyro_rad_s).norm();
      std::printf("monocular-inertial, %zu keyframes over %.2f s, IMU seed %llu: scale %.4f (truth %.4f, %.2f %% off), gravity %.3f deg "
                  "off, gyro bias %.2e rad/s off, accel bias %.3f m/s^2 off\n",
                  keyframes.size(), stamps.back().seconds() - stamps.front().seconds(), static_cast<unsigned long long>(seed), init.scale,
                  fit.scale, 100.0 * scale_error, gravity_deg, gyro_error, (init.bias.accel_mps2 - simulated.initial_bias.accel_mps2).norm());
      if (window_s > 100.0) {  // the bounds, on the refined initialisation
        EXPECT_LT(scale_error, 0.02) << "seed " << seed;
        EXPECT_LT(gravity_deg, 1.0) << "seed " << seed;
        EXPECT_LT(gyro_error, 2e-3) << "seed " << seed;
      } else {  // a regression guard on the first one (measured: see docs/inertial.md)
        EXPECT_LT(scale_error, 0.04) << "seed " << seed;
        EXPECT_LT(gravity_deg, 2.0) << "seed " << seed;
      }
    }
  }
  std::printf("%zu of %d frames tracked\n", tracked, static_cast<int>(kDuration * kFrameRate) + 1);
}

}  // namespace
}  // namespace cairn::vslam
