// Visual-inertial tracking (issue 40, its first part), after ORB-SLAM3 (Campos, Elvira, Gomez
// Rodriguez, Montiel & Tardos, "ORB-SLAM3: An Accurate Open-Source Library for Visual,
// Visual-Inertial and Multi-Map SLAM", T-RO 2021, Sec. V-VII): the IMU, preintegrated from the
// last frame's state (Forster et al., T-RO 2017; inertial/preintegration.hpp), predicts the frame
// in place of the constant-velocity model (ORB-SLAM3 Tracking::PredictStateIMU), and carries the
// frames the images do not track (ORB-SLAM3's RECENTLY_LOST state); gravity, the velocities and the
// biases come from the inertial-only MAP estimate of Campos et al. (ICRA 2020) over the recent
// keyframes, made at every keyframe. What ORB-SLAM3 has and this does not yet: the IMU factor in
// the motion-only and local bundle adjustments (the visual poses are taken as they are), and
// monocular-inertial tracking (docs/vslam.md, "With an IMU").
// The state and the declarations: slam_state.hpp.

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "cairn/core/problems.hpp"
#include "cairn/inertial/inertial_initialization.hpp"
#include "cairn/inertial/preintegration.hpp"
#include "cairn/vslam/slam_state.hpp"

namespace cairn::vslam {

bool VisualInertialOptions::is_valid(std::string* why) const {
  core::Problems problems;
  if (std::string p; !noise.is_valid(&p)) problems.add("inertial noise: " + p);
  problems.require_positive(gravity_mps2, "inertial.gravity_mps2");
  if (!(initialisation_window_s >= 1.0 && std::isfinite(initialisation_window_s))) {
    problems.add("inertial.initialisation_window_s must be >= 1 s (the initialisation needs motion over time)");
  }
  if (!(refinement_window_s >= initialisation_window_s && std::isfinite(refinement_window_s))) {
    problems.add("inertial.refinement_window_s must be finite and >= initialisation_window_s");
  }
  if (!(max_carried_s >= 0.0 && std::isfinite(max_carried_s))) problems.add("inertial.max_carried_s must be finite and >= 0");
  if (!T_body_camera.matrix().allFinite()) problems.add("inertial.T_body_camera must be finite");
  problems.require_positive(disagreement_m, "inertial.disagreement_m");
  problems.require_positive(disagreement_deg, "inertial.disagreement_deg");
  return problems.report(why);
}

void VisualSlam::add_imu(const inertial::ImuSample& sample) {
  if (!options_.inertial.enabled) throw std::logic_error("add_imu on a VisualSlam without options.inertial.enabled");
  if (!sample.gyro_rad_s.allFinite() || !sample.accel_mps2.allFinite()) {
    throw std::invalid_argument("IMU reading at " + std::to_string(sample.stamp.seconds()) + " s is not finite");
  }
  std::vector<inertial::ImuSample>& samples = impl_->imu_samples;
  if (!samples.empty() && !(samples.back().stamp < sample.stamp)) {
    throw std::invalid_argument("IMU reading at " + std::to_string(sample.stamp.seconds()) + " s is not after the previous one (" +
                                std::to_string(samples.back().stamp.seconds()) + " s)");
  }
  samples.push_back(sample);
  // Keep what an estimate (its window) and a carried stretch can still ask for, with a second
  // to spare; drop the rest in chunks (amortised O(1) per reading).
  const VisualInertialOptions& o = options_.inertial;
  const double keep_s = o.refinement_window_s + o.max_carried_s + 1.0;
  std::size_t old = 0;
  while (old < samples.size() && (sample.stamp.seconds() - samples[old].stamp.seconds()) > keep_s) ++old;
  if (old >= 4096) samples.erase(samples.begin(), samples.begin() + static_cast<std::ptrdiff_t>(old));
}

bool VisualSlam::inertial_initialised() const { return impl_->imu_initialised; }
Eigen::Vector3d VisualSlam::gravity_world() const { return impl_->gravity_world; }
inertial::ImuBias VisualSlam::imu_bias() const { return impl_->imu_bias; }

core::SE3 VisualSlam::Impl::camera_pose(const inertial::NavState& body) const {
  return body.T_world_body * options.inertial.T_body_camera;
}

// Before the first stage: the body's state at this frame from the last frame's state, its
// velocity and the biases, through the readings in between ([F] (44); ORB-SLAM3
// PredictStateIMU). Nothing when the IMU is not initialised or the readings do not cover the
// interval.
void VisualSlam::Impl::predict_with_imu(TrackingFrame& w) {
  if (!options.inertial.enabled || !imu_initialised || !have_imu_state) return;
  inertial::PreintegratedImu preintegrated(options.inertial.noise, imu_bias);
  if (!inertial::integrate_interval(imu_samples, imu_state_time, w.f.time, preintegrated)) return;
  w.imu_prediction = preintegrated.predict(imu_state, imu_bias, gravity_world);
  w.have_imu_prediction = w.imu_prediction.T_world_body.matrix().allFinite() && w.imu_prediction.v_world_mps.allFinite();
  w.result.imu_predicted = w.have_imu_prediction;
}

// A frame the images did not track: with the IMU's prediction, within max_carried_s of the last
// tracked frame, it takes the prediction and is degraded, not lost (ORB-SLAM3 RECENTLY_LOST).
// `last` keeps the last tracked frame's matches, so the next frame searches them around its own
// prediction. False (the frame is then lost as before) otherwise.
bool VisualSlam::Impl::carry_with_imu(TrackingFrame& w) {
  if (!w.have_imu_prediction) return false;
  const double since_tracked_s = w.f.time.seconds() - last_tracked_time.seconds();
  if (since_tracked_s > options.inertial.max_carried_s) {
    w.result.note = "lost: the IMU has carried the pose for " + std::to_string(since_tracked_s) + " s (max_carried_s " +
                    std::to_string(options.inertial.max_carried_s) + ")";
    return false;
  }
  w.f.T_world_camera = camera_pose(w.imu_prediction);
  w.result.health = TrackingHealth::kDegraded;
  w.result.tracked = false;
  w.result.carried_by_imu = true;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "%d inlier matches (lost below %d): pose from the IMU, %.2f s since the last tracked frame",
                w.inliers, options.lost_below_inliers, since_tracked_s);
  w.result.note = buffer;
  ++summary->frames_carried_by_imu;
  map_carried_view(w);
  return true;
}

// A carried frame that sees enough stereo/depth points sees a view the map does not cover (a turn
// faster than the last frame's points could follow): it becomes a keyframe at the IMU's pose, so
// the next frames have points to track (record_frame makes it `last`). cairn's: ORB-SLAM3 maps
// nothing while RECENTLY_LOST and starts a new map when that lasts 5 s. Measured in
// tests/vslam/test_stereo_inertial.cpp (a 150 degree turn in 0.4 s: without it the view's frames
// were carried until max_carried_s ran out).
void VisualSlam::Impl::map_carried_view(TrackingFrame& w) {
  if (localization_only || w.result.stereo_points < options.min_new_points) return;
  const auto mapping_start = Clock::now();
  std::fill(w.f.map_point.begin(), w.f.map_point.end(), -1);
  insert_keyframe(w.f);
  detect_and_close_loop(w.result);
  w.f.T_world_camera = keyframes.back().frame.T_world_camera;
  w.f.map_point = keyframes.back().frame.map_point;
  w.times.mapping_s = seconds_since(mapping_start);
  w.result.keyframe = true;
  w.result.note += "; its view mapped as a keyframe at that pose";
}

// After the frame: the body's state at it. A tracked frame is first checked against the IMU's
// prediction (check_against_imu), then keeps its visual pose and the IMU's
// velocity; a keyframe re-estimates gravity, velocities and biases (estimate_inertial) and takes
// its velocity from there; a carried frame keeps the prediction; a lost one leaves no state (the
// next keyframe's estimate gives one again).
void VisualSlam::Impl::advance_inertial_state(TrackingFrame& w) {
  if (!options.inertial.enabled) return;
  FrameResult& result = w.result;
  if (result.tracked) {
    check_against_imu(w);
    last_tracked_time = w.f.time;
    if (w.have_imu_prediction) {
      imu_state.T_world_body = w.f.T_world_camera * options.inertial.T_body_camera.inverse();
      imu_state.v_world_mps = w.imu_prediction.v_world_mps;
      imu_state_time = w.f.time;
      have_imu_state = true;
    } else {
      have_imu_state = false;
    }
    if (result.keyframe && !localization_only) estimate_inertial(w.f.time);
  } else if (result.carried_by_imu) {
    imu_state.T_world_body = w.f.T_world_camera * options.inertial.T_body_camera.inverse();
    imu_state.v_world_mps = w.imu_prediction.v_world_mps;
    imu_state_time = w.f.time;
  } else {
    have_imu_state = false;
  }
}

// Issue 40's health rule: a tracked frame whose visual pose the IMU's prediction contradicts
// (farther than disagreement_m / disagreement_deg) is degraded, with both distances in its note.
void VisualSlam::Impl::check_against_imu(TrackingFrame& w) {
  if (!w.have_imu_prediction) return;
  const core::SE3 predicted = camera_pose(w.imu_prediction);
  const double distance_m = (predicted.translation() - w.f.T_world_camera.translation()).norm();
  const double angle_deg = (predicted.so3().inverse() * w.f.T_world_camera.so3()).log().norm() * 180.0 / 3.14159265358979323846;
  if (distance_m <= options.inertial.disagreement_m && angle_deg <= options.inertial.disagreement_deg) return;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "the IMU's prediction and the images disagree by %.3f m and %.2f deg", distance_m, angle_deg);
  if (w.result.health == TrackingHealth::kOk) w.result.health = TrackingHealth::kDegraded;
  w.result.note = w.result.note.empty() ? std::string(buffer) : w.result.note + "; " + buffer;
  ++summary->frames_contradicting_imu;
}

// The inertial-only MAP estimate (Campos et al., ICRA 2020; inertial_initialization.hpp) over
// the good keyframes of the current segment within the last window (initialisation_window_s
// before the first success, refinement_window_s after), the scale held at 1 (stereo and depth
// are metric). Needs the keyframes to span three quarters of the initialisation window; a refusal is counted with
// its reason and changes nothing. On success the newest keyframe (the frame just tracked) gives
// the state: its visual pose, its estimated velocity.
void VisualSlam::Impl::estimate_inertial(core::Timestamp now) {
  const VisualInertialOptions& o = options.inertial;
  const double window_s = imu_initialised ? o.refinement_window_s : o.initialisation_window_s;
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> poses;
  const int current = find(segment);
  for (const KeyFrame& kf : keyframes) {
    if (kf.bad || find(kf.segment) != current || now.seconds() - kf.frame.time.seconds() > window_s + 1e-9) continue;
    if (!stamps.empty() && !(stamps.back() < kf.frame.time)) continue;
    stamps.push_back(kf.frame.time);
    poses.push_back(kf.frame.T_world_camera);
  }
  // Keyframes come every few frames: three quarters of the initialisation window is "spans it".
  if (stamps.size() < 3 || stamps.back().seconds() - stamps.front().seconds() < 0.75 * o.initialisation_window_s) return;
  const auto start = Clock::now();
  inertial::InertialInitializationOptions io;
  io.estimate_scale = false;
  io.gravity_mps2 = o.gravity_mps2;
  const inertial::InertialInitialization init =
      inertial::initialize_inertial(stamps, poses, o.T_body_camera.inverse(), imu_samples, o.noise, io);
  summary->inertial_s += seconds_since(start);
  if (!init.ok || !init.gravity_world.allFinite() || init.v_world_mps.empty()) {
    ++summary->inertial_estimates_refused;
    summary->inertial_refusal = init.ok ? "the estimate is not finite" : init.why;
    return;
  }
  ++summary->inertial_estimates;
  if (!imu_initialised) summary->inertial_initialised_at_s = now.seconds();
  imu_initialised = true;
  gravity_world = init.gravity_world;
  imu_bias = init.bias;
  imu_state.T_world_body = poses.back() * o.T_body_camera.inverse();
  imu_state.v_world_mps = init.v_world_mps.back();
  imu_state_time = stamps.back();
  have_imu_state = true;
}

}  // namespace cairn::vslam
