// Issue 40's stereo-inertial tracking in simulation: a stereo camera with an IMU (the simulator's
// ADIS16448, EuRoC's class: its noise and drawn biases) flies down the synthetic textured corridor
// (inertial_flight.hpp) at 20 Hz; for one second the images are black (lights off). Visual-only
// tracking loses those frames; with the IMU (VisualInertialOptions) they are carried, degraded,
// and tracking resumes when the images return. Errors are measured against the closed-form path
// after an SE(3) alignment of the whole trajectory (eval::umeyama), never against the code's own
// output; gravity's truth in the map's frame comes from that alignment too.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>

#include "cairn/eval/alignment.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/vslam/visual_slam.hpp"
#include "inertial_flight.hpp"
#include "synthetic_world.hpp"

namespace cairn::vslam {
namespace {

using test::StereoCamera;
using test::SyntheticWorld;
using Vector3 = Eigen::Vector3d;

constexpr double kFrameRate = 20.0;
constexpr double kDuration = 6.0;
constexpr double kBlankFrom = 3.0, kBlankTo = 4.0;  // [from, to): black images

struct FlightRun {
  std::size_t lost = 0, degraded = 0, carried = 0, frames = 0, contradicted = 0;
  int first_tracked = -1;  // monocular: the two-view initialisation's second frame
  double sim3_scale = 0.0; // of the Sim(3) fit of the trajectory to the truth (metric: 1)
  bool tracked_after_blank = false;  // the first frame after the blank
  double ate_rmse_m = 0.0, blank_end_error_m = 0.0, distance_m = 0.0, gravity_error_deg = -1.0;
  bool initialised = false;
  VisualSlamSummary summary;
};

// What goes wrong on the flight: a second of black images, or a fast turn (a yaw of turn_deg
// over turn_s seconds and back, inertial_flight.hpp).
struct Trouble {
  bool monocular = false;  // the left camera only
  bool blank = false;
  double turn_at_s = -1.0, turn_deg = 0.0, turn_s = 1.0;
  core::SE3 camera(double t) const { return test::camera_in_render_world(t, turn_at_s, turn_deg, turn_s); }
  bool black(double t) const { return blank && t >= kBlankFrom - 1e-9 && t < kBlankTo - 1e-9; }
};

// The IMU's readings follow `imu_trouble`'s path when given (an IMU that contradicts the images).
FlightRun fly(bool with_imu, const Trouble& trouble, const Trouble* imu_trouble = nullptr) {
  const Trouble& imu_path = imu_trouble ? *imu_trouble : trouble;
  SyntheticWorld world;
  world.add_corridor_z(Vector3(-1.0, -1.0, -1.0), Vector3(1.0, 1.3, 22.0), 101);
  const StereoCamera camera;
  VisualSlamOptions options;
  options.loop_closure = false;
  sim::ImuSimulationOptions imu = *sim::imu_preset("adis16448");
  imu.seed = 7;
  options.inertial.enabled = with_imu;
  options.inertial.T_body_camera = test::T_body_camera();
  options.inertial.noise = imu.noise;
  const sim::SimulatedImu simulated = sim::simulate_imu(
      [&](double t) { return test::kinematics_of([&](double s) { return imu_path.camera(s); }, t); }, 0.0, kDuration + 0.2, imu);
  VisualSlam slam(camera.calibration(), trouble.monocular ? io::SequenceKind::kMonocular : io::SequenceKind::kStereo, options);
  FlightRun run;
  std::size_t next_sample = 0;
  const int frames = static_cast<int>(kDuration * kFrameRate) + 1;
  std::vector<double> times;
  for (int k = 0; k < frames; ++k) {
    const double t = k / kFrameRate;
    times.push_back(t);
    // The IMU's readings up to the first at or after the frame (the prediction's last interval).
    while (with_imu && next_sample < simulated.samples.size()) {
      const inertial::ImuSample& sample = simulated.samples[next_sample];
      slam.add_imu(sample);
      ++next_sample;
      if (sample.stamp.seconds() >= t) break;
    }
    cv::Mat left, right;
    if (trouble.black(t)) {
      left = right = cv::Mat::zeros(camera.height, camera.width, CV_8UC1);
    } else if (trouble.monocular) {
      left = world.render(trouble.camera(t), camera);
    } else {
      std::tie(left, right) = world.render_stereo(trouble.camera(t), camera);
    }
    const core::Timestamp stamp = core::Timestamp::from_seconds(t);
    const FrameResult r = trouble.monocular ? slam.add_monocular(stamp, left) : slam.add_stereo(stamp, left, right);
    if (r.tracked && run.first_tracked < 0) run.first_tracked = k;
    run.lost += r.health == TrackingHealth::kLost ? 1 : 0;
    run.degraded += r.health == TrackingHealth::kDegraded ? 1 : 0;
    run.carried += r.carried_by_imu ? 1 : 0;
    const bool contradicted = r.note.find("the IMU's prediction and the images disagree") != std::string::npos;
    run.contradicted += contradicted ? 1 : 0;
    if (contradicted) {
      EXPECT_NE(r.health, TrackingHealth::kOk) << "frame " << k;
    }
    if (std::abs(t - kBlankTo) < 1e-9) run.tracked_after_blank = r.tracked;
  }
  run.frames = static_cast<std::size_t>(frames);
  // From the first tracked frame (monocular: the frames before the two-view initialisation have
  // no pose), SE(3)-aligned: a metric trajectory needs no scale. The Sim(3) fit's scale says how
  // metric it is.
  const std::vector<core::SE3> trajectory = slam.trajectory();
  const int from = std::max(run.first_tracked, 0), n = frames - from;
  Eigen::MatrixXd estimated(3, n), truth(3, n);
  for (int k = from; k < frames; ++k) {
    estimated.col(k - from) = trajectory[static_cast<std::size_t>(k)].translation();
    truth.col(k - from) = trouble.camera(times[static_cast<std::size_t>(k)]).translation();
    if (k > from) run.distance_m += (truth.col(k - from) - truth.col(k - from - 1)).norm();
  }
  const eval::UmeyamaResult fit = eval::umeyama(estimated, truth, false);
  EXPECT_TRUE(fit.outcome.ok()) << fit.outcome.message;
  const eval::UmeyamaResult similarity = eval::umeyama(estimated, truth, true);
  run.sim3_scale = similarity.scale;
  double sum2 = 0.0;
  for (int k = from; k < frames; ++k) {
    const double e = (fit.R * estimated.col(k - from) + fit.t - truth.col(k - from)).norm();
    sum2 += e * e;
    if (std::abs(times[static_cast<std::size_t>(k)] - (kBlankTo - 1.0 / kFrameRate)) < 1e-9) run.blank_end_error_m = e;
  }
  run.ate_rmse_m = std::sqrt(sum2 / n);
  run.initialised = with_imu && slam.inertial_initialised();
  if (run.initialised) {
    // Gravity's true direction in the map: the render world's turned into it by the rotation that
    // best maps the true camera orientations onto the estimated ones (chordal mean of R_est R_true^T
    // over the tracked frames). The position fit's rotation is not used: along a nearly straight
    // path it leaves a roll about the path's axis free by degrees.
    Eigen::Matrix3d sum = Eigen::Matrix3d::Zero();
    for (int k = from; k < frames; ++k) {
      sum += trajectory[static_cast<std::size_t>(k)].so3().matrix() * trouble.camera(times[static_cast<std::size_t>(k)]).so3().matrix().transpose();
    }
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sum, Eigen::ComputeFullU | Eigen::ComputeFullV);
    Eigen::Matrix3d R_map_render = svd.matrixU() * svd.matrixV().transpose();
    if (R_map_render.determinant() < 0.0) R_map_render = svd.matrixU() * Eigen::Vector3d(1, 1, -1).asDiagonal() * svd.matrixV().transpose();
    const Vector3 gravity_truth = R_map_render * (test::R_render_imu() * Vector3(0.0, 0.0, -inertial::kStandardGravity));
    const Vector3 g = slam.gravity_world();
    run.gravity_error_deg = std::atan2(g.cross(gravity_truth).norm(), g.dot(gravity_truth)) * 180.0 / test::kFlightPi;
  }
  run.summary = slam.summary();
  const char* sensors = trouble.monocular ? (with_imu ? "monocular-inertial" : "monocular only") : (with_imu ? "stereo-inertial" : "stereo only");
  std::printf("%s%s: %zu frames (first tracked %d), %zu lost, %zu degraded, %zu carried by the IMU, %zu contradicting it; frame at %.1f s %s; ATE %.4f m over %.2f m "
              "(%.2f %%), Sim(3) scale %.4f, error at %.2f s %.3f m; inertial estimates %zu (refused %zu%s%s), first at %.2f s, gravity %.3f "
              "deg off, %.1f ms in them; monocular: initial scale %.4f, last scale estimate %.4f, %zu frames flagged for scale drift\n",
              sensors, trouble.blank ? ", blank second" : trouble.turn_at_s >= 0.0 ? ", fast turn" : imu_trouble ? ", straight images, turning IMU" : "", run.frames, run.first_tracked, run.lost, run.degraded, run.carried, run.contradicted, kBlankTo,
              run.tracked_after_blank ? "tracked" : "not tracked", run.ate_rmse_m, run.distance_m, 100.0 * run.ate_rmse_m / run.distance_m,
              run.sim3_scale, kBlankTo - 1.0 / kFrameRate, run.blank_end_error_m, run.summary.inertial_estimates, run.summary.inertial_estimates_refused,
              run.summary.inertial_refusal.empty() ? "" : ": ", run.summary.inertial_refusal.c_str(), run.summary.inertial_initialised_at_s,
              run.gravity_error_deg, 1e3 * run.summary.inertial_s, run.summary.monocular_initial_scale, run.summary.monocular_scale_estimate,
              run.summary.frames_scale_drifted);
  return run;
}

TEST(StereoInertial, CarriesASecondOfBlankFramesThatVisualOnlyTrackingLoses) {
  const int blank_frames = static_cast<int>(std::lround((kBlankTo - kBlankFrom) * kFrameRate));
  // The control: without the IMU the blank frames are lost.
  Trouble lights_off;
  lights_off.blank = true;
  const FlightRun visual = fly(false, lights_off);
  EXPECT_GE(visual.lost, static_cast<std::size_t>(blank_frames));
  const FlightRun inertial = fly(true, lights_off);
  ASSERT_TRUE(inertial.initialised) << inertial.summary.inertial_refusal;
  EXPECT_LT(inertial.summary.inertial_initialised_at_s, kBlankFrom);  // initialised before the lights go off
  EXPECT_EQ(inertial.carried, static_cast<std::size_t>(blank_frames));
  EXPECT_EQ(inertial.lost, 0u);
  EXPECT_TRUE(inertial.tracked_after_blank);
  // Issue 40: ATE within 1 % of the distance travelled, the blank included.
  EXPECT_LT(inertial.ate_rmse_m, 0.01 * inertial.distance_m);
  EXPECT_LT(inertial.ate_rmse_m, visual.ate_rmse_m);
  EXPECT_LT(inertial.gravity_error_deg, 1.0);
  EXPECT_EQ(inertial.contradicted, 0u);
  EXPECT_EQ(inertial.summary.frames_contradicting_imu, 0u);
}

// A yaw of 150 degrees in 0.4 s and back (peak 750 deg/s, 37.5 degrees between frames at the
// peak; the renderer draws no motion blur): visual-only tracking loses frames at the turn, the
// IMU carries them and the turned view is mapped at its pose (map_carried_view).
TEST(StereoInertial, CarriesAFastTurnThatVisualOnlyTrackingLoses) {
  Trouble turn;
  turn.turn_at_s = 3.0;
  turn.turn_deg = 150.0;
  turn.turn_s = 0.4;
  const FlightRun visual = fly(false, turn);
  EXPECT_GE(visual.lost, 1u);
  const FlightRun inertial = fly(true, turn);
  ASSERT_TRUE(inertial.initialised) << inertial.summary.inertial_refusal;
  EXPECT_EQ(inertial.lost, 0u);
  EXPECT_GE(inertial.carried, 1u);
  EXPECT_LT(inertial.ate_rmse_m, 0.01 * inertial.distance_m);
  EXPECT_LT(inertial.ate_rmse_m, visual.ate_rmse_m);
}

}  // namespace
}  // namespace cairn::vslam


namespace cairn::vslam {
namespace {

// The health rule: the images fly straight on while the IMU reads the fast turn of the test
// above (a wrong IMU, or images of something else). The frames where the two disagree are
// degraded, each saying so; in the runs above, where they agree, no frame is.
TEST(StereoInertial, FramesTheImuContradictsAreDegraded) {
  Trouble straight, turn;
  turn.turn_at_s = 3.0;
  turn.turn_deg = 150.0;
  turn.turn_s = 0.4;
  const FlightRun run = fly(true, straight, &turn);
  ASSERT_TRUE(run.initialised) << run.summary.inertial_refusal;
  EXPECT_GE(run.contradicted, 1u);
  EXPECT_EQ(run.summary.frames_contradicting_imu, run.contradicted);
}

}  // namespace
}  // namespace cairn::vslam

namespace cairn::vslam {
namespace {

// Monocular with the IMU: the first inertial estimate rescales the map to metres (issue 40:
// metric scale within 2 % after the initialisation), and the IMU carries the blank second as in
// stereo. The control without the IMU loses the blank frames.
TEST(MonocularInertial, IsMetricAndCarriesASecondOfBlankFrames) {
  const int blank_frames = static_cast<int>(std::lround((kBlankTo - kBlankFrom) * kFrameRate));
  Trouble lights_off;
  lights_off.monocular = true;
  lights_off.blank = true;
  const FlightRun visual = fly(false, lights_off);
  EXPECT_GE(visual.lost, static_cast<std::size_t>(blank_frames));
  const FlightRun inertial = fly(true, lights_off);
  ASSERT_TRUE(inertial.initialised) << inertial.summary.inertial_refusal;
  EXPECT_LT(inertial.summary.inertial_initialised_at_s, kBlankFrom);
  EXPECT_NEAR(inertial.sim3_scale, 1.0, 0.02);
  EXPECT_EQ(inertial.carried, static_cast<std::size_t>(blank_frames));
  EXPECT_TRUE(inertial.tracked_after_blank);
  EXPECT_LT(inertial.ate_rmse_m, 0.01 * inertial.distance_m);
  EXPECT_LT(inertial.gravity_error_deg, 1.0);
  EXPECT_EQ(inertial.summary.frames_scale_drifted, 0u);
}

}  // namespace
}  // namespace cairn::vslam

namespace cairn::vslam {
namespace {

// One camera, a yaw of 170 degrees in 0.3 s and back (peak 1,133 deg/s): monocular tracking
// loses frames at the turn; with the IMU none is lost after the initialisation and the map stays
// metric. The windowed scale estimates made during the turn are off (0.92 the last one) and a
// few frames are flagged for scale drift although the map's scale holds: printed, not asserted
// (docs/vslam.md).
TEST(MonocularInertial, CarriesAFastTurnThatVisualOnlyTrackingLoses) {
  Trouble turn;
  turn.monocular = true;
  turn.turn_at_s = 3.0;
  turn.turn_deg = 170.0;
  turn.turn_s = 0.3;
  const FlightRun visual = fly(false, turn);
  const FlightRun inertial = fly(true, turn);
  // The frames before the two-view initialisation are lost in both runs.
  const std::size_t before_init = static_cast<std::size_t>(inertial.first_tracked);
  EXPECT_GT(visual.lost, static_cast<std::size_t>(visual.first_tracked));
  ASSERT_TRUE(inertial.initialised) << inertial.summary.inertial_refusal;
  EXPECT_EQ(inertial.lost, before_init);
  EXPECT_NEAR(inertial.sim3_scale, 1.0, 0.02);
  EXPECT_LT(inertial.ate_rmse_m, 0.01 * inertial.distance_m);
}

}  // namespace
}  // namespace cairn::vslam
