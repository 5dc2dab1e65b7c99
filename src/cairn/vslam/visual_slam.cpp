#include "cairn/vslam/visual_slam.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <set>
#include <unordered_map>

#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/io/pose_graph.hpp"
#include "cairn/backend/reprojection_factors.hpp"

namespace cairn::vslam {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// A factor whose residual and Jacobians are scaled by sqrt(information) = 1 / sigma of the
// keypoint's level (ORB-SLAM2's invLevelSigma2 information), optionally with the point held
// fixed inside it (motion-only BA: the factor then has the pose as its only variable).
class ScaledFactor final : public backend::Factor {
 public:
  ScaledFactor(std::unique_ptr<backend::Factor> inner, double sqrt_information, const Eigen::Vector3d* fixed_point = nullptr)
      : inner_(std::move(inner)), weight_(sqrt_information), fixed_(fixed_point != nullptr) {
    if (fixed_point) point_ = *fixed_point;
  }
  int residual_size() const override { return inner_->residual_size(); }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    const int m = inner_->residual_size();
    bool ok;
    if (fixed_) {
      const double* v[2] = {values[0], point_.data()};
      double* j[2] = {jacobians ? jacobians[0] : nullptr, nullptr};
      ok = inner_->evaluate(v, residual, jacobians ? j : nullptr);
    } else {
      ok = inner_->evaluate(values, residual, jacobians);
    }
    if (!ok) return false;
    for (int i = 0; i < m; ++i) residual[i] *= weight_;
    if (jacobians) {
      const int blocks = fixed_ ? 1 : 2;
      const int sizes[2] = {6, 3};
      for (int b = 0; b < blocks; ++b) {
        if (!jacobians[b]) continue;
        for (int i = 0; i < m * sizes[b]; ++i) jacobians[b][i] *= weight_;
      }
    }
    return true;
  }

 private:
  std::unique_ptr<backend::Factor> inner_;
  double weight_;
  bool fixed_;
  Eigen::Vector3d point_ = Eigen::Vector3d::Zero();
};

constexpr int kGridCols = 64;
constexpr int kGridRows = 48;

struct FrameData {
  std::size_t index = 0;
  core::Timestamp time;
  std::vector<cv::KeyPoint> keypoints;
  std::vector<Eigen::Vector2d> undistorted;
  std::vector<double> u_right, depth;
  cv::Mat descriptors;
  std::vector<int> map_point;  // id or -1
  std::vector<char> outlier;
  std::vector<std::vector<int>> grid;
  core::SE3 T_world_camera;
  std::size_t size() const { return keypoints.size(); }
};

struct MapPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  cv::Mat descriptor;  // 1 x 32
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double min_distance = 0.0, max_distance = 0.0;
  std::map<int, int> observations;  // keyframe id -> keypoint index
  int first_keyframe = 0;
  int reference_keyframe = 0;
  int visible = 1, found = 1;
  bool bad = false;
  std::uint64_t last_search = 0;  // search_by_projection's stamp: considered already
};

struct KeyFrame {
  int id = 0;
  FrameData frame;
  bool bad = false;
  int segment = 0;              // the map segment it was created in
  bool starts_segment = false;  // the first keyframe of a segment: no odometry link to the one before
  vision::BowVector bow;  // empty without a vocabulary
};

}  // namespace

vision::OrbOptions doubled(vision::OrbOptions o) {
  o.features *= 2;
  return o;
}

struct VisualSlam::Impl {
  io::CameraCalibration camera;
  io::SequenceKind kind;
  VisualSlamOptions options;
  VisualSlamSummary* summary = nullptr;
  vision::OrbExtractor orb;
  vision::OrbExtractor orb_initialisation;  // monocular, until initialised: twice the features (ORB-SLAM2 mpIniORBextractor)
  double bf = 0.0;            // fx * baseline (virtual for RGB-D)
  double close_depth_m = 0.0; // ThDepth in metres
  double min_x = 0, max_x = 0, min_y = 0, max_y = 0;
  double cell_w_inv = 0, cell_h_inv = 0;
  int width = 0, height = 0;
  std::vector<double> scales, inv_sigma2;

  std::vector<MapPoint> points;
  std::vector<KeyFrame> keyframes;
  std::vector<int> recent_points;
  FrameData last;
  bool have_last = false;
  bool have_velocity = false;
  core::SE3 velocity;  // T_last_current of the last step: T_current = T_last * velocity
  int reference_keyframe = -1;
  int last_keyframe_frame = 0;
  std::size_t frames = 0;
  bool lost = false;
  std::uint64_t search_stamp = 0;
  // Place recognition.
  vision::BowDatabase database;
  int last_loop_keyframe = 0;
  std::vector<std::pair<std::set<int>, int>> consistent_groups;  // ORB-SLAM2 mvConsistentGroups
  // The Atlas: map segments, merged by union-find.
  int segment = 0;
  std::vector<int> segment_parent{0};
  int lost_frames = 0;
  int find(int s) const {
    while (segment_parent[static_cast<std::size_t>(s)] != s) s = segment_parent[static_cast<std::size_t>(s)];
    return s;
  }
  int segment_of(int kf) const { return find(keyframes[static_cast<std::size_t>(kf)].segment); }
  // Per frame: reference keyframe and the pose relative to it, for the final trajectory.
  std::vector<std::pair<int, core::SE3>> relative;

  Impl(const io::CameraCalibration& c, io::SequenceKind k, const VisualSlamOptions& o)
      : camera(c), kind(k), options(o), orb(o.orb), orb_initialisation(doubled(o.orb)) {
    const double baseline = kind == io::SequenceKind::kStereo ? camera.baseline_m : camera.virtual_baseline_m;
    bf = camera.fx * baseline;
    close_depth_m = options.close_depth_baselines * baseline;
    double s = 1.0;
    for (int l = 0; l < options.orb.levels; ++l) {
      scales.push_back(s);
      inv_sigma2.push_back(1.0 / (s * s));
      s *= options.orb.scale_factor;
    }
  }

  void set_image_size(int w, int h) {
    if (width != 0) return;
    width = w;
    height = h;
    std::vector<cv::KeyPoint> corners{cv::KeyPoint(0.f, 0.f, 1.f), cv::KeyPoint(static_cast<float>(w), 0.f, 1.f),
                                      cv::KeyPoint(0.f, static_cast<float>(h), 1.f),
                                      cv::KeyPoint(static_cast<float>(w), static_cast<float>(h), 1.f)};
    const auto u = vision::undistort_keypoints(corners, camera);
    min_x = std::min(u[0].x(), u[2].x());
    max_x = std::max(u[1].x(), u[3].x());
    min_y = std::min(u[0].y(), u[1].y());
    max_y = std::max(u[2].y(), u[3].y());
    cell_w_inv = kGridCols / (max_x - min_x);
    cell_h_inv = kGridRows / (max_y - min_y);
  }

  bool cell_of(double x, double y, int& cx, int& cy) const {
    cx = static_cast<int>(std::floor((x - min_x) * cell_w_inv));
    cy = static_cast<int>(std::floor((y - min_y) * cell_h_inv));
    return cx >= 0 && cx < kGridCols && cy >= 0 && cy < kGridRows;
  }

  void build_grid(FrameData& f) const {
    f.grid.assign(kGridCols * kGridRows, {});
    for (std::size_t i = 0; i < f.size(); ++i) {
      int cx, cy;
      if (cell_of(f.undistorted[i].x(), f.undistorted[i].y(), cx, cy)) f.grid[static_cast<std::size_t>(cy * kGridCols + cx)].push_back(static_cast<int>(i));
    }
  }

  std::vector<int> features_in_area(const FrameData& f, double x, double y, double r, int min_level, int max_level) const {
    std::vector<int> out;
    const int x0 = std::max(0, static_cast<int>(std::floor((x - r - min_x) * cell_w_inv)));
    const int x1 = std::min(kGridCols - 1, static_cast<int>(std::ceil((x + r - min_x) * cell_w_inv)));
    const int y0 = std::max(0, static_cast<int>(std::floor((y - r - min_y) * cell_h_inv)));
    const int y1 = std::min(kGridRows - 1, static_cast<int>(std::ceil((y + r - min_y) * cell_h_inv)));
    if (x0 > x1 || y0 > y1) return out;
    for (int cy = y0; cy <= y1; ++cy) {
      for (int cx = x0; cx <= x1; ++cx) {
        for (const int i : f.grid[static_cast<std::size_t>(cy * kGridCols + cx)]) {
          const cv::KeyPoint& kp = f.keypoints[static_cast<std::size_t>(i)];
          if (kp.octave < min_level || kp.octave > max_level) continue;
          const Eigen::Vector2d& u = f.undistorted[static_cast<std::size_t>(i)];
          if (std::abs(u.x() - x) < r && std::abs(u.y() - y) < r) out.push_back(i);
        }
      }
    }
    return out;
  }

  bool project(const core::SE3& T_camera_world, const Eigen::Vector3d& p_world, double& u, double& v, double& ur, double& z) const {
    const Eigen::Vector3d p = T_camera_world * p_world;
    z = p.z();
    if (!(z > 1e-6)) return false;
    u = camera.fx * p.x() / z + camera.cx;
    v = camera.fy * p.y() / z + camera.cy;
    ur = u - bf / z;
    return u >= min_x && u < max_x && v >= min_y && v < max_y;
  }

  int predict_level(const MapPoint& mp, double distance) const {
    const double ratio = mp.max_distance / distance;
    int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(options.orb.scale_factor)));
    return std::clamp(level, 0, options.orb.levels - 1);
  }

  Eigen::Vector3d unproject(const FrameData& f, std::size_t i) const {
    const double z = f.depth[i];
    const Eigen::Vector3d p_camera((f.undistorted[i].x() - camera.cx) * z / camera.fx, (f.undistorted[i].y() - camera.cy) * z / camera.fy, z);
    return f.T_world_camera * p_camera;
  }

  // --- Frames ---------------------------------------------------------------------------------

  FrameData make_frame(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo) const {
    FrameData f;
    f.index = frames;
    f.time = time;
    f.keypoints = std::move(left.keypoints);
    f.descriptors = left.descriptors;
    f.undistorted = vision::undistort_keypoints(f.keypoints, camera);
    f.u_right = stereo.u_right;
    f.depth = stereo.depth_m;
    f.map_point.assign(f.size(), -1);
    f.outlier.assign(f.size(), 0);
    build_grid(f);
    return f;
  }

  // --- Map points -----------------------------------------------------------------------------

  void update_normal_and_depth(MapPoint& mp) {
    if (mp.observations.empty()) return;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    for (const auto& [kf, idx] : mp.observations) {
      const Eigen::Vector3d d = mp.p_world - keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera.translation();
      normal += d.normalized();
    }
    mp.normal = normal.normalized();
    const KeyFrame& ref = keyframes[static_cast<std::size_t>(mp.reference_keyframe)];
    auto it = mp.observations.find(mp.reference_keyframe);
    if (it == mp.observations.end()) it = mp.observations.begin();
    const KeyFrame& r = it->first == mp.reference_keyframe ? ref : keyframes[static_cast<std::size_t>(it->first)];
    const double distance = (mp.p_world - r.frame.T_world_camera.translation()).norm();
    const int level = r.frame.keypoints[static_cast<std::size_t>(it->second)].octave;
    mp.max_distance = distance * scales[static_cast<std::size_t>(level)];
    mp.min_distance = mp.max_distance / scales.back();
  }

  // The observation's descriptor with the least median distance to the others (ORB-SLAM2
  // MapPoint::ComputeDistinctiveDescriptors).
  void update_descriptor(MapPoint& mp) {
    std::vector<const unsigned char*> d;
    for (const auto& [kf, idx] : mp.observations) d.push_back(keyframes[static_cast<std::size_t>(kf)].frame.descriptors.ptr(idx));
    if (d.empty()) return;
    if (d.size() <= 2) {
      mp.descriptor = cv::Mat(1, 32, CV_8U, const_cast<unsigned char*>(d.front())).clone();
      return;
    }
    std::size_t best = 0;
    int best_median = 1 << 30;
    for (std::size_t i = 0; i < d.size(); ++i) {
      std::vector<int> dist;
      for (std::size_t j = 0; j < d.size(); ++j) dist.push_back(vision::descriptor_distance(d[i], d[j]));
      std::nth_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>((dist.size() - 1) / 2), dist.end());
      const int median = dist[(dist.size() - 1) / 2];
      if (median < best_median) {
        best_median = median;
        best = i;
      }
    }
    mp.descriptor = cv::Mat(1, 32, CV_8U, const_cast<unsigned char*>(d[best])).clone();
  }

  int observation_weight(const MapPoint& mp) const {
    int n = 0;
    for (const auto& [kf, idx] : mp.observations) n += keyframes[static_cast<std::size_t>(kf)].frame.u_right[static_cast<std::size_t>(idx)] >= 0 ? 2 : 1;
    return n;
  }

  void erase_observation(int point, int kf) {
    MapPoint& mp = points[static_cast<std::size_t>(point)];
    auto it = mp.observations.find(kf);
    if (it == mp.observations.end()) return;
    FrameData& f = keyframes[static_cast<std::size_t>(kf)].frame;
    if (f.map_point[static_cast<std::size_t>(it->second)] == point) f.map_point[static_cast<std::size_t>(it->second)] = -1;
    mp.observations.erase(it);
    if (mp.observations.empty() || observation_weight(mp) <= 1) {
      set_bad(point);
    } else if (mp.reference_keyframe == kf) {
      mp.reference_keyframe = mp.observations.begin()->first;
    }
  }

  void set_bad(int point) {
    MapPoint& mp = points[static_cast<std::size_t>(point)];
    if (mp.bad) return;
    mp.bad = true;
    for (const auto& [kf, idx] : mp.observations) {
      FrameData& f = keyframes[static_cast<std::size_t>(kf)].frame;
      if (f.map_point[static_cast<std::size_t>(idx)] == point) f.map_point[static_cast<std::size_t>(idx)] = -1;
    }
    mp.observations.clear();
    ++summary->map_points_culled;
  }

  // --- Matching -------------------------------------------------------------------------------

  // ORB-SLAM2 ORBmatcher::SearchByProjection(CurrentFrame, LastFrame, th, bMono) without the
  // rotation-histogram check (stereo and RGB-D do not use it).
  int search_from_last(FrameData& current, const FrameData& previous, double radius_px) {
    const core::SE3 T_cw = current.T_world_camera.inverse();
    int matches = 0;
    for (std::size_t i = 0; i < previous.size(); ++i) {
      const int id = previous.map_point[i];
      if (id < 0 || previous.outlier[i]) continue;
      const MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) continue;
      double u, v, ur, z;
      if (!project(T_cw, mp.p_world, u, v, ur, z)) continue;
      const int level = previous.keypoints[i].octave;
      const double r = radius_px * scales[static_cast<std::size_t>(level)];
      const std::vector<int> candidates = features_in_area(current, u, v, r, std::max(0, level - 1), level + 1);
      int best = 256, best_j = -1;
      for (const int j : candidates) {
        const auto sj = static_cast<std::size_t>(j);
        if (current.map_point[sj] >= 0) continue;
        if (current.u_right[sj] >= 0 && std::abs(ur - current.u_right[sj]) > r) continue;
        const int d = vision::descriptor_distance(mp.descriptor.ptr(), current.descriptors.ptr(j));
        if (d < best) {
          best = d;
          best_j = j;
        }
      }
      if (best_j >= 0 && best <= options.max_descriptor_distance) {
        current.map_point[static_cast<std::size_t>(best_j)] = id;
        ++matches;
      }
    }
    return matches;
  }

  // Brute-force descriptor matching of the frame's keypoints against the points `ids` with a
  // ratio test and TH_LOW (50): the matcher of the reference fallback, relocalisation and loop
  // verification (ORB-SLAM2 restricts these to keypoints in the same bag-of-words node instead).
  int match_brute_force(FrameData& current, const std::vector<int>& point_ids) {
    std::vector<int> ids;
    cv::Mat descriptors;
    for (const int id : point_ids) {
      if (id < 0 || points[static_cast<std::size_t>(id)].bad) continue;
      ids.push_back(id);
      descriptors.push_back(points[static_cast<std::size_t>(id)].descriptor);
    }
    if (ids.empty() || current.descriptors.rows == 0) return 0;
    cv::BFMatcher matcher(cv::NORM_HAMMING);
    std::vector<std::vector<cv::DMatch>> knn;
    matcher.knnMatch(current.descriptors, descriptors, knn, 2);
    std::vector<int> taken(ids.size(), -1);
    std::vector<float> taken_distance(ids.size(), 1e9f);
    for (const auto& m : knn) {
      if (m.empty() || static_cast<double>(m[0].distance) > options.max_descriptor_distance / 2.0) continue;
      if (m.size() > 1 && static_cast<double>(m[0].distance) > options.reference_match_ratio * static_cast<double>(m[1].distance)) continue;
      if (current.map_point[static_cast<std::size_t>(m[0].queryIdx)] >= 0) continue;
      const auto t = static_cast<std::size_t>(m[0].trainIdx);
      if (m[0].distance < taken_distance[t]) {
        taken[t] = m[0].queryIdx;
        taken_distance[t] = m[0].distance;
      }
    }
    int matches = 0;
    for (std::size_t t = 0; t < ids.size(); ++t) {
      if (taken[t] < 0) continue;
      current.map_point[static_cast<std::size_t>(taken[t])] = ids[t];
      ++matches;
    }
    return matches;
  }

  int search_reference(FrameData& current, const KeyFrame& kf) { return match_brute_force(current, kf.frame.map_point); }

  // PnP with RANSAC (OpenCV's solvePnPRansac, EPnP minimal sets; Lepetit et al. 2009) on the
  // frame's map-point matches: the starting pose when there is no prediction. Matches that are
  // not RANSAC inliers are dropped. Returns the inliers (0 when it fails).
  int pnp_ransac(FrameData& f) const {
    std::vector<cv::Point3d> object;
    std::vector<cv::Point2d> image;
    std::vector<std::size_t> index;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.map_point[i] < 0) continue;
      const Eigen::Vector3d& p = points[static_cast<std::size_t>(f.map_point[i])].p_world;
      object.emplace_back(p.x(), p.y(), p.z());
      image.emplace_back(f.undistorted[i].x(), f.undistorted[i].y());
      index.push_back(i);
    }
    if (object.size() < 6) return 0;
    const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    cv::Mat rvec, tvec;
    std::vector<int> inliers;
    bool ok = false;
    try {
      ok = cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 200, 3.0f, 0.99, inliers, cv::SOLVEPNP_EPNP);
    } catch (const cv::Exception&) {
      ok = false;
    }
    if (!ok || inliers.size() < 6) {
      std::fill(f.map_point.begin(), f.map_point.end(), -1);
      return 0;
    }
    cv::Matx33d R;
    cv::Rodrigues(rvec, R);
    Eigen::Matrix4d T_camera_world = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) T_camera_world(r, c) = R(r, c);
      T_camera_world(r, 3) = tvec.at<double>(r);
    }
    f.T_world_camera = core::SE3::from_matrix(T_camera_world).inverse();
    std::vector<char> keep(index.size(), 0);
    for (const int k : inliers) keep[static_cast<std::size_t>(k)] = 1;
    for (std::size_t k = 0; k < index.size(); ++k) {
      if (!keep[k]) f.map_point[index[k]] = -1;
    }
    return static_cast<int>(inliers.size());
  }

  // --- Motion-only bundle adjustment (ORB-SLAM2 Optimizer::PoseOptimization) ------------------

  // chi^2 of keypoint i of f observing p_world from T_camera_world: the squared reprojection
  // error (u, v and, with stereo/depth, u_right) times the level's information (ORB-SLAM2's
  // chi2() of its edges); infinite behind the camera.
  double chi2(const FrameData& f, std::size_t i, const core::SE3& T_cw, const Eigen::Vector3d& p_world) const {
    const Eigen::Vector3d p = T_cw * p_world;
    if (!(p.z() > 1e-6)) return std::numeric_limits<double>::infinity();
    const double u = camera.fx * p.x() / p.z() + camera.cx, v = camera.fy * p.y() / p.z() + camera.cy;
    double e2 = (u - f.undistorted[i].x()) * (u - f.undistorted[i].x()) + (v - f.undistorted[i].y()) * (v - f.undistorted[i].y());
    if (f.u_right[i] >= 0) {
      const double ur = u - bf / p.z();
      e2 += (ur - f.u_right[i]) * (ur - f.u_right[i]);
    }
    return e2 * inv_sigma2[static_cast<std::size_t>(f.keypoints[i].octave)];
  }
  double chi2_of(const FrameData& f, std::size_t i, const core::SE3& T_cw) const {
    return chi2(f, i, T_cw, points[static_cast<std::size_t>(f.map_point[i])].p_world);
  }

  std::unique_ptr<backend::Factor> observation_factor(const FrameData& f, std::size_t i) const {
    const backend::PinholeIntrinsics K{camera.fx, camera.fy, camera.cx, camera.cy};
    const double baseline = bf / camera.fx;
    if (f.u_right[i] >= 0) {
      return std::make_unique<backend::StereoReprojectionFactor>(K, baseline, f.undistorted[i].x(), f.undistorted[i].y(), f.u_right[i]);
    }
    return std::make_unique<backend::PinholeReprojectionFactor>(K, f.undistorted[i].x(), f.undistorted[i].y());
  }

  // Returns the inliers; marks outliers in f.outlier; sets f.T_world_camera.
  int optimize_pose(FrameData& f, double* sigma_position_m = nullptr) {
    std::vector<std::size_t> matched;
    for (std::size_t i = 0; i < f.size(); ++i) {
      f.outlier[i] = 0;
      if (f.map_point[i] >= 0) matched.push_back(i);
    }
    if (matched.size() < 3) return 0;
    const core::SE3 initial = f.T_world_camera;
    core::SE3 T = initial;
    backend::LeastSquaresOptions lso;
    lso.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
    lso.max_iterations = 10;
    lso.threads = 1;
    int inliers = 0;
    for (int round = 0; round < 4; ++round) {
      backend::LeastSquaresProblem problem;
      double pose[7];
      backend::se3_to_values(initial, pose);  // every round starts from the prediction, as ORB-SLAM2
      const int var = problem.add_variable(pose, backend::se3_manifold());
      for (const std::size_t i : matched) {
        if (f.outlier[i]) continue;
        const bool stereo = f.u_right[i] >= 0;
        const double sqrt_info = 1.0 / scales[static_cast<std::size_t>(f.keypoints[i].octave)];
        backend::FactorLoss loss;
        if (round < 2) loss = {backend::RobustKernel::kHuber, std::sqrt(stereo ? options.chi2_stereo : options.chi2_mono)};
        problem.add_factor(std::make_unique<ScaledFactor>(observation_factor(f, i), sqrt_info,
                                                          &points[static_cast<std::size_t>(f.map_point[i])].p_world),
                           {var}, loss);
      }
      if (problem.num_factors() < 3) break;
      const backend::LeastSquaresSummary s = backend::solve(problem, lso);
      if (s.is_solution_usable()) T = backend::se3_from_values(pose);
      const core::SE3 T_cw = T.inverse();
      inliers = 0;
      for (const std::size_t i : matched) {
        const double chi2 = chi2_of(f, i, T_cw);
        const double threshold = f.u_right[i] >= 0 ? options.chi2_stereo : options.chi2_mono;
        f.outlier[i] = chi2 > threshold ? 1 : 0;
        if (!f.outlier[i]) ++inliers;
      }
      if (round == 3 && sigma_position_m && inliers >= 3) {
        // Covariance of the pose at the solution, from the inliers only.
        backend::LeastSquaresProblem cp;
        double cpose[7];
        backend::se3_to_values(T, cpose);
        const int cv = cp.add_variable(cpose, backend::se3_manifold());
        for (const std::size_t i : matched) {
          if (f.outlier[i]) continue;
          cp.add_factor(std::make_unique<ScaledFactor>(observation_factor(f, i), 1.0 / scales[static_cast<std::size_t>(f.keypoints[i].octave)],
                                                       &points[static_cast<std::size_t>(f.map_point[i])].p_world),
                        {cv});
        }
        const backend::MarginalCovariances c = backend::marginal_covariances(cp, {cv}, 1);
        if (c.ok) {
          // Tangent (rho, phi) on the right: the position block in the camera frame; its
          // largest eigenvalue is frame-independent. Pixel noise of 1 px at level 0 assumed.
          const Eigen::Matrix3d P = c.blocks[0].topLeftCorner<3, 3>();
          *sigma_position_m = std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(P).eigenvalues().maxCoeff()));
        }
      }
    }
    f.T_world_camera = T;
    return inliers;
  }

  void drop_outliers(FrameData& f) {
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.map_point[i] >= 0 && f.outlier[i]) {
        f.map_point[i] = -1;
        f.outlier[i] = 0;
      }
    }
  }

  // --- Local map (ORB-SLAM2 Tracking::TrackLocalMap) ------------------------------------------

  // Projects the points `ids` (repeats allowed) at f's pose and matches each to the best
  // unmatched keypoint near its projection (ORB-SLAM2 ORBmatcher::SearchByProjection(Frame,
  // vector<MapPoint*>, th) after Frame::isInFrustum): in front, inside the image, within the
  // point's scale-invariance distances, viewed within 60 degrees of its mean viewing direction;
  // radius th x (2.5 or 4 by viewing angle) x the predicted level's scale; the best descriptor
  // within TH_HIGH and, when the second best is on the same level, better than ratio x it.
  // Points the frame already holds are skipped. Returns the new matches.
  int search_by_projection(FrameData& f, const std::vector<int>& ids, double th, bool count_visible) {
    ++search_stamp;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.map_point[i] >= 0) points[static_cast<std::size_t>(f.map_point[i])].last_search = search_stamp;
    }
    const core::SE3 T_cw = f.T_world_camera.inverse();
    const Eigen::Vector3d center = f.T_world_camera.translation();
    int matches = 0;
    for (const int id : ids) {
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad || mp.last_search == search_stamp) continue;
      mp.last_search = search_stamp;
      double u, v, ur, z;
      if (!project(T_cw, mp.p_world, u, v, ur, z)) continue;
      const Eigen::Vector3d po = mp.p_world - center;
      const double distance = po.norm();
      if (distance < 0.8 * mp.min_distance || distance > 1.2 * mp.max_distance) continue;
      const double view_cos = po.dot(mp.normal) / distance;
      if (view_cos < 0.5) continue;
      if (count_visible) ++mp.visible;
      const int level = predict_level(mp, distance);
      const double r = (view_cos > 0.998 ? 2.5 : 4.0) * th * scales[static_cast<std::size_t>(level)];
      const std::vector<int> candidates = features_in_area(f, u, v, r, level - 1, level);
      int best = 256, second = 256, best_level = -1, second_level = -1, best_j = -1;
      for (const int j : candidates) {
        const auto sj = static_cast<std::size_t>(j);
        if (f.map_point[sj] >= 0) continue;
        if (f.u_right[sj] >= 0 && std::abs(ur - f.u_right[sj]) > r) continue;
        const int d = vision::descriptor_distance(mp.descriptor.ptr(), f.descriptors.ptr(j));
        if (d < best) {
          second = best;
          second_level = best_level;
          best = d;
          best_level = f.keypoints[sj].octave;
          best_j = j;
        } else if (d < second) {
          second = d;
          second_level = f.keypoints[sj].octave;
        }
      }
      if (best_j < 0 || best > options.max_descriptor_distance) continue;
      if (best_level == second_level && best > options.local_match_ratio * second) continue;
      f.map_point[static_cast<std::size_t>(best_j)] = id;
      ++matches;
    }
    return matches;
  }

  int track_local_map(FrameData& f, double* sigma_position_m, int* given) {
    // Keyframes sharing points with the frame, most shared first.
    std::unordered_map<int, int> shared;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const int id = f.map_point[i];
      if (id < 0) continue;
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) {
        f.map_point[i] = -1;
        continue;
      }
      for (const auto& [kf, idx] : mp.observations) ++shared[kf];
    }
    std::vector<std::pair<int, int>> ranked;
    for (const auto& [kf, n] : shared) ranked.emplace_back(n, kf);
    std::sort(ranked.begin(), ranked.end(), std::greater<>());
    if (!ranked.empty()) reference_keyframe = ranked.front().second;
    if (ranked.size() > static_cast<std::size_t>(options.local_map_keyframes)) ranked.resize(static_cast<std::size_t>(options.local_map_keyframes));
    // Project the local map's points that the frame has not matched yet.
    std::vector<int> ids;
    for (const auto& [n, kf] : ranked) {
      for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
        if (id >= 0) ids.push_back(id);
      }
    }
    const double th = kind == io::SequenceKind::kRgbd ? 3.0 * options.local_search_radius_px : options.local_search_radius_px;
    search_by_projection(f, ids, th, true);
    int matched = 0;
    for (std::size_t i = 0; i < f.size(); ++i) matched += f.map_point[i] >= 0 ? 1 : 0;
    *given = matched;
    const int inliers = optimize_pose(f, sigma_position_m);
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.map_point[i] >= 0 && !f.outlier[i]) ++points[static_cast<std::size_t>(f.map_point[i])].found;
    }
    drop_outliers(f);
    return inliers;
  }

  // --- Keyframes and local mapping ------------------------------------------------------------

  bool need_keyframe(const FrameData& f, int inliers) const {
    if (reference_keyframe < 0) return true;
    const KeyFrame& ref = keyframes[static_cast<std::size_t>(reference_keyframe)];
    // The reference keyframe's points seen by enough keyframes (a stereo observation counts 2).
    const int min_obs = keyframes.size() <= 2 ? 2 : 3;
    int reference_points = 0;
    for (const int id : ref.frame.map_point) {
      if (id >= 0 && !points[static_cast<std::size_t>(id)].bad && observation_weight(points[static_cast<std::size_t>(id)]) >= min_obs) ++reference_points;
    }
    int tracked_close = 0, untracked_close = 0;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.depth[i] > 0 && f.depth[i] < close_depth_m) {
        if (f.map_point[i] >= 0) ++tracked_close;
        else ++untracked_close;
      }
    }
    const bool need_close = tracked_close < options.keyframe_close_tracked && untracked_close > options.keyframe_close_untracked;
    const bool c1 = static_cast<int>(f.index) - last_keyframe_frame >= options.keyframe_max_frames;
    const double ratio = kind == io::SequenceKind::kMonocular ? 0.9 : options.keyframe_tracked_ratio;  // ORB-SLAM2 thRefRatio
    const bool c2 = (inliers < ratio * reference_points || need_close) && inliers > options.lost_below_inliers;
    return c2 || (c1 && inliers > options.lost_below_inliers);
  }

  void insert_keyframe(FrameData& f, bool starts_segment = false) {
    KeyFrame kf;
    kf.id = static_cast<int>(keyframes.size());
    kf.frame = f;
    kf.segment = segment;
    kf.starts_segment = starts_segment || kf.id == 0;
    // New points from stereo/depth, nearest first: every close one, at least min_new_points.
    std::vector<std::pair<double, std::size_t>> by_depth;
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (f.depth[i] > 0) by_depth.emplace_back(f.depth[i], i);
    }
    std::sort(by_depth.begin(), by_depth.end());
    keyframes.push_back(std::move(kf));
    KeyFrame& k = keyframes.back();
    int created_or_seen = 0;
    for (const auto& [z, i] : by_depth) {
      if (k.frame.map_point[i] < 0) {
        MapPoint mp;
        mp.p_world = unproject(k.frame, i);
        mp.descriptor = k.frame.descriptors.row(static_cast<int>(i)).clone();
        mp.first_keyframe = mp.reference_keyframe = k.id;
        mp.observations[k.id] = static_cast<int>(i);
        points.push_back(std::move(mp));
        const int id = static_cast<int>(points.size()) - 1;
        k.frame.map_point[i] = id;
        f.map_point[i] = id;
        update_normal_and_depth(points.back());
        recent_points.push_back(id);
        ++summary->map_points;
      }
      ++created_or_seen;
      // The first keyframe of a map takes every stereo point (ORB-SLAM2 StereoInitialization).
      if (!k.starts_segment && z > close_depth_m && created_or_seen > options.min_new_points) break;
    }
    // Observations of the points the frame tracked.
    for (std::size_t i = 0; i < k.frame.size(); ++i) {
      const int id = k.frame.map_point[i];
      if (id < 0) continue;
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) {
        k.frame.map_point[i] = -1;
        continue;
      }
      if (!mp.observations.count(k.id)) {
        mp.observations[k.id] = static_cast<int>(i);
        update_normal_and_depth(mp);
        update_descriptor(mp);
      }
    }
    reference_keyframe = k.id;
    last_keyframe_frame = static_cast<int>(f.index);
    ++summary->keyframes;
  }

  // ORB-SLAM2 LocalMapping::CreateNewMapPoints: the newest keyframe's unmatched keypoints are
  // matched to those of its 10 most covisible keyframes (descriptor within TH_LOW, the best one
  // within 3.84 sigma^2 of the epipolar line; ORB-SLAM2 restricts the search to bag-of-words
  // nodes, here every unmatched keypoint is compared) and triangulated (linear, Hartley &
  // Zisserman 12.2) when the rays' parallax beats the stereo parallax, else taken from the view
  // with the better stereo depth; kept when in front of both cameras, within the chi^2
  // thresholds in both, and at consistent scales (distance ratio within 1.5 x scale factor of
  // the octave ratio). Returns the points created.
  int triangulate_new_points(int current, int count) {
    std::vector<std::pair<int, int>> neighbours = covisible(current, 1);
    if (neighbours.size() > static_cast<std::size_t>(count)) neighbours.resize(static_cast<std::size_t>(count));
    const double stereo_baseline = bf / camera.fx;
    const double ratio_factor = 1.5 * options.orb.scale_factor;
    const Eigen::Matrix3d K = (Eigen::Matrix3d() << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1).finished();
    const Eigen::Matrix3d K_inv = K.inverse();
    int created = 0;
    for (const auto& [shared, k2_id] : neighbours) {
      const KeyFrame& k2 = keyframes[static_cast<std::size_t>(k2_id)];
      const FrameData& f1 = keyframes[static_cast<std::size_t>(current)].frame;
      const FrameData& f2 = k2.frame;
      const Eigen::Vector3d O1 = f1.T_world_camera.translation(), O2 = f2.T_world_camera.translation();
      const core::SE3 T1_cw = f1.T_world_camera.inverse(), T2_cw = f2.T_world_camera.inverse();
      if (kind == io::SequenceKind::kMonocular) {
        // ORB-SLAM2: baseline / the neighbour's median scene depth at least 0.01.
        std::vector<double> depths;
        for (const int id : f2.map_point) {
          if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) depths.push_back((T2_cw * points[static_cast<std::size_t>(id)].p_world).z());
        }
        if (depths.empty()) continue;
        std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
        if ((O2 - O1).norm() / depths[depths.size() / 2] < 0.01) continue;
      } else if ((O2 - O1).norm() < stereo_baseline) {
        continue;  // ORB-SLAM2: no triangulation below the stereo baseline
      }
      // The epipole of camera 1 in image 2 (monocular matches next to it are ill-conditioned).
      const Eigen::Vector3d c1_in_2 = T2_cw * O1;
      const bool epipole_valid = c1_in_2.z() > 1e-9;
      const double ex = epipole_valid ? camera.fx * c1_in_2.x() / c1_in_2.z() + camera.cx : 0.0;
      const double ey = epipole_valid ? camera.fy * c1_in_2.y() / c1_in_2.z() + camera.cy : 0.0;
      // Fundamental matrix of x1^T F12 x2 = 0: F12 = K^-T [t12]x R12 K^-1, T12 = T1_cw T2_wc.
      const core::SE3 T12 = T1_cw * f2.T_world_camera;
      const Eigen::Vector3d t = T12.translation();
      Eigen::Matrix3d tx;
      tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
      const Eigen::Matrix3d F12 = K_inv.transpose() * tx * T12.rotation_matrix() * K_inv;
      std::vector<int> taken_by(f2.size(), -1);
      std::vector<int> taken_distance(f2.size(), 256);
      for (std::size_t i1 = 0; i1 < f1.size(); ++i1) {
        if (f1.map_point[i1] >= 0) continue;
        const Eigen::Vector3d x1(f1.undistorted[i1].x(), f1.undistorted[i1].y(), 1.0);
        const Eigen::Vector3d line = F12.transpose() * x1;  // epipolar line in image 2: x2^T (F12^T x1) = 0
        const double line_norm2 = line.x() * line.x() + line.y() * line.y();
        if (!(line_norm2 > 0.0)) continue;
        int best = 256, second = 256, best_i2 = -1;
        for (std::size_t i2 = 0; i2 < f2.size(); ++i2) {
          if (f2.map_point[i2] >= 0) continue;
          const int level2 = f2.keypoints[i2].octave;
          if (std::abs(level2 - f1.keypoints[i1].octave) > 1) continue;
          if (epipole_valid && f1.depth[i1] <= 0 && f2.depth[i2] <= 0) {
            const double dx = ex - f2.undistorted[i2].x(), dy = ey - f2.undistorted[i2].y();
            if (dx * dx + dy * dy < 100.0 * scales[static_cast<std::size_t>(level2)]) continue;
          }
          const double d = line.x() * f2.undistorted[i2].x() + line.y() * f2.undistorted[i2].y() + line.z();
          if (d * d / line_norm2 >= 3.84 * scales[static_cast<std::size_t>(level2)] * scales[static_cast<std::size_t>(level2)]) continue;
          const int dist = vision::descriptor_distance(f1.descriptors.ptr(static_cast<int>(i1)), f2.descriptors.ptr(static_cast<int>(i2)));
          if (dist < best) {
            second = best;
            best = dist;
            best_i2 = static_cast<int>(i2);
          } else if (dist < second) {
            second = dist;
          }
        }
        // TH_LOW, and a ratio test along the epipolar band: without ORB-SLAM2's bag-of-words
        // nodes the band holds many look-alikes (repeated texture, forward motion).
        if (best_i2 < 0 || best > options.max_descriptor_distance / 2 || best > options.triangulation_match_ratio * second) continue;
        if (best >= taken_distance[static_cast<std::size_t>(best_i2)]) continue;
        taken_by[static_cast<std::size_t>(best_i2)] = static_cast<int>(i1);
        taken_distance[static_cast<std::size_t>(best_i2)] = best;
      }
      for (std::size_t i2 = 0; i2 < f2.size(); ++i2) {
        const int signed_i1 = taken_by[i2];
        if (signed_i1 < 0) continue;
        const auto i1 = static_cast<std::size_t>(signed_i1);
        const Eigen::Vector3d xn1 = K_inv * Eigen::Vector3d(f1.undistorted[i1].x(), f1.undistorted[i1].y(), 1.0);
        const Eigen::Vector3d xn2 = K_inv * Eigen::Vector3d(f2.undistorted[i2].x(), f2.undistorted[i2].y(), 1.0);
        const Eigen::Vector3d ray1 = f1.T_world_camera.rotation_matrix() * xn1, ray2 = f2.T_world_camera.rotation_matrix() * xn2;
        const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
        const bool stereo1 = f1.depth[i1] > 0, stereo2 = f2.depth[i2] > 0;
        const double cos_stereo1 = stereo1 ? std::cos(2.0 * std::atan2(stereo_baseline / 2.0, f1.depth[i1])) : 2.0;
        const double cos_stereo2 = stereo2 ? std::cos(2.0 * std::atan2(stereo_baseline / 2.0, f2.depth[i2])) : 2.0;
        const double cos_stereo = std::min(cos_stereo1, cos_stereo2);
        Eigen::Vector3d X;
        if (cos_rays < cos_stereo && cos_rays > 0.0 && (stereo1 || stereo2 || cos_rays < 0.9998)) {
          // Linear triangulation: A X = 0 from x cross (P X) = 0 in both views.
          const Eigen::Matrix<double, 3, 4> P1 = T1_cw.matrix3x4(), P2 = T2_cw.matrix3x4();
          Eigen::Matrix4d A;
          A.row(0) = xn1.x() * P1.row(2) - P1.row(0);
          A.row(1) = xn1.y() * P1.row(2) - P1.row(1);
          A.row(2) = xn2.x() * P2.row(2) - P2.row(0);
          A.row(3) = xn2.y() * P2.row(2) - P2.row(1);
          const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
          if (std::abs(h(3)) < 1e-12) continue;
          X = h.head<3>() / h(3);
        } else if (stereo1 && cos_stereo1 < cos_stereo2) {
          X = unproject(f1, i1);
        } else if (stereo2 && cos_stereo2 < cos_stereo1) {
          X = unproject(f2, i2);
        } else {
          continue;  // too little parallax either way
        }
        if (!((T1_cw * X).z() > 0.0) || !((T2_cw * X).z() > 0.0)) continue;
        if (chi2(f1, i1, T1_cw, X) > (stereo1 ? options.chi2_stereo : options.chi2_mono)) continue;
        if (chi2(f2, i2, T2_cw, X) > (stereo2 ? options.chi2_stereo : options.chi2_mono)) continue;
        const double dist1 = (X - O1).norm(), dist2 = (X - O2).norm();
        if (dist1 <= 0.0 || dist2 <= 0.0) continue;
        const double ratio_dist = dist2 / dist1;
        const double ratio_octave = scales[static_cast<std::size_t>(f1.keypoints[i1].octave)] / scales[static_cast<std::size_t>(f2.keypoints[i2].octave)];
        if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) continue;
        MapPoint mp;
        mp.p_world = X;
        mp.descriptor = f1.descriptors.row(static_cast<int>(i1)).clone();
        mp.first_keyframe = mp.reference_keyframe = current;
        mp.observations[current] = static_cast<int>(i1);
        mp.observations[k2_id] = static_cast<int>(i2);
        points.push_back(std::move(mp));
        const int id = static_cast<int>(points.size()) - 1;
        keyframes[static_cast<std::size_t>(current)].frame.map_point[i1] = id;
        keyframes[static_cast<std::size_t>(k2_id)].frame.map_point[i2] = id;
        update_normal_and_depth(points.back());
        update_descriptor(points.back());
        recent_points.push_back(id);
        ++summary->map_points;
        ++created;
      }
    }
    return created;
  }

  // ORB-SLAM2 LocalMapping::MapPointCulling (stereo: 3 observations, a stereo one counting 2).
  void cull_points() {
    const int current = static_cast<int>(keyframes.size()) - 1;
    std::vector<int> keep;
    for (const int id : recent_points) {
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) continue;
      if (static_cast<double>(mp.found) / mp.visible < 0.25) {
        set_bad(id);
      } else if (current - mp.first_keyframe >= 2 && observation_weight(mp) <= (kind == io::SequenceKind::kMonocular ? 2 : 3)) {
        set_bad(id);
      } else if (current - mp.first_keyframe < 3) {
        keep.push_back(id);
      }
    }
    recent_points = std::move(keep);
  }

  // Keyframes sharing at least `min_shared` good points with keyframe `kf`, most first.
  std::vector<std::pair<int, int>> covisible(int kf, int min_shared) const {
    std::unordered_map<int, int> shared;
    for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
      if (id < 0 || points[static_cast<std::size_t>(id)].bad) continue;
      for (const auto& [other, idx] : points[static_cast<std::size_t>(id)].observations) {
        if (other != kf) ++shared[other];
      }
    }
    std::vector<std::pair<int, int>> ranked;
    for (const auto& [other, n] : shared) {
      if (n >= min_shared) ranked.emplace_back(n, other);
    }
    std::sort(ranked.begin(), ranked.end(), std::greater<>());
    return ranked;
  }

  // ORB-SLAM2 Optimizer::LocalBundleAdjustment: the newest keyframe and its covisible ones.
  void local_bundle_adjustment() {
    const auto start = Clock::now();
    const int current = static_cast<int>(keyframes.size()) - 1;
    std::vector<std::pair<int, int>> ranked = covisible(current, options.min_covisible_points);
    if (ranked.size() > static_cast<std::size_t>(options.max_local_ba_keyframes)) ranked.resize(static_cast<std::size_t>(options.max_local_ba_keyframes));
    std::set<int> local{current};
    for (const auto& [n, kf] : ranked) local.insert(kf);
    bundle_adjustment(local, 5, 10);
    ++summary->local_bas;
    summary->local_ba_s += seconds_since(start);
  }

  // Bundle adjustment on the engine of the keyframes `local` (free, but keyframe 0) and every
  // point they see, the other keyframes that see those points fixed; `first` LM iterations with
  // Huber, chi^2 outliers removed, `second` more without the kernel, outlier observations erased.
  void bundle_adjustment(const std::set<int>& local, int first, int second_iterations) {
    std::set<int> local_points;
    for (const int kf : local) {
      for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
        if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) local_points.insert(id);
      }
    }
    std::set<int> fixed;
    for (const int id : local_points) {
      for (const auto& [kf, idx] : points[static_cast<std::size_t>(id)].observations) {
        if (!local.count(kf)) fixed.insert(kf);
      }
    }
    if (local.size() < 2 && fixed.empty()) return;
    std::map<int, std::array<double, 7>> pose_values;
    std::map<int, int> pose_var;
    backend::LeastSquaresProblem problem;
    auto add_pose = [&](int kf, bool constant) {
      auto& v = pose_values[kf];
      backend::se3_to_values(keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera, v.data());
      pose_var[kf] = problem.add_variable(v.data(), backend::se3_manifold());
      if (constant || kf == 0) problem.set_constant(pose_var[kf]);
    };
    for (const int kf : local) add_pose(kf, false);
    for (const int kf : fixed) add_pose(kf, true);
    std::unordered_map<int, Eigen::Vector3d> point_values;
    point_values.reserve(local_points.size());
    struct Edge {
      int point, kf, idx;
    };
    std::vector<Edge> edges;
    std::unordered_map<int, int> point_var;
    for (const int id : local_points) {
      point_values[id] = points[static_cast<std::size_t>(id)].p_world;
    }
    for (const int id : local_points) {
      point_var[id] = problem.add_variable(point_values[id].data(), backend::euclidean_manifold(3), backend::VariableGroup::kEliminate);
      for (const auto& [kf, idx] : points[static_cast<std::size_t>(id)].observations) edges.push_back({id, kf, idx});
    }
    auto build = [&](backend::LeastSquaresProblem& p, const std::vector<char>& is_outlier, bool robust) {
      for (std::size_t e = 0; e < edges.size(); ++e) {
        if (is_outlier[e]) continue;
        const Edge& edge = edges[e];
        const FrameData& f = keyframes[static_cast<std::size_t>(edge.kf)].frame;
        const auto i = static_cast<std::size_t>(edge.idx);
        const bool stereo = f.u_right[i] >= 0;
        backend::FactorLoss loss;
        if (robust) loss = {backend::RobustKernel::kHuber, std::sqrt(stereo ? options.chi2_stereo : options.chi2_mono)};
        p.add_factor(std::make_unique<ScaledFactor>(observation_factor(f, i), 1.0 / scales[static_cast<std::size_t>(f.keypoints[i].octave)]),
                     {pose_var[edge.kf], point_var[edge.point]}, loss);
      }
    };
    std::vector<char> is_outlier(edges.size(), 0);
    build(problem, is_outlier, true);
    backend::LeastSquaresOptions lso;
    lso.linear_solver = backend::LinearSolverType::kSparseSchur;
    lso.max_iterations = first;
    lso.threads = 1;
    backend::solve(problem, lso);
    auto edge_chi2 = [&](const Edge& edge, const core::SE3& T_wc, const Eigen::Vector3d& p_world) {
      return chi2(keyframes[static_cast<std::size_t>(edge.kf)].frame, static_cast<std::size_t>(edge.idx), T_wc.inverse(), p_world);
    };
    auto classify = [&]() {
      for (std::size_t e = 0; e < edges.size(); ++e) {
        const Edge& edge = edges[e];
        const FrameData& f = keyframes[static_cast<std::size_t>(edge.kf)].frame;
        const double threshold = f.u_right[static_cast<std::size_t>(edge.idx)] >= 0 ? options.chi2_stereo : options.chi2_mono;
        is_outlier[e] = edge_chi2(edge, backend::se3_from_values(pose_values[edge.kf].data()), point_values[edge.point]) > threshold ? 1 : 0;
      }
    };
    classify();
    {
      // The second pass without the outliers and without the robust kernel, from where the first
      // ended (ORB-SLAM2 sets the outliers' level to 1 and removes the kernels).
      backend::LeastSquaresProblem second;
      std::map<int, int> second_pose;
      for (auto& [kf, v] : pose_values) {
        second_pose[kf] = second.add_variable(v.data(), backend::se3_manifold());
        if (fixed.count(kf) || kf == 0) second.set_constant(second_pose[kf]);
      }
      std::swap(pose_var, second_pose);
      for (const int id : local_points) {
        point_var[id] = second.add_variable(point_values[id].data(), backend::euclidean_manifold(3), backend::VariableGroup::kEliminate);
      }
      build(second, is_outlier, false);
      lso.max_iterations = std::max(1, second_iterations);
      if (second_iterations > 0) backend::solve(second, lso);
    }
    classify();
    for (std::size_t e = 0; e < edges.size(); ++e) {
      if (is_outlier[e]) erase_observation(edges[e].point, edges[e].kf);
    }
    for (const int kf : local) {
      if (kf != 0) keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera = backend::se3_from_values(pose_values[kf].data());
    }
    for (const int id : local_points) {
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) continue;
      mp.p_world = point_values[id];
      update_normal_and_depth(mp);
    }
  }

  // --- Place recognition: loop closure (ORB-SLAM2 LoopClosing) -------------------------------

  // Replaces point `old_id` by `new_id` everywhere (ORB-SLAM2 MapPoint::Replace): its
  // observations move to the new point where the keyframe does not see that one already.
  void replace_point(int old_id, int new_id) {
    if (old_id == new_id) return;
    MapPoint& old_point = points[static_cast<std::size_t>(old_id)];
    MapPoint& new_point = points[static_cast<std::size_t>(new_id)];
    for (const auto& [kf, idx] : old_point.observations) {
      FrameData& f = keyframes[static_cast<std::size_t>(kf)].frame;
      if (!new_point.observations.count(kf)) {
        new_point.observations[kf] = idx;
        f.map_point[static_cast<std::size_t>(idx)] = new_id;
      } else {
        f.map_point[static_cast<std::size_t>(idx)] = -1;
      }
    }
    new_point.visible += old_point.visible;
    new_point.found += old_point.found;
    old_point.observations.clear();
    old_point.bad = true;
    for (int& id : last.map_point) {
      if (id == old_id) id = new_id;
    }
    ++summary->map_points_fused;
  }

  // Geometric verification of a loop candidate (stereo / RGB-D: SE(3), ORB-SLAM2 ComputeSim3
  // with the scale fixed): the keyframe's keypoints matched to the candidate's points, a PnP
  // RANSAC pose, the motion-only BA, then the points of the candidate and its covisible
  // keyframes projected at that pose and the BA again. `probe` gets the keyframe at the pose
  // the candidate's part of the map gives it, with its matches to that part.
  bool verify_loop(int current, int candidate, LoopRecord& record, FrameData& probe) {
    probe = keyframes[static_cast<std::size_t>(current)].frame;
    std::fill(probe.map_point.begin(), probe.map_point.end(), -1);
    std::fill(probe.outlier.begin(), probe.outlier.end(), 0);
    const int matches = match_brute_force(probe, keyframes[static_cast<std::size_t>(candidate)].frame.map_point);
    if (matches < options.loop_min_pnp_inliers) {
      record.reason = std::to_string(matches) + " descriptor matches to the candidate's points (< " + std::to_string(options.loop_min_pnp_inliers) + ")";
      return false;
    }
    record.pnp_inliers = pnp_ransac(probe);
    if (record.pnp_inliers < options.loop_min_pnp_inliers) {
      record.reason = "PnP RANSAC: " + std::to_string(record.pnp_inliers) + " inliers of " + std::to_string(matches) + " (< " +
                      std::to_string(options.loop_min_pnp_inliers) + ")";
      return false;
    }
    optimize_pose(probe);
    drop_outliers(probe);
    std::vector<int> ids;
    std::vector<std::pair<int, int>> group = covisible(candidate, options.min_covisible_points);
    if (group.size() > 10) group.resize(10);
    group.emplace_back(0, candidate);
    for (const auto& [n, kf] : group) {
      for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
        if (id >= 0) ids.push_back(id);
      }
    }
    search_by_projection(probe, ids, 3.0, false);
    record.matches = optimize_pose(probe);
    drop_outliers(probe);
    if (record.matches < options.loop_min_matches) {
      record.reason = "after projecting the candidate's neighbourhood: " + std::to_string(record.matches) +
                      " inlier matches (< " + std::to_string(options.loop_min_matches) + ")";
      return false;
    }
    return true;
  }

  // Loop correction (ORB-SLAM2 CorrectLoop, stereo: SE(3)): the pose graph of every keyframe
  // (consecutive keyframes, covisibility edges of >= 100 shared points, the loop edge; unit
  // information as ORB-SLAM2's essential graph; keyframe 0 fixed) optimised on the back end;
  // points follow their reference keyframe; the keyframe's loop matches fuse its points into the
  // old ones; then a global bundle adjustment.
  void correct_loop(int current, int candidate, const FrameData& probe, LoopRecord& record) {
    const std::size_t n = keyframes.size();
    std::vector<core::SE3> old_poses(n);
    for (std::size_t k = 0; k < n; ++k) old_poses[k] = keyframes[k].frame.T_world_camera;
    const core::SE3 T_loop = probe.T_world_camera;
    const core::SE3 change = old_poses[static_cast<std::size_t>(current)].inverse() * T_loop;
    record.correction_m = change.translation().norm();
    record.correction_deg = Eigen::AngleAxisd(change.rotation_matrix()).angle() * 180.0 / 3.14159265358979323846;
    io::PoseGraph3D graph;
    for (std::size_t k = 0; k < n; ++k) graph.vertices.push_back({static_cast<std::int64_t>(k), old_poses[k]});
    auto add_edge = [&](int a, int b, const core::SE3& T_a_b, double weight = 1.0) {
      io::GraphEdge<core::SE3> e;
      e.from = a;
      e.to = b;
      e.T_from_to = T_a_b;
      e.information *= weight;
      graph.edges.push_back(e);
    };
    // Consecutive keyframes; into the first keyframe of a segment the link is only the motion
    // model's guess across the lost stretch: a weight of 1e-6 keeps the graph connected without
    // holding the segments where the guess put them.
    for (std::size_t k = 1; k < n; ++k) {
      add_edge(static_cast<int>(k) - 1, static_cast<int>(k), old_poses[k - 1].inverse() * old_poses[k], keyframes[k].starts_segment ? 1e-6 : 1.0);
    }
    for (std::size_t k = 0; k < n; ++k) {
      for (const auto& [shared, other] : covisible(static_cast<int>(k), 100)) {
        if (other < static_cast<int>(k) - 1) add_edge(other, static_cast<int>(k), old_poses[static_cast<std::size_t>(other)].inverse() * old_poses[k]);
      }
    }
    add_edge(candidate, current, old_poses[static_cast<std::size_t>(candidate)].inverse() * T_loop);
    graph.fixed.push_back(0);
    backend::Problem3D problem = backend::make_problem(graph, "vslam essential graph");
    backend::OptimizerOptions solver;
    solver.max_iterations = 20;
    solver.function_tolerance = 1e-9;
    solver.threads = 1;
    backend::optimize(problem, solver);
    for (std::size_t k = 0; k < n; ++k) keyframes[k].frame.T_world_camera = problem.T_world_pose[k];
    for (MapPoint& mp : points) {
      if (mp.bad) continue;
      const auto r = static_cast<std::size_t>(mp.reference_keyframe);
      mp.p_world = keyframes[r].frame.T_world_camera * (old_poses[r].inverse() * mp.p_world);
    }
    if (reference_keyframe >= 0) {
      const auto r = static_cast<std::size_t>(reference_keyframe);
      last.T_world_camera = keyframes[r].frame.T_world_camera * (old_poses[r].inverse() * last.T_world_camera);
    }
    // Fuse: the keyframe's keypoints matched to the old part of the map take its points.
    KeyFrame& kf = keyframes[static_cast<std::size_t>(current)];
    for (std::size_t i = 0; i < probe.size(); ++i) {
      const int loop_id = probe.map_point[i];
      if (loop_id < 0 || points[static_cast<std::size_t>(loop_id)].bad) continue;
      const int own = kf.frame.map_point[i];
      if (own == loop_id) continue;
      if (own >= 0 && !points[static_cast<std::size_t>(own)].bad) {
        replace_point(own, loop_id);
      } else if (!points[static_cast<std::size_t>(loop_id)].observations.count(current)) {
        points[static_cast<std::size_t>(loop_id)].observations[current] = static_cast<int>(i);
        kf.frame.map_point[i] = loop_id;
      }
      update_descriptor(points[static_cast<std::size_t>(loop_id)]);
      update_normal_and_depth(points[static_cast<std::size_t>(loop_id)]);
    }
    if (options.global_ba_after_loop) {
      const auto start = Clock::now();
      std::set<int> all;
      for (std::size_t k = 0; k < n; ++k) all.insert(static_cast<int>(k));
      bundle_adjustment(all, 10, 10);
      ++summary->global_bas;
      summary->global_ba_s += seconds_since(start);
    }
  }

  // ORB-SLAM2 LoopClosing::DetectLoop: candidates from the database scoring at least as well as
  // the keyframe's worst covisible neighbour and sharing at least 80 % of the best candidate's
  // words, kept only when their covisibility group was also a candidate group for the previous
  // loop_consistency - 1 keyframes; then verified, best score first.
  void detect_and_close_loop(FrameResult& result) {
    if (!options.vocabulary) return;
    if (kind == io::SequenceKind::kMonocular) {
      // Monocular loops need Sim(3) (scale drifts); not implemented: keyframes only go into the
      // database, for relocalisation.
      KeyFrame& kf = keyframes.back();
      kf.bow = options.vocabulary->transform(kf.frame.descriptors);
      database.add(static_cast<std::uint32_t>(kf.id), kf.bow);
      return;
    }
    const auto start = Clock::now();
    const int current = static_cast<int>(keyframes.size()) - 1;
    KeyFrame& kf = keyframes[static_cast<std::size_t>(current)];
    kf.bow = options.vocabulary->transform(kf.frame.descriptors);
    // Loops within a segment wait for enough keyframes since the start and the last loop; a
    // merge with another segment may come at any keyframe.
    const bool too_early = current < 2 * options.loop_min_keyframes_apart || current < last_loop_keyframe + options.loop_min_keyframes_apart;
    bool other_segments = false;
    for (const KeyFrame& other : keyframes) other_segments = other_segments || segment_of(other.id) != segment_of(current);
    if (!options.loop_closure || (too_early && !other_segments)) {
      database.add(static_cast<std::uint32_t>(current), kf.bow);
      summary->loop_s += seconds_since(start);
      return;
    }
    ++summary->loop_queries;
    const std::vector<std::pair<int, int>> neighbours = covisible(current, options.min_covisible_points);
    double min_score = 1.0;
    std::vector<std::uint32_t> exclude{static_cast<std::uint32_t>(current)};
    for (const auto& [shared, k] : neighbours) {
      min_score = std::min(min_score, vision::Vocabulary::score(kf.bow, keyframes[static_cast<std::size_t>(k)].bow));
      exclude.push_back(static_cast<std::uint32_t>(k));
    }
    for (int k = std::max(0, current - options.loop_min_keyframes_apart); k < current; ++k) exclude.push_back(static_cast<std::uint32_t>(k));
    const std::vector<vision::BowDatabase::Result> results = database.query(kf.bow, 20, exclude);
    database.add(static_cast<std::uint32_t>(current), kf.bow);
    int max_common = 0;
    for (const auto& r : results) max_common = std::max(max_common, r.common_words);
    std::vector<std::pair<std::set<int>, int>> groups;
    std::vector<std::tuple<double, int, int>> consistent;  // score, candidate, consistency
    for (const auto& r : results) {
      if (r.score < min_score || r.common_words < 0.8 * max_common) continue;
      const int candidate = static_cast<int>(r.id);
      if (too_early && segment_of(candidate) == segment_of(current)) continue;
      std::set<int> group{candidate};
      for (const auto& [shared, k] : covisible(candidate, options.min_covisible_points)) group.insert(k);
      int consistency = 0;
      for (const auto& [previous, count] : consistent_groups) {
        const bool shares = std::any_of(group.begin(), group.end(), [&](int k) { return previous.count(k) > 0; });
        if (shares) consistency = std::max(consistency, count + 1);
      }
      groups.emplace_back(group, consistency);
      if (consistency + 1 >= options.loop_consistency) consistent.emplace_back(r.score, candidate, consistency + 1);
    }
    consistent_groups = std::move(groups);
    std::sort(consistent.begin(), consistent.end(), std::greater<>());
    for (const auto& [score, candidate, consistency] : consistent) {
      LoopRecord record;
      record.keyframe = static_cast<std::size_t>(current);
      record.candidate = static_cast<std::size_t>(candidate);
      record.frame = kf.frame.index;
      record.candidate_frame = keyframes[static_cast<std::size_t>(candidate)].frame.index;
      record.score = score;
      record.min_covisible_score = min_score;
      record.consistency = consistency;
      record.merge = segment_of(candidate) != segment_of(current);
      FrameData probe;
      if (verify_loop(current, candidate, record, probe)) {
        record.decision = "accepted";
        record.reason = std::to_string(record.matches) + " inlier matches to the candidate's neighbourhood";
        correct_loop(current, candidate, probe, record);
        if (record.merge) {
          // The segment being tracked joins the candidate's (the older one keeps its id).
          const int a = segment_of(current), b = segment_of(candidate);
          segment_parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
          ++summary->maps_merged;
        }
        summary->loops.push_back(record);
        ++summary->loops_accepted;
        result.loop_closed = true;
        last_loop_keyframe = current;
        consistent_groups.clear();
        break;
      }
      record.decision = "rejected";
      summary->loops.push_back(record);
    }
    summary->loop_s += seconds_since(start);
  }

  // --- Monocular initialisation (ORB-SLAM2 Initializer, Mur-Artal et al. T-RO 2015 Sec. IV) ----

  FrameData init_reference;
  bool have_init_reference = false;

  // Level-0 keypoints of the reference matched to the frame within 100 px (ORB-SLAM2
  // SearchForInitialization: TH_LOW, ratio 0.9, one-to-one).
  std::vector<std::pair<int, int>> match_for_initialisation(const FrameData& a, const FrameData& b) const {
    std::vector<int> owner(b.size(), -1), owner_distance(b.size(), 256);
    for (std::size_t i = 0; i < a.size(); ++i) {
      if (a.keypoints[i].octave > 0) continue;
      int best = 256, second = 256, best_j = -1;
      for (const int j : features_in_area(b, a.undistorted[i].x(), a.undistorted[i].y(), 100.0, 0, 0)) {
        const int d = vision::descriptor_distance(a.descriptors.ptr(static_cast<int>(i)), b.descriptors.ptr(j));
        if (d < best) {
          second = best;
          best = d;
          best_j = j;
        } else if (d < second) {
          second = d;
        }
      }
      if (best_j < 0 || best > options.max_descriptor_distance / 2 || best >= 0.9 * second) continue;
      if (best >= owner_distance[static_cast<std::size_t>(best_j)]) continue;
      owner[static_cast<std::size_t>(best_j)] = static_cast<int>(i);
      owner_distance[static_cast<std::size_t>(best_j)] = best;
    }
    std::vector<std::pair<int, int>> out;
    for (std::size_t j = 0; j < b.size(); ++j) {
      if (owner[j] >= 0) out.emplace_back(owner[j], static_cast<int>(j));
    }
    return out;
  }

  // Two-view reconstruction: the homography and the essential matrix (RANSAC, OpenCV), scored
  // as ORB-SLAM2 scores them (sum of chi^2 margins below 5.991 of the symmetric transfer errors
  // for H, of the distances to the epipolar lines below 3.841 for F); H when
  // S_H / (S_H + S_F) > 0.40, else E; the pose from cv::recoverPose / the homography's
  // decompositions (the one with most points in front); points triangulated, kept in front of
  // both cameras within 2 px; success with >= 50 points seen at >= 1 degree of parallax.
  // `note` says which model and why it failed.
  bool reconstruct_two_views(const FrameData& a, const FrameData& b, const std::vector<std::pair<int, int>>& matches, core::SE3& T_b_a,
                             std::vector<std::pair<int, Eigen::Vector3d>>& points_a, std::string& note) const {
    std::vector<cv::Point2d> pa, pb;
    for (const auto& [i, j] : matches) {
      pa.emplace_back(a.undistorted[static_cast<std::size_t>(i)].x(), a.undistorted[static_cast<std::size_t>(i)].y());
      pb.emplace_back(b.undistorted[static_cast<std::size_t>(j)].x(), b.undistorted[static_cast<std::size_t>(j)].y());
    }
    const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
    cv::Mat H, E, mask_h, mask_e;
    try {
      H = cv::findHomography(pa, pb, cv::RANSAC, 2.0, mask_h, 200, 0.99);
      E = cv::findEssentialMat(pa, pb, K, cv::RANSAC, 0.999, 1.0, mask_e);
    } catch (const cv::Exception& e) {
      note = std::string("two-view models failed: ") + e.what();
      return false;
    }
    if (H.empty() || E.empty() || E.rows != 3) {
      note = "no homography or essential matrix";
      return false;
    }
    const Eigen::Matrix3d K_e = (Eigen::Matrix3d() << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1).finished();
    Eigen::Matrix3d He, Ee;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        He(r, c) = H.at<double>(r, c);
        Ee(r, c) = E.at<double>(r, c);
      }
    }
    const Eigen::Matrix3d H_inv = He.inverse();
    const Eigen::Matrix3d F = K_e.inverse().transpose() * Ee * K_e.inverse();
    double score_h = 0.0, score_f = 0.0;
    for (std::size_t k = 0; k < pa.size(); ++k) {
      const Eigen::Vector3d x1(pa[k].x, pa[k].y, 1.0), x2(pb[k].x, pb[k].y, 1.0);
      const Eigen::Vector3d h21 = He * x1, h12 = H_inv * x2;
      const double e2 = (h21.head<2>() / h21.z() - x2.head<2>()).squaredNorm(), e1 = (h12.head<2>() / h12.z() - x1.head<2>()).squaredNorm();
      if (e2 < 5.991) score_h += 5.991 - e2;
      if (e1 < 5.991) score_h += 5.991 - e1;
      const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
      const double d2 = std::pow(l2.dot(x2), 2) / (l2.x() * l2.x() + l2.y() * l2.y());
      const double d1 = std::pow(l1.dot(x1), 2) / (l1.x() * l1.x() + l1.y() * l1.y());
      if (d2 < 3.841) score_f += 5.991 - d2;
      if (d1 < 3.841) score_f += 5.991 - d1;
    }
    const bool use_h = score_h / (score_h + score_f) > 0.40;
    std::vector<std::pair<cv::Matx33d, cv::Vec3d>> poses;
    if (use_h) {
      std::vector<cv::Mat> Rs, ts, normals;
      cv::decomposeHomographyMat(H, K, Rs, ts, normals);
      for (std::size_t k = 0; k < Rs.size(); ++k) poses.emplace_back(cv::Matx33d(Rs[k]), cv::Vec3d(ts[k]));
    } else {
      cv::Mat R, t;
      cv::recoverPose(E, pa, pb, K, R, t, mask_e);
      poses.emplace_back(cv::Matx33d(R), cv::Vec3d(t));
    }
    // Triangulate with every pose; keep the one with most good points.
    std::size_t best_good = 0, second_good = 0;
    std::vector<std::pair<int, Eigen::Vector3d>> best_points;
    Eigen::Matrix3d best_R = Eigen::Matrix3d::Identity();
    Eigen::Vector3d best_t = Eigen::Vector3d::Zero();
    double best_parallax_deg = 0.0;
    for (const auto& [Rc, tc] : poses) {
      Eigen::Matrix3d R;
      Eigen::Vector3d t(tc[0], tc[1], tc[2]);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) R(r, c) = Rc(r, c);
      }
      if (t.norm() < 1e-12) continue;
      t.normalize();
      const Eigen::Vector3d O2 = -R.transpose() * t;
      std::vector<std::pair<int, Eigen::Vector3d>> good;
      std::vector<double> parallax;
      for (std::size_t k = 0; k < pa.size(); ++k) {
        const Eigen::Vector3d xn1 = K_e.inverse() * Eigen::Vector3d(pa[k].x, pa[k].y, 1.0);
        const Eigen::Vector3d xn2 = K_e.inverse() * Eigen::Vector3d(pb[k].x, pb[k].y, 1.0);
        Eigen::Matrix4d A;
        Eigen::Matrix<double, 3, 4> P2;
        P2 << R, t;
        A.row(0) << -1.0, 0.0, xn1.x(), 0.0;
        A.row(1) << 0.0, -1.0, xn1.y(), 0.0;
        A.row(2) = xn2.x() * P2.row(2) - P2.row(0);
        A.row(3) = xn2.y() * P2.row(2) - P2.row(1);
        const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
        if (std::abs(h(3)) < 1e-12) continue;
        const Eigen::Vector3d X = h.head<3>() / h(3);
        const Eigen::Vector3d X2 = R * X + t;
        if (!(X.z() > 0.0) || !(X2.z() > 0.0) || !X.allFinite()) continue;
        const Eigen::Vector2d u1(camera.fx * X.x() / X.z() + camera.cx, camera.fy * X.y() / X.z() + camera.cy);
        const Eigen::Vector2d u2(camera.fx * X2.x() / X2.z() + camera.cx, camera.fy * X2.y() / X2.z() + camera.cy);
        if ((u1 - Eigen::Vector2d(pa[k].x, pa[k].y)).squaredNorm() > 4.0 || (u2 - Eigen::Vector2d(pb[k].x, pb[k].y)).squaredNorm() > 4.0) continue;
        const double cos_parallax = X.normalized().dot((X - O2).normalized());
        parallax.push_back(std::acos(std::clamp(cos_parallax, -1.0, 1.0)) * 180.0 / 3.14159265358979323846);
        good.emplace_back(matches[k].first, X);
      }
      if (good.size() > best_good) {
        second_good = best_good;
        best_good = good.size();
        best_points = good;
        best_R = R;
        best_t = t;
        std::sort(parallax.begin(), parallax.end(), std::greater<>());
        // ORB-SLAM2 (Initializer::CheckRT): the parallax of the 50th largest-parallax point.
        best_parallax_deg = parallax.empty() ? 0.0 : parallax[std::min<std::size_t>(50, parallax.size() - 1)];
      } else if (good.size() > second_good) {
        second_good = good.size();
      }
    }
    const std::string model = use_h ? "homography" : "essential matrix";
    if (best_good < 50) {
      note = model + ": " + std::to_string(best_good) + " points triangulated (< 50)";
      return false;
    }
    if (use_h && static_cast<double>(second_good) > 0.75 * static_cast<double>(best_good)) {
      note = model + ": two decompositions explain the matches alike (" + std::to_string(best_good) + " vs " + std::to_string(second_good) + ")";
      return false;
    }
    if (best_parallax_deg < 1.0) {
      note = model + ": parallax " + std::to_string(best_parallax_deg) + " deg (< 1)";
      return false;
    }
    T_b_a = core::SE3(core::SO3::from_matrix(best_R), best_t);
    points_a = std::move(best_points);
    note = model + " (S_H / (S_H + S_F) = " + std::to_string(score_h / (score_h + score_f)) + "), " + std::to_string(best_good) +
           " points, parallax " + std::to_string(best_parallax_deg) + " deg";
    return true;
  }

  FrameResult initialise_monocular(FrameData f, FrameResult result, FrameTimes times, Clock::time_point start, Clock::time_point tracking_start) {
    result.health = TrackingHealth::kLost;
    result.tracked = false;
    auto finish = [&]() {
      relative.emplace_back(-1, core::SE3());
      times.tracking_s = seconds_since(tracking_start);
      result.times = times;
      result.times.total_s = seconds_since(start);
      ++frames;
      return result;
    };
    if (!have_init_reference) {
      if (f.size() > 100) {
        init_reference = std::move(f);
        have_init_reference = true;
        result.note = "monocular initialisation: reference frame";
      } else {
        result.note = "monocular initialisation: too few features (" + std::to_string(f.size()) + ")";
      }
      return finish();
    }
    const std::vector<std::pair<int, int>> matches = match_for_initialisation(init_reference, f);
    if (matches.size() < 100) {
      result.note = "monocular initialisation: " + std::to_string(matches.size()) + " matches to the reference (< 100): this frame is the new reference";
      if (f.size() > 100) init_reference = std::move(f);
      return finish();
    }
    core::SE3 T_f_ref;
    std::vector<std::pair<int, Eigen::Vector3d>> reconstructed;
    std::string note;
    if (!reconstruct_two_views(init_reference, f, matches, T_f_ref, reconstructed, note)) {
      result.note = "monocular initialisation: " + note;
      return finish();
    }
    // Scale: the median depth of the points in the reference is 1 (ORB-SLAM2; the scale is not
    // observable with one camera).
    std::vector<double> depths;
    for (const auto& [i, X] : reconstructed) depths.push_back(X.z());
    std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
    const double scale = 1.0 / depths[depths.size() / 2];
    init_reference.T_world_camera = core::SE3();
    f.T_world_camera = core::SE3(T_f_ref.so3(), T_f_ref.translation() * scale).inverse();
    std::fill(init_reference.map_point.begin(), init_reference.map_point.end(), -1);
    std::fill(f.map_point.begin(), f.map_point.end(), -1);
    std::unordered_map<int, int> match_of;
    for (const auto& [i, j] : matches) match_of[i] = j;
    FrameData reference = init_reference;
    insert_keyframe(reference, true);
    insert_keyframe(f);
    KeyFrame& k0 = keyframes[keyframes.size() - 2];
    KeyFrame& k1 = keyframes.back();
    for (const auto& [i, X] : reconstructed) {
      const int j = match_of[i];
      MapPoint mp;
      mp.p_world = X * scale;
      mp.descriptor = k0.frame.descriptors.row(i).clone();
      mp.first_keyframe = mp.reference_keyframe = k0.id;
      mp.observations[k0.id] = i;
      mp.observations[k1.id] = j;
      points.push_back(std::move(mp));
      const int id = static_cast<int>(points.size()) - 1;
      k0.frame.map_point[static_cast<std::size_t>(i)] = id;
      k1.frame.map_point[static_cast<std::size_t>(j)] = id;
      f.map_point[static_cast<std::size_t>(j)] = id;
      update_normal_and_depth(points.back());
      update_descriptor(points.back());
      ++summary->map_points;
    }
    if (options.vocabulary) {
      for (KeyFrame* kf : {&k0, &k1}) {
        kf->bow = options.vocabulary->transform(kf->frame.descriptors);
        database.add(static_cast<std::uint32_t>(kf->id), kf->bow);
      }
    }
    const auto mapping_start = Clock::now();
    bundle_adjustment({k0.id, k1.id}, 20, 0);  // ORB-SLAM2: a global BA of the two keyframes
    times.mapping_s = seconds_since(mapping_start);
    f.T_world_camera = keyframes.back().frame.T_world_camera;
    for (std::size_t i = 0; i < f.size(); ++i) f.map_point[i] = keyframes.back().frame.map_point[i];
    // The reference frame's trajectory entry becomes keyframe 0's.
    relative[init_reference.index] = {k0.id, core::SE3()};
    result.tracked = true;
    result.health = TrackingHealth::kOk;
    result.keyframe = true;
    result.inliers = static_cast<int>(reconstructed.size());
    result.inlier_ratio = static_cast<double>(reconstructed.size()) / static_cast<double>(matches.size());
    result.note = "monocular initialisation with frame " + std::to_string(init_reference.index) + ": " + note + "; scale unobservable (median depth set to 1)";
    reference_keyframe = k1.id;
    last = std::move(f);
    have_last = true;
    have_velocity = false;
    relative.emplace_back(reference_keyframe, core::SE3());
    result.T_world_camera = last.T_world_camera;
    result.segment = segment;
    times.tracking_s = seconds_since(tracking_start) - times.mapping_s;
    result.times = times;
    result.times.total_s = seconds_since(start);
    ++frames;
    return result;
  }

  // --- One frame ------------------------------------------------------------------------------

  FrameResult track(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo, FrameTimes times,
                    Clock::time_point start) {
    FrameResult result;
    result.frame = frames;
    result.time = time;
    result.features = static_cast<int>(left.keypoints.size());
    result.stereo_points = static_cast<int>(stereo.matched);
    const auto tracking_start = Clock::now();
    FrameData f = make_frame(time, left, stereo);
    bool mapped = false;
    if (keyframes.empty() && kind == io::SequenceKind::kMonocular) return initialise_monocular(std::move(f), result, times, start, tracking_start);
    if (keyframes.empty()) {
      if (result.stereo_points < options.min_new_points) {
        result.note = "too few stereo/depth points to start a map (" + std::to_string(result.stereo_points) + ")";
        result.health = TrackingHealth::kLost;
        times.tracking_s = seconds_since(tracking_start);
      } else {
        f.T_world_camera = core::SE3();
        times.tracking_s = seconds_since(tracking_start);
        const auto mapping_start = Clock::now();
        insert_keyframe(f);
        detect_and_close_loop(result);
        times.mapping_s = seconds_since(mapping_start);
        result.tracked = true;
        result.health = TrackingHealth::kOk;
        result.keyframe = true;
        result.inliers = static_cast<int>(std::count_if(f.map_point.begin(), f.map_point.end(), [](int id) { return id >= 0; }));
        result.inlier_ratio = 1.0;
        mapped = true;
      }
      if (!mapped) {
        relative.emplace_back(-1, core::SE3());
        result.times = times;
        result.times.total_s = seconds_since(start);
        ++frames;
        return result;
      }
    } else {
      // Stage 1: the previous frame's points at the constant-velocity prediction.
      f.T_world_camera = have_velocity && !lost ? last.T_world_camera * velocity : last.T_world_camera;
      int matches = 0;
      const bool was_lost = lost;
      if (have_last && have_velocity && !lost) {
        // ORB-SLAM2 TrackWithMotionModel: th 7 for stereo, 15 for RGB-D.
        const double radius = kind == io::SequenceKind::kStereo ? options.motion_search_radius_px
                              : kind == io::SequenceKind::kRgbd ? options.motion_search_radius_rgbd_px
                                                                : options.motion_search_radius_mono_px;
        matches = search_from_last(f, last, radius);
        if (matches < options.min_motion_matches) {
          std::fill(f.map_point.begin(), f.map_point.end(), -1);
          matches = search_from_last(f, last, 2.0 * radius);
        }
      }
      int inliers = 0;
      if (matches >= options.min_motion_matches) {
        inliers = optimize_pose(f);
        drop_outliers(f);
      }
      if (inliers < std::max(30, matches / 2)) {
        // The prediction explains too little (fast motion, or no prediction): the reference
        // keyframe's points by descriptor, a PnP RANSAC pose, then the same optimisation; the
        // better of the two is kept.
        // When lost, the most recent keyframes are tried too (a bounded stand-in for ORB-SLAM2's
        // bag-of-words relocalisation over the whole map).
        std::vector<int> candidates{reference_keyframe >= 0 ? reference_keyframe : static_cast<int>(keyframes.size()) - 1};
        if (lost && options.vocabulary && database.size() > 0) {
          // Relocalisation (ORB-SLAM2 Tracking::Relocalization): the keyframes the database
          // ranks best for this frame's words.
          for (const auto& r : database.query(options.vocabulary->transform(f.descriptors), 8)) {
            if (static_cast<int>(r.id) != candidates.front()) candidates.push_back(static_cast<int>(r.id));
          }
        } else if (lost) {
          for (int kf = static_cast<int>(keyframes.size()) - 1; kf >= 0 && candidates.size() < 9; --kf) {
            if (kf != candidates.front()) candidates.push_back(kf);
          }
        }
        for (const int kf : candidates) {
          FrameData alternative = f;
          std::fill(alternative.map_point.begin(), alternative.map_point.end(), -1);
          alternative.T_world_camera = keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera;
          int alternative_matches = search_reference(alternative, keyframes[static_cast<std::size_t>(kf)]);
          ++summary->reference_fallbacks;
          int alternative_inliers = 0;
          if (alternative_matches >= 15) alternative_matches = pnp_ransac(alternative);
          if (alternative_matches >= 15) {
            alternative_inliers = optimize_pose(alternative);
            drop_outliers(alternative);
          }
          if (alternative_inliers > inliers) {
            f = std::move(alternative);
            inliers = alternative_inliers;
            matches = alternative_matches;
            result.used_reference = true;
          }
          if (inliers >= 30) break;
        }
      }
      result.motion_matches = matches;
      int given = 0;
      if (inliers >= 10) {
        // The local map must not make the frame worse than the first stage left it (wrong
        // matches from a poorly predicted projection): then the first stage's result stands.
        FrameData first_stage = f;
        const int first_inliers = inliers;
        inliers = track_local_map(f, &result.sigma_position_m, &given);
        if (inliers < first_inliers / 2) {
          f = std::move(first_stage);
          inliers = first_inliers;
          given = first_inliers;
          result.note = "local-map matches contradicted the first stage; its pose kept";
        }
      }
      result.inliers = inliers;
      result.inlier_ratio = given > 0 ? static_cast<double>(inliers) / given : 0.0;
      times.tracking_s = seconds_since(tracking_start);
      if (was_lost && inliers >= options.lost_below_inliers && inliers < options.relocalisation_min_inliers) {
        result.note = "relocalisation candidate with " + std::to_string(inliers) + " inliers (< " +
                      std::to_string(options.relocalisation_min_inliers) + " needed after being lost): still lost";
        inliers = 0;
      }
      if (inliers < options.lost_below_inliers) {
        result.health = TrackingHealth::kLost;
        result.tracked = false;
        if (result.note.empty()) {
          result.note = "only " + std::to_string(inliers) + " inlier map-point matches (lost below " +
                        std::to_string(options.lost_below_inliers) + "): pose from the motion model";
        }
        f.T_world_camera = have_velocity ? last.T_world_camera * velocity : last.T_world_camera;
        lost = true;
        ++lost_frames;
        if (options.new_map_after_lost_frames > 0 && kind != io::SequenceKind::kMonocular && lost_frames >= options.new_map_after_lost_frames &&
            result.stereo_points >= options.min_new_points) {
          // The Atlas: a new map segment from this frame, where the motion model put it.
          segment = static_cast<int>(segment_parent.size());
          segment_parent.push_back(segment);
          const auto mapping_start = Clock::now();
          std::fill(f.map_point.begin(), f.map_point.end(), -1);
          insert_keyframe(f, true);
          detect_and_close_loop(result);
          times.mapping_s = seconds_since(mapping_start);
          ++summary->maps_started;
          result.new_map = true;
          result.keyframe = true;
          result.tracked = true;
          result.health = TrackingHealth::kDegraded;
          result.note = "lost for " + std::to_string(lost_frames) + " frames: new map segment " + std::to_string(segment) + " started";
          result.inliers = 0;
          lost = false;
          lost_frames = 0;
          have_velocity = false;
        }
      } else {
        lost_frames = 0;
        result.tracked = true;
        if (was_lost) {
          result.relocalised = true;
          ++summary->relocalisations;
        }
        lost = false;
        if (inliers < options.degraded_below_inliers) {
          result.health = TrackingHealth::kDegraded;
          result.note = std::to_string(inliers) + " inlier matches (degraded below " + std::to_string(options.degraded_below_inliers) + ")";
        } else {
          result.health = TrackingHealth::kOk;
        }
        if (need_keyframe(f, inliers)) {
          const auto mapping_start = Clock::now();
          insert_keyframe(f);
          cull_points();
          if (kind == io::SequenceKind::kMonocular) {
            triangulate_new_points(static_cast<int>(keyframes.size()) - 1, 20);  // the only source of points (ORB-SLAM2: 20)
          } else if (options.triangulation_keyframes > 0) {
            triangulate_new_points(static_cast<int>(keyframes.size()) - 1, options.triangulation_keyframes);
          }
          if (options.local_ba) local_bundle_adjustment();
          detect_and_close_loop(result);
          times.mapping_s = seconds_since(mapping_start);
          result.keyframe = true;
        }
      }
    }
    result.keypoints = f.keypoints;
    result.keypoint_states.resize(f.size());
    for (std::size_t i = 0; i < f.size(); ++i) {
      result.keypoint_states[i] = static_cast<signed char>(f.map_point[i] >= 0 ? 2 : (f.depth[i] > 0 ? 1 : 0));
    }
    if (result.tracked) {
      if (have_last && !result.new_map) {
        velocity = last.T_world_camera.inverse() * f.T_world_camera;
        have_velocity = true;
      }
      // Tracking may have relocalised into another segment, or a merge may have renamed it.
      segment = segment_of(reference_keyframe);
      last = std::move(f);
      have_last = true;
      const KeyFrame& ref = keyframes[static_cast<std::size_t>(reference_keyframe)];
      relative.emplace_back(reference_keyframe, ref.frame.T_world_camera.inverse() * last.T_world_camera);
      result.T_world_camera = last.T_world_camera;
    } else {
      // Keep the last tracked frame and its points for the next attempt; report the guess.
      const KeyFrame& ref = keyframes[static_cast<std::size_t>(std::max(reference_keyframe, 0))];
      relative.emplace_back(ref.id, ref.frame.T_world_camera.inverse() * f.T_world_camera);
      result.T_world_camera = f.T_world_camera;
      if (have_last) {
        last.T_world_camera = f.T_world_camera;
        have_velocity = false;
      }
    }
    result.segment = segment;
    result.times = times;
    result.times.total_s = seconds_since(start);
    ++frames;
    return result;
  }
};

std::string VisualSlamOptions::problems() const {
  std::string out;
  auto add = [&](const std::string& p) { out += (out.empty() ? "" : "; ") + p; };
  if (const std::string p = orb.problems(); !p.empty()) add(p);
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
  if (new_map_after_lost_frames < 0) add("new_map_after_lost_frames must be >= 0");
  if (triangulation_keyframes < 0) add("triangulation_keyframes must be >= 0");
  if (!(triangulation_match_ratio > 0.0 && triangulation_match_ratio <= 1.0)) add("triangulation_match_ratio must be in (0, 1]");
  return out;
}

std::string_view to_string(TrackingHealth health) {
  switch (health) {
    case TrackingHealth::kOk: return "ok";
    case TrackingHealth::kDegraded: return "degraded";
    case TrackingHealth::kLost: return "lost";
  }
  return "?";
}

VisualSlam::VisualSlam(const io::CameraCalibration& camera, io::SequenceKind kind, const VisualSlamOptions& options)
    : options_(options) {
  if (const std::string p = options.problems(); !p.empty()) throw std::invalid_argument("visual SLAM options: " + p);
  if (const std::string p = camera.problems(); !p.empty()) throw std::invalid_argument("camera calibration: " + p);
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
  times.features_s = seconds_since(start);
  const auto stereo_start = Clock::now();
  const vision::StereoMatches stereo = vision::match_stereo(fl, fr, impl_->camera, options_.stereo);
  times.stereo_s = seconds_since(stereo_start);
  FrameResult r = impl_->track(time, fl, stereo, times, start);
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
  times.features_s = seconds_since(start);
  const auto stereo_start = Clock::now();
  const std::vector<Eigen::Vector2d> undistorted = vision::undistort_keypoints(f.keypoints, impl_->camera);
  const vision::StereoMatches stereo = vision::depth_from_rgbd(f.keypoints, undistorted, depth, impl_->camera);
  times.stereo_s = seconds_since(stereo_start);
  FrameResult r = impl_->track(time, f, stereo, times, start);
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
  vision::Features f = (impl_->keyframes.empty() ? impl_->orb_initialisation : impl_->orb).extract(gray);
  times.features_s = seconds_since(start);
  vision::StereoMatches none;
  none.u_right.assign(f.keypoints.size(), -1.0);
  none.depth_m.assign(f.keypoints.size(), -1.0);
  FrameResult r = impl_->track(time, f, none, times, start);
  count(summary_, r);
  return r;
}

std::vector<core::SE3> VisualSlam::trajectory() const {
  std::vector<core::SE3> out;
  out.reserve(impl_->relative.size());
  for (const auto& [kf, T_kf_frame] : impl_->relative) {
    out.push_back(kf < 0 ? core::SE3() : impl_->keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera * T_kf_frame);
  }
  return out;
}

std::vector<int> VisualSlam::frame_segments() const {
  std::vector<int> out;
  out.reserve(impl_->relative.size());
  for (const auto& [kf, T] : impl_->relative) out.push_back(kf < 0 ? -1 : impl_->segment_of(kf));
  return out;
}

int VisualSlam::main_segment() const { return impl_->keyframes.empty() ? 0 : impl_->segment_of(0); }

std::vector<core::SE3> VisualSlam::keyframe_poses() const {
  std::vector<core::SE3> out;
  for (const auto& kf : impl_->keyframes) out.push_back(kf.frame.T_world_camera);
  return out;
}

std::vector<std::size_t> VisualSlam::keyframe_frames() const {
  std::vector<std::size_t> out;
  for (const auto& kf : impl_->keyframes) out.push_back(kf.frame.index);
  return out;
}

std::vector<Eigen::Vector3d> VisualSlam::map_points() const {
  std::vector<Eigen::Vector3d> out;
  for (const auto& mp : impl_->points) {
    if (!mp.bad) out.push_back(mp.p_world);
  }
  return out;
}

}  // namespace cairn::vslam
