// VisualSlam's public interface: options, checks of the input, the entry points per sensor and
// the results. The work: tracking.cpp, local_mapping.cpp, loop_closing.cpp, initialisation.cpp.

#include "cairn/vslam/visual_slam.hpp"

#include "cairn/core/problems.hpp"
#include "cairn/vslam/slam_state.hpp"

namespace cairn::vslam {

bool VisualSlamOptions::is_valid(std::string* why) const {
  core::Problems problems;
  auto add = [&](const std::string& p) { problems.add(p); };
  if (std::string p; !orb.is_valid(&p)) add(p);
  if (std::string p; !stereo.is_valid(&p)) add(p);
  if (std::string p; !inertial.is_valid(&p)) add(p);
  if (!(close_depth_baselines > 0.0)) add("close_depth_baselines must be > 0");
  if (min_new_points < 1) add("min_new_points must be >= 1");
  if (!(motion_search_radius_px > 0.0) || !(local_search_radius_px > 0.0)) add("search radii must be > 0");
  if (max_descriptor_distance < 1 || max_descriptor_distance > 256) add("max_descriptor_distance must be in [1, 256]");
  if (!(local_match_ratio > 0.0 && local_match_ratio <= 1.0) || !(reference_match_ratio > 0.0 && reference_match_ratio <= 1.0)) {
    add("match ratios must be in (0, 1]");
  }
  if (lost_below_inliers < 3 || degraded_below_inliers < lost_below_inliers) add("need 3 <= lost_below_inliers <= degraded_below_inliers");
  if (!(keyframe_tracked_ratio > 0.0 && keyframe_tracked_ratio <= 1.0)) add("keyframe_tracked_ratio must be in (0, 1]");
  if (keyframe_max_frames < 1) add("keyframe_max_frames must be >= 1");
  if (max_local_ba_keyframes < 1 || local_map_keyframes < 1) add("keyframe counts must be >= 1");
  if (!(chi2_mono > 0.0) || !(chi2_stereo > 0.0)) add("chi2 thresholds must be > 0");
  if (!(motion_search_radius_rgbd_px > 0.0)) add("motion_search_radius_rgbd_px must be > 0");
  if (loop_min_keyframes_apart < 1 || loop_consistency < 1) add("loop_min_keyframes_apart and loop_consistency must be >= 1");
  if (loop_min_pnp_inliers < 6 || loop_min_matches < loop_min_pnp_inliers) add("need 6 <= loop_min_pnp_inliers <= loop_min_matches");
  if (relocalisation_min_inliers < lost_below_inliers) add("relocalisation_min_inliers must be >= lost_below_inliers");
  if (new_map_after_lost_frames < 0 || merge_recent_keyframes_of_new_map < 0) add("new_map_after_lost_frames and merge_recent_keyframes_of_new_map must be >= 0");
  if (triangulation_keyframes < 0) add("triangulation_keyframes must be >= 0");
  if (!(loop_drift_floor_m >= 0.0) || !(loop_drift_fraction >= 0.0) || !(loop_drift_floor_deg >= 0.0) || !(loop_drift_deg_per_m >= 0.0)) {
    add("the loop drift bounds must be >= 0");
  }
  if (!(triangulation_match_ratio > 0.0 && triangulation_match_ratio <= 1.0)) add("triangulation_match_ratio must be in (0, 1]");
  if (!(keyframe_culling_redundancy > 0.0 && keyframe_culling_redundancy <= 1.0)) add("keyframe_culling_redundancy must be in (0, 1]");
  return problems.report(why);
}

VisualSlam::VisualSlam(const io::CameraCalibration& camera, io::SequenceKind kind, const VisualSlamOptions& options)
    : options_(options) {
  if (std::string p; !options.is_valid(&p)) throw std::invalid_argument("visual SLAM options: " + p);
  if (std::string p; !camera.is_valid(&p)) throw std::invalid_argument("camera calibration: " + p);
  if (kind == io::SequenceKind::kStereo && !(camera.baseline_m > 0.0)) throw std::invalid_argument("stereo needs a positive baseline");
  if (kind == io::SequenceKind::kRgbd && (!(camera.depth_units_per_m > 0.0) || !(camera.virtual_baseline_m > 0.0))) {
    throw std::invalid_argument("RGB-D needs depth_units_per_m and virtual_baseline_m > 0");
  }
  impl_ = std::make_unique<Impl>(camera, kind, options);
  impl_->summary = &summary_;
}

VisualSlam::~VisualSlam() = default;

namespace {
void count(VisualSlamSummary& s, const FrameResult& r) {
  ++s.frames;
  if (r.health == TrackingHealth::kOk) ++s.frames_ok;
  else if (r.health == TrackingHealth::kDegraded) ++s.frames_degraded;
  else ++s.frames_lost;
}
void check_gray(const cv::Mat& image, const char* what) {
  if (image.empty() || image.type() != CV_8UC1) throw std::invalid_argument(std::string(what) + " must be a non-empty 8-bit grey image");
}
// The frame's small blurry image when the tracker may use it (and the image is large enough).
vision::SmallBlurryImage small_blurry_image(const cv::Mat& gray, const VisualSlamOptions& options) {
  if (!options.image_alignment || gray.cols < 64 || gray.rows < 64) return {};
  return vision::make_small_blurry_image(gray);
}
}  // namespace

FrameResult VisualSlam::add_stereo(core::Timestamp time, const cv::Mat& left, const cv::Mat& right) {
  if (impl_->kind != io::SequenceKind::kStereo) throw std::logic_error("add_stereo on an RGB-D VisualSlam");
  check_gray(left, "the left image");
  check_gray(right, "the right image");
  if (left.size() != right.size()) throw std::invalid_argument("the left and right images differ in size");
  impl_->set_image_size(left.cols, left.rows);
  if (left.cols != impl_->width || left.rows != impl_->height) throw std::invalid_argument("the image size changed within the sequence");
  const auto start = Clock::now();
  FrameTimes times;
  vision::Features fl, fr;
  tbb::parallel_invoke([&] { fl = impl_->orb.extract(left); }, [&] { fr = impl_->orb.extract(right); });
  vision::SmallBlurryImage sbi = small_blurry_image(left, options_);
  times.features_s = seconds_since(start);
  const auto stereo_start = Clock::now();
  const vision::StereoMatches stereo = vision::match_stereo(fl, fr, impl_->camera, options_.stereo);
  times.stereo_s = seconds_since(stereo_start);
  FrameResult r = impl_->track(time, fl, stereo, std::move(sbi), times, start);
  count(summary_, r);
  return r;
}

FrameResult VisualSlam::add_rgbd(core::Timestamp time, const cv::Mat& gray, const cv::Mat& depth) {
  if (impl_->kind != io::SequenceKind::kRgbd) throw std::logic_error("add_rgbd on a stereo VisualSlam");
  check_gray(gray, "the image");
  if (depth.type() != CV_16UC1 || depth.size() != gray.size()) throw std::invalid_argument("the depth image must be 16-bit, the image's size");
  impl_->set_image_size(gray.cols, gray.rows);
  if (gray.cols != impl_->width || gray.rows != impl_->height) throw std::invalid_argument("the image size changed within the sequence");
  const auto start = Clock::now();
  FrameTimes times;
  vision::Features f = impl_->orb.extract(gray);
  vision::SmallBlurryImage sbi = small_blurry_image(gray, options_);
  times.features_s = seconds_since(start);
  const auto stereo_start = Clock::now();
  const std::vector<Eigen::Vector2d> undistorted = vision::undistort_keypoints(f.keypoints, impl_->camera);
  const vision::StereoMatches stereo = vision::depth_from_rgbd(f.keypoints, undistorted, depth, impl_->camera);
  times.stereo_s = seconds_since(stereo_start);
  FrameResult r = impl_->track(time, f, stereo, std::move(sbi), times, start);
  count(summary_, r);
  return r;
}

FrameResult VisualSlam::add_monocular(core::Timestamp time, const cv::Mat& gray) {
  if (impl_->kind != io::SequenceKind::kMonocular) throw std::logic_error("add_monocular on a stereo or RGB-D VisualSlam");
  check_gray(gray, "the image");
  impl_->set_image_size(gray.cols, gray.rows);
  if (gray.cols != impl_->width || gray.rows != impl_->height) throw std::invalid_argument("the image size changed within the sequence");
  const auto start = Clock::now();
  FrameTimes times;
  // Twice the features while a map is being initialised, the first or a new segment's (ORB-SLAM3
  // uses mpIniORBextractor whenever its active map is not initialised).
  const bool initialising = impl_->keyframes.empty() || impl_->initialising_new_segment();
  vision::Features f = (initialising ? impl_->orb_initialisation : impl_->orb).extract(gray);
  vision::SmallBlurryImage sbi = small_blurry_image(gray, options_);
  times.features_s = seconds_since(start);
  vision::StereoMatches none;
  none.u_right.assign(f.keypoints.size(), -1.0);
  none.depth_m.assign(f.keypoints.size(), -1.0);
  FrameResult r = impl_->track(time, f, none, std::move(sbi), times, start);
  count(summary_, r);
  return r;
}

std::vector<core::SE3> VisualSlam::trajectory() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<core::SE3> out;
  out.reserve(impl_->relative.size());
  for (const auto& [kf, T_kf_frame] : impl_->relative) {
    out.push_back(kf < 0 ? core::SE3() : impl_->keyframe_pose(kf) * T_kf_frame);
  }
  return out;
}

std::vector<int> VisualSlam::frame_segments() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<int> out;
  out.reserve(impl_->relative.size());
  for (const auto& [kf, T] : impl_->relative) out.push_back(kf < 0 ? -1 : impl_->segment_of(kf));
  return out;
}

int VisualSlam::main_segment() const {
  impl_->join_local_mapping(nullptr);
  return impl_->keyframes.empty() ? 0 : impl_->segment_of(0);
}

const VisualSlamSummary& VisualSlam::summary() const {
  impl_->join_local_mapping(nullptr);
  return summary_;
}

std::vector<core::SE3> VisualSlam::keyframe_poses() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<core::SE3> out;
  for (const auto& kf : impl_->keyframes) {
    if (!kf.bad) out.push_back(kf.frame.T_world_camera);
  }
  return out;
}

std::vector<std::size_t> VisualSlam::keyframe_frames() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<std::size_t> out;
  for (const auto& kf : impl_->keyframes) {
    if (!kf.bad) out.push_back(kf.frame.index);
  }
  return out;
}

std::vector<core::Timestamp> VisualSlam::keyframe_times() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<core::Timestamp> out;
  for (const auto& kf : impl_->keyframes) {
    if (!kf.bad) out.push_back(kf.frame.time);
  }
  return out;
}

std::vector<Eigen::Vector3d> VisualSlam::map_points() const {
  impl_->join_local_mapping(nullptr);  // a keyframe's local mapping still running
  std::vector<Eigen::Vector3d> out;
  for (const auto& mp : impl_->points) {
    if (!mp.bad) out.push_back(mp.p_world);
  }
  return out;
}

}  // namespace cairn::vslam
