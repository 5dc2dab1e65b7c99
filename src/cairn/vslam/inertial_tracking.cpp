// Visual-inertial tracking (issue 40), after ORB-SLAM3 (Campos, Elvira, Gomez
// Rodriguez, Montiel & Tardos, "ORB-SLAM3: An Accurate Open-Source Library for Visual,
// Visual-Inertial and Multi-Map SLAM", T-RO 2021, Sec. V-VII): the IMU, preintegrated from the
// last frame's state (Forster et al., T-RO 2017; inertial/preintegration.hpp), predicts the frame
// in place of the constant-velocity model (ORB-SLAM3 Tracking::PredictStateIMU), and carries the
// frames the images do not track (ORB-SLAM3's RECENTLY_LOST state); gravity, the velocities and the
// biases come from the inertial-only MAP estimate of Campos et al. (ICRA 2020) over the recent
// keyframes, made at every keyframe (with one camera it also gives the map's scale, then watches
// it); the IMU's factor joins each tracked frame's motion-only BA (inertial_pose_terms; ORB-SLAM3
// PoseInertialOptimizationLastFrame). The IMU's factors in the local bundle adjustment:
// local_mapping.cpp (collect_inertial_scope); loops in 4 DoF: loop_closing.cpp (docs/vslam.md,
// "With an IMU").
// The state and the declarations: slam_state.hpp.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

#include "cairn/core/problems.hpp"
#include "cairn/inertial/imu_factors.hpp"
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
  problems.require_positive(pose_sigma_m, "inertial.pose_sigma_m");
  problems.require_positive(pose_sigma_deg, "inertial.pose_sigma_deg");
  problems.require_positive(velocity_sigma_mps, "inertial.velocity_sigma_mps");
  if (!(max_scale_drift > 0.0 && max_scale_drift < 1.0)) problems.add("inertial.max_scale_drift must be in (0, 1)");
  if (!(min_scale_excitation_mps2 >= 0.0 && std::isfinite(min_scale_excitation_mps2))) {
    problems.add("inertial.min_scale_excitation_mps2 must be finite and >= 0");
  }
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
  // to spare; drop the rest in chunks of at least 4,096 (the readings are sorted: a binary search).
  const VisualInertialOptions& o = options_.inertial;
  const double keep_s = o.refinement_window_s + o.max_carried_s + 1.0;
  const auto first_kept = std::partition_point(samples.begin(), samples.end(), [&](const inertial::ImuSample& s) {
    return sample.stamp.seconds() - s.stamp.seconds() > keep_s;
  });
  if (first_kept - samples.begin() >= 4096) samples.erase(samples.begin(), first_kept);
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

// The visual-inertial motion-only BA's terms for this frame (ORB-SLAM3
// PoseInertialOptimizationLastFrame): the last frame's state and its covariance (from that
// frame's own pose optimisation, else pose_sigma_m / pose_sigma_deg / velocity_sigma_mps),
// the readings since, preintegrated at the current biases with the hold's error
// (inertial::hold_error_covariance). None when the IMU does not predict this frame, its scale
// is judged drifted, or inertial.pose_optimisation is off; nor for a frame that relocalises or
// whose pose jumped (ORB-SLAM3 also leaves the IMU out of the frames after a relocalisation):
// the images' verdict on where the camera is must not be pulled back to the IMU's.
std::optional<VisualSlam::Impl::InertialPoseTerms> VisualSlam::Impl::inertial_pose_terms(const TrackingFrame& w) const {
  const VisualInertialOptions& o = options.inertial;
  if (!o.enabled || !o.pose_optimisation || !w.have_imu_prediction || scale_drifted || !have_imu_state) return std::nullopt;
  if (w.relocalising || w.jumped) return std::nullopt;
  InertialPoseTerms terms{inertial::PreintegratedImu(o.noise, imu_bias), core::SE3(), Eigen::Vector3d::Zero()};
  if (!inertial::integrate_interval(imu_samples, imu_state_time, w.f.time, terms.preintegrated) || !(terms.preintegrated.delta_time_s() > 0.0)) {
    return std::nullopt;
  }
  terms.preintegrated.add_covariance(inertial::hold_error_covariance(imu_samples, imu_state_time, w.f.time));
  terms.T_world_camera_previous = camera_pose(imu_state);
  terms.v_world_previous = imu_state.v_world_mps;
  if (have_imu_state_covariance) {
    terms.pose_covariance_previous = imu_state_pose_covariance;
    terms.velocity_covariance_previous = imu_state_velocity_covariance;
  } else {
    const double p = o.pose_sigma_m * o.pose_sigma_m, r = std::pow(o.pose_sigma_deg * std::numbers::pi / 180.0, 2);
    terms.pose_covariance_previous.diagonal() << p, p, p, r, r, r;
    terms.velocity_covariance_previous = Eigen::Matrix3d::Identity() * o.velocity_sigma_mps * o.velocity_sigma_mps;
  }
  terms.v_world = w.imu_prediction.v_world_mps;
  return terms;
}

// The last frame's pose and velocity as variables held by their prior (a pose prior on the camera
// and a velocity prior: the cross-covariance is dropped), this frame's velocity, the biases held
// constant; the IMU factor on the two camera poses (inertial::SensorPoseImuFactor, [F] (45)).
int VisualSlam::Impl::add_inertial_pose_terms(const InertialPoseTerms& imu, backend::LeastSquaresProblem& problem, int pose_variable,
                                               double* values) const {
  backend::se3_to_values(imu.T_world_camera_previous, values);
  Eigen::Map<Eigen::Vector3d>(values + 7) = imu.v_world_previous;
  Eigen::Map<Eigen::Vector3d>(values + 10) = imu.v_world;
  Eigen::Map<inertial::BiasValues>(values + 13) = inertial::to_values(imu_bias);
  const int previous_pose = problem.add_variable(values, backend::se3_manifold());
  const int previous_velocity = problem.add_variable(values + 7, backend::euclidean_manifold(3));
  const int current_velocity = problem.add_variable(values + 10, backend::euclidean_manifold(3));
  const int bias = problem.add_variable(values + 13, backend::euclidean_manifold(6));
  problem.set_constant(bias);
  problem.add_factor(std::make_unique<inertial::PosePriorFactor>(imu.T_world_camera_previous, imu.pose_covariance_previous), {previous_pose});
  problem.add_factor(std::make_unique<inertial::VectorPriorFactor<3>>(imu.v_world_previous, imu.velocity_covariance_previous), {previous_velocity});
  problem.add_factor(std::make_unique<inertial::SensorPoseImuFactor>(inertial::ImuFactor(imu.preintegrated, gravity_world), options.inertial.T_body_camera),
                     {previous_pose, previous_velocity, pose_variable, current_velocity, bias},
                     backend::FactorLoss{backend::RobustKernel::kHuber, std::sqrt(16.92)});
  return current_velocity;
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
// tests/vslam/test_visual_inertial.cpp (a 150 degree turn in 0.4 s: without it the view's frames
// were carried until max_carried_s ran out).
void VisualSlam::Impl::map_carried_view(TrackingFrame& w) {
  if (localization_only || w.result.stereo_points < options.min_new_points) return;
  const auto mapping_start = Clock::now();
  std::fill(w.f.map_point.begin(), w.f.map_point.end(), -1);
  insert_keyframe(w.f);
  start_keyframe_imu_state(w);
  detect_and_close_loop(w.result);
  w.f.T_world_camera = keyframes.back().frame.T_world_camera;
  w.f.map_point = keyframes.back().frame.map_point;
  w.times.mapping_s = seconds_since(mapping_start);
  w.result.keyframe = true;
  w.result.note += "; its view mapped as a keyframe at that pose";
}

// The newest keyframe's velocity and biases, until the inertial estimate or the local BA
// refines them: the IMU's prediction at its frame and the current biases (ORB-SLAM3 gives a new
// keyframe the frame's predicted state the same way).
void VisualSlam::Impl::start_keyframe_imu_state(const TrackingFrame& w) {
  if (!w.have_imu_prediction) return;
  KeyFrame& kf = keyframes.back();
  kf.has_imu_state = true;
  kf.v_world_mps = w.imu_terms && w.imu_terms->solved ? w.imu_terms->v_world : w.imu_prediction.v_world_mps;
  kf.imu_bias = imu_bias;
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
      // The visual-inertial pose optimisation's velocity and covariance when it ran.
      const bool refined = w.imu_terms && w.imu_terms->solved;
      imu_state.T_world_body = w.f.T_world_camera * options.inertial.T_body_camera.inverse();
      imu_state.v_world_mps = refined ? w.imu_terms->v_world : w.imu_prediction.v_world_mps;
      imu_state_time = w.f.time;
      have_imu_state = true;
      have_imu_state_covariance = refined && w.imu_terms->covariance_ok;
      if (have_imu_state_covariance) {
        imu_state_pose_covariance = w.imu_terms->pose_covariance;
        imu_state_velocity_covariance = w.imu_terms->velocity_covariance;
      }
    } else {
      have_imu_state = false;
      have_imu_state_covariance = false;
    }
    if (result.keyframe && !localization_only) estimate_inertial(w);
    if (scale_drifted && kind == io::SequenceKind::kMonocular) {
      char buffer[160];
      std::snprintf(buffer, sizeof buffer, "the IMU puts the map's scale at %.3f of itself (max_scale_drift %.2f): monocular scale drift",
                    summary->monocular_scale_estimate, options.inertial.max_scale_drift);
      if (result.health == TrackingHealth::kOk) result.health = TrackingHealth::kDegraded;
      result.note = result.note.empty() ? std::string(buffer) : result.note + "; " + buffer;
      ++summary->frames_scale_drifted;
    }
  } else if (result.carried_by_imu) {
    imu_state.T_world_body = w.f.T_world_camera * options.inertial.T_body_camera.inverse();
    imu_state.v_world_mps = w.imu_prediction.v_world_mps;
    imu_state_time = w.f.time;
    have_imu_state_covariance = false;
  } else {
    have_imu_state = false;
    have_imu_state_covariance = false;
  }
}

// Issue 40's health rule: a tracked frame whose visual pose the IMU's prediction contradicts
// (farther than disagreement_m / disagreement_deg) is degraded, with both distances in its note.
void VisualSlam::Impl::check_against_imu(TrackingFrame& w) {
  if (!w.have_imu_prediction) return;
  double distance_m = 0.0, angle_deg = 0.0;
  if (agrees_with_imu(w, &distance_m, &angle_deg)) return;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "the IMU's prediction and the images disagree by %.3f m and %.2f deg", distance_m, angle_deg);
  if (w.result.health == TrackingHealth::kOk) w.result.health = TrackingHealth::kDegraded;
  w.result.note = w.result.note.empty() ? std::string(buffer) : w.result.note + "; " + buffer;
  ++summary->frames_contradicting_imu;
}

// Whether the frame's pose lies within disagreement_m / disagreement_deg of the IMU's prediction
// (false without one); the distances when asked.
bool VisualSlam::Impl::agrees_with_imu(const TrackingFrame& w, double* distance_m, double* angle_deg) const {
  if (!w.have_imu_prediction) return false;
  const core::SE3 predicted = camera_pose(w.imu_prediction);
  const double d = (predicted.translation() - w.f.T_world_camera.translation()).norm();
  const double a = (predicted.so3().inverse() * w.f.T_world_camera.so3()).log().norm() * 180.0 / 3.14159265358979323846;
  if (distance_m) *distance_m = d;
  if (angle_deg) *angle_deg = a;
  return d <= options.inertial.disagreement_m && a <= options.inertial.disagreement_deg;
}

// The inertial-only MAP estimate (Campos et al., ICRA 2020; inertial_initialization.hpp) over
// the good keyframes of the current segment within the last window (initialisation_window_s
// before the first success, refinement_window_s after). Stereo and depth are metric: the scale is
// held at 1. One camera: the first estimate's scale rescales the segment to metres
// (rescale_segment; ORB-SLAM3 scales its map after the inertial initialisation), and every later
// one estimates the scale again to watch it: more than max_scale_drift off 1, the map's unit has
// drifted (or collapsed), the frames are degraded (advance_inertial_state) and the IMU stops
// predicting until an estimate agrees again. Needs the keyframes to span three quarters of the
// initialisation window; a refusal is counted with its reason and changes nothing. On success
// the newest keyframe (the frame just tracked) gives the state: its pose, its estimated velocity.
void VisualSlam::Impl::estimate_inertial(TrackingFrame& w) {
  const VisualInertialOptions& o = options.inertial;
  const bool monocular = kind == io::SequenceKind::kMonocular;
  const int current = find(segment);
  // A monocular segment has its own unit: a new one (or a merge that renamed it) starts again.
  if (monocular && current != inertial_segment) {
    imu_initialised = false;
    have_imu_state = false;
    scale_drifted = false;
  }
  inertial_segment = current;
  // The first monocular estimate rescales the map: the keyframe's bundle adjustment (running in
  // the background) is taken first, so it does not overwrite the rescaled map with its unit.
  if (monocular && !imu_initialised && mapping_job.running) {
    join_local_mapping(&w.result);
    w.f.T_world_camera = keyframes.back().frame.T_world_camera;
    w.f.map_point = keyframes.back().frame.map_point;
  }
  const double now_s = w.f.time.seconds();
  const double window_s = imu_initialised ? o.refinement_window_s : o.initialisation_window_s;
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> poses;
  std::vector<int> ids;
  for (const KeyFrame& kf : keyframes) {
    if (kf.bad || find(kf.segment) != current || now_s - kf.frame.time.seconds() > window_s + 1e-9) continue;
    if (!stamps.empty() && !(stamps.back() < kf.frame.time)) continue;
    stamps.push_back(kf.frame.time);
    poses.push_back(kf.frame.T_world_camera);
    ids.push_back(kf.id);
  }
  // Keyframes come every few frames: three quarters of the initialisation window is "spans it".
  if (stamps.size() < 3 || stamps.back().seconds() - stamps.front().seconds() < 0.75 * o.initialisation_window_s) return;
  // The IMU sees the scale only through acceleration ([C] Sec. V: no excitation, no scale): the
  // keyframes' accelerations by second differences of their positions (metres once initialised),
  // RMS over the window. Below min_scale_excitation_mps2 a refinement holds the scale at 1 and
  // does not judge it (on a straight leg at constant speed the scale estimate is noise).
  double excitation2 = 0.0;
  for (std::size_t k = 1; k + 1 < stamps.size(); ++k) {
    const double dt0 = stamps[k].seconds() - stamps[k - 1].seconds(), dt1 = stamps[k + 1].seconds() - stamps[k].seconds();
    const Eigen::Vector3d v0 = (poses[k].translation() - poses[k - 1].translation()) / dt0;
    const Eigen::Vector3d v1 = (poses[k + 1].translation() - poses[k].translation()) / dt1;
    excitation2 += (2.0 * (v1 - v0) / (dt0 + dt1)).squaredNorm() / static_cast<double>(stamps.size() - 2);
  }
  const bool judge_scale = monocular && (!imu_initialised || std::sqrt(excitation2) >= o.min_scale_excitation_mps2);
  if (monocular && imu_initialised && !judge_scale) {
    ++summary->scale_estimates_unexcited;
    if (scale_drifted) return;  // the last judgement stands until an excited window says otherwise
  }
  const auto start = Clock::now();
  inertial::InertialInitializationOptions io;
  io.estimate_scale = judge_scale;
  io.gravity_mps2 = o.gravity_mps2;
  const inertial::InertialInitialization init =
      inertial::initialize_inertial(stamps, poses, o.T_body_camera.inverse(), imu_samples, o.noise, io);
  summary->inertial_s += seconds_since(start);
  if (!init.ok || !init.gravity_world.allFinite() || init.v_world_mps.empty() || !(init.scale > 0.0)) {
    ++summary->inertial_estimates_refused;
    summary->inertial_refusal = init.ok ? "the estimate is not finite" : init.why;
    return;
  }
  ++summary->inertial_estimates;
  if (monocular && !imu_initialised) {
    rescale_segment(current, init.scale);
    summary->monocular_initial_scale = init.scale;
    w.f.T_world_camera = keyframes.back().frame.T_world_camera;  // the frame is the newest keyframe
  } else if (judge_scale) {
    summary->monocular_scale_estimate = init.scale;
    scale_drifted = std::abs(init.scale - 1.0) > o.max_scale_drift;
    if (scale_drifted) {
      have_imu_state = false;
      return;
    }
  }
  if (!imu_initialised) summary->inertial_initialised_at_s = now_s;
  imu_initialised = true;
  gravity_world = init.gravity_world;
  imu_bias = init.bias;
  // The window's keyframes take the estimate's velocities and biases: the local BA's start.
  for (std::size_t k = 0; k < ids.size() && k < init.v_world_mps.size(); ++k) {
    KeyFrame& kf = keyframes[static_cast<std::size_t>(ids[k])];
    kf.has_imu_state = true;
    kf.v_world_mps = init.v_world_mps[k];
    kf.imu_bias = init.bias;
  }
  imu_state.T_world_body = w.f.T_world_camera * o.T_body_camera.inverse();
  imu_state.v_world_mps = init.v_world_mps.back();
  imu_state_time = w.f.time;
  have_imu_state = true;
  have_imu_state_covariance = false;
}

// Multiplies segment `seg`'s distances by `scale` about its first keyframe's camera centre:
// keyframe positions, culled keyframes' offsets from their parents, points, the frames' offsets
// from their reference keyframes, and, when it is the current segment, the last frame and the
// constant-velocity step (as a Sim(3) correction moves them, loop_closing.cpp).
void VisualSlam::Impl::rescale_segment(int seg, double scale) {
  std::vector<char> in(keyframes.size(), 0);
  int first = -1;
  for (const KeyFrame& kf : keyframes) {
    if (find(kf.segment) != seg) continue;
    in[static_cast<std::size_t>(kf.id)] = 1;
    if (first < 0) first = kf.id;
  }
  if (first < 0) return;
  const Eigen::Vector3d a = keyframe_pose(first).translation();
  const auto moved = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d { return a + scale * (p - a); };
  const auto scaled = [&](const core::SE3& T) { return core::SE3(T.so3(), scale * T.translation()); };
  for (KeyFrame& kf : keyframes) {
    if (!in[static_cast<std::size_t>(kf.id)]) continue;
    kf.frame.T_world_camera = core::SE3(kf.frame.T_world_camera.so3(), moved(kf.frame.T_world_camera.translation()));
    kf.T_parent_keyframe = scaled(kf.T_parent_keyframe);
  }
  for (MapPoint& mp : points) {
    if (mp.bad || !in[static_cast<std::size_t>(mp.reference_keyframe)]) continue;
    mp.p_world = moved(mp.p_world);
    update_normal_and_depth(mp);
  }
  for (auto& [r, T_r_frame] : relative) {
    if (r >= 0 && in[static_cast<std::size_t>(r)]) T_r_frame = scaled(T_r_frame);
  }
  if (find(segment) == seg) {
    last.T_world_camera = core::SE3(last.T_world_camera.so3(), moved(last.T_world_camera.translation()));
    T_world_last_tracked = core::SE3(T_world_last_tracked.so3(), moved(T_world_last_tracked.translation()));
    velocity = scaled(velocity);
  }
}

}  // namespace cairn::vslam
