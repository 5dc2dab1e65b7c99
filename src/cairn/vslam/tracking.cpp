// Tracking after ORB-SLAM2 (Tracking.cc, Optimizer::PoseOptimization, ORBmatcher): frames, the keypoint grid, map-point upkeep, matching by projection and by descriptor, PnP RANSAC, motion-only BA, local-map tracking and one whole frame.
// The state and the declarations: slam_state.hpp.

#include "cairn/vslam/slam_state.hpp"

#include <cstdio>

namespace cairn::vslam {

void VisualSlam::Impl::set_image_size(int w, int h) {
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

void VisualSlam::Impl::build_grid(FrameData& f) const {
  f.grid.assign(kGridCols * kGridRows, {});
  for (std::size_t i = 0; i < f.size(); ++i) {
    int cx, cy;
    if (cell_of(f.undistorted[i].x(), f.undistorted[i].y(), cx, cy)) f.grid[static_cast<std::size_t>(cy * kGridCols + cx)].push_back(static_cast<int>(i));
  }
}

std::vector<int> VisualSlam::Impl::features_in_area(const FrameData& f, double x, double y, double r, int min_level, int max_level) const {
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

bool VisualSlam::Impl::project(const core::SE3& T_camera_world, const Eigen::Vector3d& p_world, double& u, double& v, double& ur, double& z) const {
  const Eigen::Vector3d p = T_camera_world * p_world;
  z = p.z();
  if (!(z > 1e-6)) return false;
  u = camera.fx * p.x() / z + camera.cx;
  v = camera.fy * p.y() / z + camera.cy;
  ur = u - bf / z;
  return u >= min_x && u < max_x && v >= min_y && v < max_y;
}

int VisualSlam::Impl::predict_level(const MapPoint& mp, double distance) const {
  const double ratio = mp.max_distance / distance;
  int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(options.orb.scale_factor)));
  return std::clamp(level, 0, options.orb.levels - 1);
}

Eigen::Vector3d VisualSlam::Impl::unproject(const FrameData& f, std::size_t i) const {
  const double z = f.depth[i];
  const Eigen::Vector3d p_camera((f.undistorted[i].x() - camera.cx) * z / camera.fx, (f.undistorted[i].y() - camera.cy) * z / camera.fy, z);
  return f.T_world_camera * p_camera;
}

FrameData VisualSlam::Impl::make_frame(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo) const {
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

void VisualSlam::Impl::update_normal_and_depth(MapPoint& mp) {
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
void VisualSlam::Impl::update_descriptor(MapPoint& mp) {
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

int VisualSlam::Impl::observation_weight(const MapPoint& mp) const {
  int n = 0;
  for (const auto& [kf, idx] : mp.observations) n += keyframes[static_cast<std::size_t>(kf)].frame.u_right[static_cast<std::size_t>(idx)] >= 0 ? 2 : 1;
  return n;
}

void VisualSlam::Impl::erase_observation(int point, int kf) {
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

void VisualSlam::Impl::set_bad(int point) {
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

// ORB-SLAM2 ORBmatcher::SearchByProjection(CurrentFrame, LastFrame, th, bMono) without the
// rotation-histogram check (ORB-SLAM2's TrackWithMotionModel uses it for every sensor,
// ORBmatcher(0.9, true); tried for monocular on the synthetic loop route, 2026-11-25, it moved a
// scale collapse from frame 67 to frame 112 without preventing it, and was not kept).
int VisualSlam::Impl::search_from_last(FrameData& current, const FrameData& previous, double radius_px) {
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
int VisualSlam::Impl::match_to_keyframe(FrameData& current, const std::vector<std::uint32_t>* frame_nodes, const KeyFrame& kf) {
  if (!options.bow_restricted_matching || frame_nodes == nullptr || kf.nodes.size() != kf.frame.size() || frame_nodes->size() != current.size()) {
    return match_brute_force(current, kf.frame.map_point);
  }
  std::unordered_map<std::uint32_t, std::vector<int>> by_node;
  for (std::size_t j = 0; j < kf.frame.size(); ++j) {
    const int id = kf.frame.map_point[j];
    if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) by_node[kf.nodes[j]].push_back(static_cast<int>(j));
  }
  std::vector<int> owner(kf.frame.size(), -1), owner_distance(kf.frame.size(), 256);
  for (std::size_t i = 0; i < current.size(); ++i) {
    if (current.map_point[i] >= 0) continue;
    const auto it = by_node.find((*frame_nodes)[i]);
    if (it == by_node.end()) continue;
    BestTwo m;
    for (const int j : it->second) {
      m.offer(vision::descriptor_distance(current.descriptors.ptr(static_cast<int>(i)),
                                          points[static_cast<std::size_t>(kf.frame.map_point[static_cast<std::size_t>(j)])].descriptor.ptr()),
              j);
    }
    if (!m.passes(options.max_descriptor_distance / 2, 0.75)) continue;
    if (m.best >= owner_distance[static_cast<std::size_t>(m.index)]) continue;
    owner[static_cast<std::size_t>(m.index)] = static_cast<int>(i);
    owner_distance[static_cast<std::size_t>(m.index)] = m.best;
  }
  int matches = 0;
  for (std::size_t j = 0; j < kf.frame.size(); ++j) {
    if (owner[j] < 0) continue;
    current.map_point[static_cast<std::size_t>(owner[j])] = kf.frame.map_point[j];
    ++matches;
  }
  return matches;
}

int VisualSlam::Impl::match_brute_force(FrameData& current, const std::vector<int>& point_ids) {
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

// PnP with RANSAC (OpenCV's solvePnPRansac, EPnP minimal sets; Lepetit et al. 2009) on the
// frame's map-point matches: the starting pose when there is no prediction. Matches that are
// not RANSAC inliers are dropped. Returns the inliers (0 when it fails).
int VisualSlam::Impl::pnp_ransac(FrameData& f) const {
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

// chi^2 of keypoint i of f observing p_world from T_camera_world: the squared reprojection
// error (u, v and, with stereo/depth, u_right) times the level's information (ORB-SLAM2's
// chi2() of its edges); infinite behind the camera.
double VisualSlam::Impl::chi2(const FrameData& f, std::size_t i, const core::SE3& T_cw, const Eigen::Vector3d& p_world) const {
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

double VisualSlam::Impl::chi2_of(const FrameData& f, std::size_t i, const core::SE3& T_cw) const {
  return chi2(f, i, T_cw, points[static_cast<std::size_t>(f.map_point[i])].p_world);
}

std::unique_ptr<backend::Factor> VisualSlam::Impl::observation_factor(const FrameData& f, std::size_t i) const {
  const backend::PinholeIntrinsics K{camera.fx, camera.fy, camera.cx, camera.cy};
  const double baseline = bf / camera.fx;
  if (f.u_right[i] >= 0) {
    return std::make_unique<backend::StereoReprojectionFactor>(K, baseline, f.undistorted[i].x(), f.undistorted[i].y(), f.u_right[i]);
  }
  return std::make_unique<backend::PinholeReprojectionFactor>(K, f.undistorted[i].x(), f.undistorted[i].y());
}

// Returns the inliers; marks outliers in f.outlier; sets f.T_world_camera.
int VisualSlam::Impl::optimize_pose(FrameData& f, double* sigma_position_m, InertialPoseTerms* imu) {
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
    double imu_values[kInertialPoseValues];
    if (imu) add_inertial_pose_terms(*imu, problem, var, imu_values);
    int observations = 0;
    for (const std::size_t i : matched) {
      if (f.outlier[i]) continue;
      ++observations;
      const bool stereo = f.u_right[i] >= 0;
      const double sqrt_info = 1.0 / scales[static_cast<std::size_t>(f.keypoints[i].octave)];
      backend::FactorLoss loss;
      if (round < 2) loss = {backend::RobustKernel::kHuber, std::sqrt(stereo ? options.chi2_stereo : options.chi2_mono)};
      problem.add_factor(std::make_unique<ScaledFactor>(observation_factor(f, i), sqrt_info,
                                                        &points[static_cast<std::size_t>(f.map_point[i])].p_world),
                         {var}, loss);
    }
    if (observations < 3) break;
    const backend::LeastSquaresSummary s = backend::solve(problem, lso);
    if (s.is_solution_usable()) T = backend::se3_from_values(pose);
    if (imu && s.is_solution_usable()) {
      imu->solved = true;
      imu->v_world = Eigen::Map<const Eigen::Vector3d>(imu_values + 10);
    }
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
      const backend::VariableCovariances c = backend::marginal_covariances(cp, {cv}, 1);
      if (imu && imu->solved) {
        // With the IMU's terms added, the pose's and the velocity's: the next frame's prior
        // (ORB-SLAM3 marginalises the last frame's state the same way).
        double covariance_values[kInertialPoseValues];
        const int velocity_variable = add_inertial_pose_terms(*imu, cp, cv, covariance_values);
        Eigen::Map<Eigen::Vector3d>(covariance_values + 10) = imu->v_world;
        const backend::VariableCovariances ci = backend::marginal_covariances(cp, {cv, velocity_variable}, 1);
        if (ci.ok) {
          imu->pose_covariance = ci.blocks[0];
          imu->velocity_covariance = ci.blocks[1];
          imu->covariance_ok = imu->pose_covariance.allFinite() && imu->velocity_covariance.allFinite();
        }
      }
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

void VisualSlam::Impl::drop_outliers(FrameData& f) {
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.map_point[i] >= 0 && f.outlier[i]) {
      f.map_point[i] = -1;
      f.outlier[i] = 0;
    }
  }
}

// Projects the points `ids` (repeats allowed) at f's pose and matches each to the best
// unmatched keypoint near its projection (ORB-SLAM2 ORBmatcher::SearchByProjection(Frame,
// vector<MapPoint*>, th) after Frame::isInFrustum): in front, inside the image, within the
// point's scale-invariance distances, viewed within 60 degrees of its mean viewing direction;
// radius th x (2.5 or 4 by viewing angle) x the predicted level's scale; the best descriptor
// within TH_HIGH and, when the second best is on the same level, better than ratio x it.
// Points the frame already holds are skipped. Returns the new matches.
int VisualSlam::Impl::search_by_projection(FrameData& f, const std::vector<int>& ids, double th, bool count_visible) {
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

int VisualSlam::Impl::track_local_map(FrameData& f, double* sigma_position_m, int* given, bool update_statistics, InertialPoseTerms* imu) {
  const int reference_before = reference_keyframe;
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
  // A saved map's statistics stay as they were saved (localization_only).
  const bool count = update_statistics && !localization_only;
  search_by_projection(f, ids, th, count);
  int matched = 0;
  for (std::size_t i = 0; i < f.size(); ++i) matched += f.map_point[i] >= 0 ? 1 : 0;
  *given = matched;
  const int inliers = optimize_pose(f, sigma_position_m, imu);
  for (std::size_t i = 0; count && i < f.size(); ++i) {
    if (f.map_point[i] >= 0 && !f.outlier[i]) ++points[static_cast<std::size_t>(f.map_point[i])].found;
  }
  drop_outliers(f);
  if (!update_statistics) reference_keyframe = reference_before;
  return inliers;
}

int VisualSlam::Impl::match_pose_to_keyframe(FrameData& f, int kf, const std::vector<std::uint32_t>* frame_nodes, int* matches) {
  std::fill(f.map_point.begin(), f.map_point.end(), -1);
  std::fill(f.outlier.begin(), f.outlier.end(), 0);
  f.T_world_camera = keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera;
  int n = match_to_keyframe(f, frame_nodes, keyframes[static_cast<std::size_t>(kf)]);
  int inliers = 0;
  if (n >= 15) n = pnp_ransac(f);
  if (n >= 15) {
    inliers = optimize_pose(f);
    drop_outliers(f);
  }
  if (matches) *matches = n;
  return inliers;
}

double VisualSlam::Impl::travelled_between(int a, int b) const {
  // Along the good keyframes (a culled one's pose is no longer optimised), through keyframe_pose
  // at the ends should either be culled.
  double travelled = 0.0;
  Eigen::Vector3d previous = keyframe_pose(std::min(a, b)).translation();
  for (int k = std::min(a, b) + 1; k <= std::max(a, b); ++k) {
    if (keyframes[static_cast<std::size_t>(k)].bad && k != std::max(a, b)) continue;
    const Eigen::Vector3d position = keyframe_pose(k).translation();
    travelled += (position - previous).norm();
    previous = position;
  }
  return travelled;
}

bool VisualSlam::Impl::distinct_places(int kf_a, const core::SE3& T_world_a, int kf_b, const core::SE3& T_world_b) const {
  if (segment_of(kf_a) != segment_of(kf_b)) return true;  // unrelated coordinates: cannot be shown to be one place
  const double travelled = travelled_between(kf_a, kf_b);
  const core::SE3 d = T_world_a.inverse() * T_world_b;
  const double deg = Eigen::AngleAxisd(d.rotation_matrix()).angle() * 180.0 / 3.14159265358979323846;
  return d.translation().norm() > options.loop_drift_floor_m + options.loop_drift_fraction * travelled ||
         deg > options.loop_drift_floor_deg + options.loop_drift_deg_per_m * travelled;
}

// ORB-SLAM2's Tracking::Relocalization() accepts the first bag-of-words candidate whose pose
// reaches 50 inliers (PnP RANSAC, PoseOptimization, a projection search, PoseOptimization).
// When two places look alike (identical rooms, repeated offices) that is whichever the
// database ranked first: a confident wrong pose, and tracking then goes on from it reported
// ok. Here every other candidate (and every keyframe scoring >= 0.75 x the best, ORB-SLAM2's
// DetectRelocalizationCandidates cut) is taken through the same steps and the local map, as
// the accepted one was; if one passes the same absolute test (relocalisation_min_inliers) at
// another place (distinct_places), the frame is ambiguous: it stays lost, as a search that
// would rather miss than guess. The rule is the 2D localiser's (slam2d/localization.cpp
// other_fitting_place: where the map explains the scan as well as a verified match must,
// elsewhere, nothing is accepted). No ratio of the two inlier counts decides: they follow the
// map's density more than the view (measured on identical rooms, docs/vslam.md: the twin had
// 0.24-0.98 x the accepted place's inliers, the lowest where the first keyframe, which takes
// all its stereo points, saw the accepted one; a corridor view whose door shows one room's far
// wall had 0.49-0.94 x). A rival in another, unmerged map segment counts as another place: the segments'
// relation is unknown, so a look-alike cannot be told from one place mapped twice (the Atlas
// before a merge), and a young segment started in one of two look-alike rooms would otherwise
// take the frame from the other.
std::string VisualSlam::Impl::relocalisation_rival(const FrameData& f, int inliers, int accepted_kf, const std::vector<int>& candidates,
                                                   const std::vector<std::uint32_t>* frame_nodes) {
  for (const int kf : candidates) {
    if (kf == accepted_kf) continue;
    FrameData rival = f;
    if (match_pose_to_keyframe(rival, kf, frame_nodes) < 10) continue;
    if (!distinct_places(accepted_kf, f.T_world_camera, kf, rival.T_world_camera)) continue;
    double sigma = 0.0;
    int given = 0;
    const int support = track_local_map(rival, &sigma, &given, false);
    if (support < options.relocalisation_min_inliers) continue;
    if (!distinct_places(accepted_kf, f.T_world_camera, kf, rival.T_world_camera)) continue;  // the local map joined them
    char where[64];
    if (segment_of(kf) == segment_of(accepted_kf)) {
      std::snprintf(where, sizeof where, "%.2f m away", (f.T_world_camera.inverse() * rival.T_world_camera).translation().norm());
    } else {
      std::snprintf(where, sizeof where, "in map segment %d", segment_of(kf));
    }
    char buffer[256];
    std::snprintf(buffer, sizeof buffer,
                  "ambiguous relocalisation: keyframe %d gives %d inliers, keyframe %d %d inliers %s: two places explain the "
                  "frame; still lost",
                  accepted_kf, inliers, kf, support, where);
    return buffer;
  }
  return "";
}

// One frame (ORB-SLAM2 Tracking::Track for stereo / RGB-D; monocular frames before the first map
// go to initialise_monocular): the motion model, the image-alignment and reference-keyframe
// fallbacks (with relocalisation when lost), the local map, the checks a relocalisation must
// pass, then either the lost frame's handling or the tracked frame's keyframe decision, and the
// frame's record.
FrameResult VisualSlam::Impl::track(core::Timestamp time, vision::Features& left, const vision::StereoMatches& stereo, vision::SmallBlurryImage sbi,
                                    FrameTimes times, Clock::time_point start) {
  TrackingFrame w;
  w.result.frame = frames;
  w.result.time = time;
  w.result.features = static_cast<int>(left.keypoints.size());
  w.result.stereo_points = static_cast<int>(stereo.matched);
  w.times = times;
  w.start = start;
  w.tracking_start = Clock::now();
  w.f = make_frame(time, left, stereo);
  w.f.sbi = std::move(sbi);
  if (keyframes.empty() && kind == io::SequenceKind::kMonocular) return initialise_monocular(std::move(w.f), w.result, w.times, w.start, w.tracking_start);
  if (keyframes.empty()) {
    if (!start_first_map(w)) return std::move(w.result);
    return record_frame(w);
  }
  // The last keyframe's local mapping (its own thread) is taken now, before this frame is tracked;
  // its time is mapping time of this frame.
  const std::size_t corrections = summary->loops_accepted + summary->maps_merged;
  join_local_mapping(&w.result);
  // A loop or merge closed at the join moved the map under the IMU's state: the next keyframe's
  // inertial estimate gives it again (within the frame, advance_inertial_state takes the
  // corrected keyframe's pose).
  if (summary->loops_accepted + summary->maps_merged != corrections) have_imu_state = false;
  const double joined_s = seconds_since(w.tracking_start);
  w.tracking_start = Clock::now();
  predict_with_imu(w);
  track_motion_model(w);
  align_small_images(w);
  if (w.prediction_failed) track_reference_fallback(w);
  assess_first_stage(w);
  refine_with_local_map(w);
  verify_relocalisation(w);
  if (w.inliers < options.lost_below_inliers) {
    if (!carry_with_imu(w)) handle_lost_frame(w);
  } else {
    accept_tracked_frame(w);
  }
  advance_inertial_state(w);
  w.times.mapping_s += joined_s;
  return record_frame(w);
}

// Stereo / RGB-D, no map yet: the frame starts one at the origin (its stereo/depth points) when
// it has min_new_points of them. False when it did not: the frame is then recorded as lost and
// track returns w.result as it stands.
bool VisualSlam::Impl::start_first_map(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  FrameTimes& times = w.times;
  bool mapped = false;
  if (result.stereo_points < options.min_new_points) {
    result.note = "too few stereo/depth points to start a map (" + std::to_string(result.stereo_points) + ")";
    result.health = TrackingHealth::kLost;
    times.tracking_s = seconds_since(w.tracking_start);
  } else {
    f.T_world_camera = core::SE3();
    times.tracking_s = seconds_since(w.tracking_start);
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
    result.times.total_s = seconds_since(w.start);
    ++frames;
    return false;
  }
  return true;
}

// The last frame's points around `frame`'s pose (ORB-SLAM2 TrackWithMotionModel's search), the
// radius doubled when fewer than min_motion_matches match.
int VisualSlam::Impl::search_around_last(FrameData& frame, double motion_radius_px) {
  int n = search_from_last(frame, last, motion_radius_px);
  if (n < options.min_motion_matches) {
    std::fill(frame.map_point.begin(), frame.map_point.end(), -1);
    n = search_from_last(frame, last, 2.0 * motion_radius_px);
  }
  return n;
}

// Stage 1: the previous frame's points at the constant-velocity prediction (with an IMU, at the
// IMU's: predict_with_imu), then the motion-only BA when enough match; sets whether the
// prediction failed (the fallbacks' trigger).
void VisualSlam::Impl::track_motion_model(TrackingFrame& w) {
  FrameData& f = w.f;
  const bool predicted = w.have_imu_prediction || (have_velocity && !lost);
  f.T_world_camera = w.have_imu_prediction ? camera_pose(w.imu_prediction)
                     : have_velocity && !lost ? last.T_world_camera * velocity
                                              : last.T_world_camera;
  w.matches = 0;
  w.was_lost = lost;
  // ORB-SLAM2 TrackWithMotionModel: th 7 for stereo, 15 for RGB-D (cairn: 7, see the option).
  w.motion_radius_px = kind == io::SequenceKind::kStereo ? options.motion_search_radius_px
                       : kind == io::SequenceKind::kRgbd ? options.motion_search_radius_rgbd_px
                                                         : options.motion_search_radius_mono_px;
  if (have_last && predicted) w.matches = search_around_last(f, w.motion_radius_px);
  w.inliers = 0;
  if (w.matches >= options.min_motion_matches) {
    w.inliers = optimize_pose(f);
    drop_outliers(f);
  }
  w.prediction_failed = w.inliers < std::max(30, w.matches / 2);
}

// Stage 1b: the prediction explains too little, or there was none (lost). PTAM's answer to
// fast turns and motion blur (Klein & Murray, ECCV 2008, Sec. 4): the rotation since the last
// tracked frame from the two small blurry images (vision/image_alignment.hpp), then the last
// frame's points searched around it as in stage 1. The images' "rotation" also absorbs the
// shift a translation makes at the scene's depth, so it is tried with no translation and,
// when there is a velocity, with the velocity's; the most inliers win. A local search from
// the last tracked pose: it cannot jump to a look-alike place, so no uniqueness test; after
// being lost the relocalisation's inlier count still applies (verify_relocalisation).
void VisualSlam::Impl::align_small_images(TrackingFrame& w) {
  FrameData& f = w.f;
  if (options.image_alignment && w.prediction_failed && have_last && !last.sbi.empty() && !f.sbi.empty()) {
    const bool predicted = have_velocity && !lost;
    const Eigen::Matrix3d R_guess = predicted ? Eigen::Matrix3d(velocity.rotation_matrix().transpose()) : Eigen::Matrix3d::Identity();
    vision::RotationAlignmentOptions ao;
    ao.min_correlation = options.image_alignment_min_correlation;
    const vision::RotationAlignment a = vision::align_rotation(last.sbi, f.sbi, camera, R_guess, ao);
    if (a.ok) {
      std::vector<Eigen::Vector3d> shifts{Eigen::Vector3d::Zero()};
      if (predicted) shifts.push_back(velocity.translation());
      for (const Eigen::Vector3d& t_last_current : shifts) {
        FrameData trial = f;
        std::fill(trial.map_point.begin(), trial.map_point.end(), -1);
        std::fill(trial.outlier.begin(), trial.outlier.end(), 0);
        trial.T_world_camera = T_world_last_tracked * core::SE3(core::SO3::from_matrix(a.R_current_previous.transpose()), t_last_current);
        const int trial_matches = search_around_last(trial, w.motion_radius_px);
        if (trial_matches < options.min_motion_matches) continue;
        const int trial_inliers = optimize_pose(trial);
        drop_outliers(trial);
        if (trial_inliers > w.inliers) {
          f = std::move(trial);
          w.inliers = trial_inliers;
          w.matches = trial_matches;
          w.result.used_image_alignment = true;
        }
      }
    }
  }
}

// Stage 2: the prediction explains too little (fast motion, or no prediction): the reference
// keyframe's points by descriptor, a PnP RANSAC pose, then the same optimisation; the
// best of the three (prediction, images' rotation, reference keyframe) is kept.
// When lost, the most recent keyframes are tried too (a bounded stand-in for ORB-SLAM2's
// bag-of-words relocalisation over the whole map). A relocalisation (after being lost, or a
// fallback pose that jumped) keeps its candidates for the uniqueness test.
void VisualSlam::Impl::track_reference_fallback(TrackingFrame& w) {
  FallbackCandidates c = fallback_candidates(w.f);
  try_fallback_candidates(w, c);
  check_fallback_jump(w, c);
  if (w.was_lost || w.jumped) {
    w.relocalisation_candidates = c.candidates;
    for (const int id : c.rival_keyframes) {
      if (std::find(c.candidates.begin(), c.candidates.end(), id) == c.candidates.end()) w.relocalisation_candidates.push_back(id);
    }
    if (c.use_nodes) w.relocalisation_nodes = std::move(c.frame_nodes);
  }
}

// The keyframes the fallback tries, the reference keyframe first: when lost, the database's best
// for the frame's words (and the uniqueness test's rivals), or without a database the most
// recent keyframes; also the frame's words (for the query and node-restricted matching).
VisualSlam::Impl::FallbackCandidates VisualSlam::Impl::fallback_candidates(const FrameData& f) const {
  FallbackCandidates c;
  std::vector<int>& candidates = c.candidates;
  candidates = {reference_keyframe >= 0 ? reference_keyframe : static_cast<int>(keyframes.size()) - 1};
  std::vector<int>& rival_keyframes = c.rival_keyframes;
  // The frame's words: for the database query when lost, and for node-restricted matching.
  c.use_nodes = options.vocabulary && options.bow_restricted_matching;
  if (options.vocabulary && (lost || c.use_nodes)) {
    c.frame_bow = options.vocabulary->transform(f.descriptors, nullptr, c.use_nodes ? &c.frame_nodes : nullptr, bow_levels_up());
  }
  if (lost && options.vocabulary && database.size() > 0) {
    // Relocalisation (ORB-SLAM2 Tracking::Relocalization): the keyframes the database
    // ranks best for this frame's words.
    // The uniqueness test's rivals: every keyframe scoring at least 0.75 x the best, as
    // ORB-SLAM2's KeyFrameDatabase::DetectRelocalizationCandidates keeps (minScoreToRetain),
    // up to 40; the 8 best are the candidates tried first.
    const std::vector<vision::BowDatabase::Result> ranked = database.query(c.frame_bow, 40);
    for (std::size_t k = 0; k < ranked.size(); ++k) {
      const int id = static_cast<int>(ranked[k].id);
      if (k < 8 && id != candidates.front()) candidates.push_back(id);
      if (ranked[k].score >= 0.75 * ranked.front().score) rival_keyframes.push_back(id);
    }
  } else if (lost) {
    for (int kf = static_cast<int>(keyframes.size()) - 1; kf >= 0 && candidates.size() < 9; --kf) {
      if (kf != candidates.front() && !keyframes[static_cast<std::size_t>(kf)].bad) candidates.push_back(kf);
    }
  }
  return c;
}

// Each candidate keyframe in turn (match_pose_to_keyframe); the pose with the most inliers so far
// is kept, and the search stops at 30 inliers.
void VisualSlam::Impl::try_fallback_candidates(TrackingFrame& w, const FallbackCandidates& c) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  for (const int kf : c.candidates) {
    FrameData alternative = f;
    int alternative_matches = 0;
    const int alternative_inliers = match_pose_to_keyframe(alternative, kf, c.use_nodes ? &c.frame_nodes : nullptr, &alternative_matches);
    ++summary->reference_fallbacks;
    if (alternative_inliers > w.inliers) {
      f = std::move(alternative);
      w.inliers = alternative_inliers;
      w.matches = alternative_matches;
      result.used_reference = true;
      result.used_image_alignment = false;
      w.accepted_keyframe = kf;
    }
    if (w.inliers >= 30) break;
  }
}

// A fallback pose farther from the last frame than twice its last step plus
// loop_drift_floor_m is no tracking step but a jump (a kidnap, a dropped stretch of
// frames): PnP against the reference keyframe can land anywhere that keyframe's points
// explain, e.g. in its look-alike. ORB-SLAM2's TrackReferenceKeyFrame cannot jump (it
// optimises from the last pose); here such a pose is treated as a relocalisation: the
// relocalisation's inlier count and uniqueness test, against the database's candidates.
// Not without a velocity (the first frames of a map segment: no step to compare with) and
// not in monocular runs (metres have no scale there).
void VisualSlam::Impl::check_fallback_jump(TrackingFrame& w, FallbackCandidates& c) {
  const FrameData& f = w.f;
  vision::BowVector& frame_bow = c.frame_bow;
  std::vector<int>& rival_keyframes = c.rival_keyframes;
  if (!w.was_lost && w.accepted_keyframe >= 0 && have_last && have_velocity && kind != io::SequenceKind::kMonocular) {
    const double step = velocity.translation().norm();
    w.jump_m = (f.T_world_camera.translation() - last.T_world_camera.translation()).norm();
    if (w.jump_m > options.loop_drift_floor_m + 2.0 * step) {
      w.jumped = true;
      if (options.vocabulary && database.size() > 0) {
        if (frame_bow.empty()) frame_bow = options.vocabulary->transform(f.descriptors, nullptr, nullptr, bow_levels_up());
        const std::vector<vision::BowDatabase::Result> ranked = database.query(frame_bow, 40);
        for (std::size_t k = 0; k < ranked.size(); ++k) {
          if (k < 8 || ranked[k].score >= 0.75 * ranked.front().score) rival_keyframes.push_back(static_cast<int>(ranked[k].id));
        }
      } else {
        for (int kf = static_cast<int>(keyframes.size()) - 1; kf >= 0 && rival_keyframes.size() < 8; --kf) {
          if (!keyframes[static_cast<std::size_t>(kf)].bad) rival_keyframes.push_back(kf);
        }
      }
    }
  }
}

// What the first stage amounts to: whether the frame relocalises (after being lost, or a jump)
// and whether its start is unverified; counts a pose from the images' rotation.
void VisualSlam::Impl::assess_first_stage(TrackingFrame& w) {
  if (w.result.used_image_alignment) ++summary->image_alignment_poses;
  w.relocalising = w.was_lost || w.jumped;
  // Neither the prediction nor the reference keyframe explained the frame (fewer than the 30
  // first-stage inliers the fallback stops at): the local map then searches around a pose that
  // is only a guess, and what it finds must reach the relocalisation's count to be believed.
  // Measured on a kidnap (test_vslam_synthetic.cpp): 16 chance inliers at the old place made
  // a "degraded" frame, its keyframe put the new view's points there, and the next frames
  // tracked 458-895 "inliers" 14 m from the truth, reported ok. ORB-SLAM2 calls a frame lost
  // below 30 local-map inliers (50 after a relocalisation); cairn keeps `degraded` for frames
  // whose start was sound. Not for monocular runs, whose points come from triangulation only
  // and which track with fewer (on TUM fr1/desk this rule left 1 of 149 frames tracked, not 13).
  w.unverified_start = !w.relocalising && w.inliers < 30 && kind != io::SequenceKind::kMonocular;
  w.result.motion_matches = w.matches;
}

// Stage 3 (ORB-SLAM2 Tracking::TrackLocalMap): the local map's points searched at the first
// stage's pose and the pose optimised again; ends the tracking time.
void VisualSlam::Impl::refine_with_local_map(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  int& inliers = w.inliers;
  int& given = w.given;
  given = 0;
  if (inliers >= 10) {
    // The local map must not make the frame worse than the first stage left it (wrong
    // matches from a poorly predicted projection): then the first stage's result stands.
    FrameData first_stage = f;
    const int first_inliers = inliers;
    w.imu_terms = inertial_pose_terms(w);
    inliers = track_local_map(f, &result.sigma_position_m, &given, true, w.imu_terms ? &*w.imu_terms : nullptr);
    if (inliers < first_inliers / 2) {
      f = std::move(first_stage);
      inliers = first_inliers;
      given = first_inliers;
      w.imu_terms.reset();
      result.note = "local-map matches contradicted the first stage; its pose kept";
    }
  }
  result.inliers = inliers;
  result.inlier_ratio = given > 0 ? static_cast<double>(inliers) / given : 0.0;
  w.times.tracking_s = seconds_since(w.tracking_start);
}

// The evidence a relocalisation or an unverified start must give: the uniqueness test
// (relocalisation_rival) and relocalisation_min_inliers; a frame that fails them is lost
// (inliers 0, the reason in the note). A jump is named in the note.
void VisualSlam::Impl::verify_relocalisation(TrackingFrame& w) {
  FrameResult& result = w.result;
  int& inliers = w.inliers;
  if (w.relocalising && inliers >= options.relocalisation_min_inliers && w.accepted_keyframe >= 0) {
    const std::string ambiguous = relocalisation_rival(w.f, inliers, w.accepted_keyframe, w.relocalisation_candidates,
                                                       w.relocalisation_nodes.empty() ? nullptr : &w.relocalisation_nodes);
    if (!ambiguous.empty()) {
      result.note = ambiguous;
      result.relocalisation_refused = true;
      inliers = 0;
      ++summary->relocalisations_ambiguous;
    }
  }
  if (w.relocalising && inliers >= options.lost_below_inliers && inliers < options.relocalisation_min_inliers) {
    result.note = "relocalisation candidate with " + std::to_string(inliers) + " inliers (< " +
                  std::to_string(options.relocalisation_min_inliers) + " needed after being lost): still lost";
    result.relocalisation_refused = true;
    inliers = 0;
  }
  // With an IMU, a pose its prediction agrees with needs no more evidence: the prediction is a
  // local prior from the last tracked frame (after a blank stretch the first images often give
  // the first stage fewer than 30 inliers).
  if (w.unverified_start && inliers >= options.lost_below_inliers && inliers < options.relocalisation_min_inliers) {
    if (agrees_with_imu(w)) {
      result.note = "the first stage gave few inliers; the local map's " + std::to_string(inliers) + " agree with the IMU's prediction";
    } else {
      result.note = "neither the prediction nor the reference keyframe explained the frame, and the local map gave " +
                    std::to_string(inliers) + " inliers (< " + std::to_string(options.relocalisation_min_inliers) + "): lost";
      inliers = 0;
    }
  }
  if (w.jumped) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "the fallback pose jumped %.2f m from the last frame: verified as a relocalisation; ", w.jump_m);
    result.note = buffer + result.note;
  }
}

// Fewer than lost_below_inliers: the frame is lost and takes the motion model's pose; lost for
// new_map_after_lost_frames, it starts a new map segment (start_stereo_segment, or the monocular
// two-view initialisation start_monocular_segment).
void VisualSlam::Impl::handle_lost_frame(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  result.health = TrackingHealth::kLost;
  result.tracked = false;
  if (result.note.empty()) {
    result.note = "only " + std::to_string(w.inliers) + " inlier map-point matches (lost below " +
                  std::to_string(options.lost_below_inliers) + "): pose from the motion model";
  }
  f.T_world_camera = have_velocity ? last.T_world_camera * velocity : last.T_world_camera;
  lost = true;
  ++lost_frames;
  if (options.new_map_after_lost_frames > 0 && kind != io::SequenceKind::kMonocular && lost_frames >= options.new_map_after_lost_frames &&
      result.stereo_points >= options.min_new_points) {
    start_stereo_segment(w);
  } else if (options.new_map_after_lost_frames > 0 && kind == io::SequenceKind::kMonocular && lost_frames >= options.new_map_after_lost_frames) {
    start_monocular_segment(f, result, w.times);
  }
}

// The Atlas: a new map segment from this frame, where the motion model put it (stereo / RGB-D).
void VisualSlam::Impl::start_stereo_segment(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  segment = static_cast<int>(segment_parent.size());
  segment_parent.push_back(segment);
  const auto mapping_start = Clock::now();
  std::fill(f.map_point.begin(), f.map_point.end(), -1);
  insert_keyframe(f, true);
  detect_and_close_loop(result);
  if (!result.loop_closed) merge_with_recent(result);
  f.T_world_camera = keyframes.back().frame.T_world_camera;
  w.times.mapping_s = seconds_since(mapping_start);
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

// The frame is tracked: its health from the inliers, a relocalisation counted, and a keyframe
// made when need_keyframe asks for one (map_keyframe).
void VisualSlam::Impl::accept_tracked_frame(TrackingFrame& w) {
  FrameResult& result = w.result;
  const int inliers = w.inliers;
  lost_frames = 0;
  result.tracked = true;
  // Tracking may have relocalised into another segment: a keyframe made now belongs to the
  // segment whose points it tracked, not to the one it was lost from.
  segment = segment_of(reference_keyframe);
  if (w.relocalising) {
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
  if (!localization_only && need_keyframe(w.f, inliers)) map_keyframe(w);
}

// Local mapping of a new keyframe (ORB-SLAM2 LocalMapping::Run, in line): insert, cull points,
// triangulate, fuse, local BA, cull keyframes, then loop closing or a merge.
void VisualSlam::Impl::map_keyframe(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
  const auto mapping_start = Clock::now();
  insert_keyframe(f);
  start_keyframe_imu_state(w);
  cull_points();
  if (kind == io::SequenceKind::kMonocular) {
    triangulate_new_points(static_cast<int>(keyframes.size()) - 1, 20);  // the only source of points (ORB-SLAM2: 20)
  } else if (options.triangulation_keyframes > 0) {
    triangulate_new_points(static_cast<int>(keyframes.size()) - 1, options.triangulation_keyframes);
  }
  if (options.fuse_points) search_in_neighbours(static_cast<int>(keyframes.size()) - 1);
  if (options.local_ba && options.local_mapping_thread && kind != io::SequenceKind::kMonocular) {
    // The rest (bundle adjustment, culling, loop closing) in the background until the next
    // frame is tracked (join_local_mapping).
    start_local_mapping();
  } else {
    if (options.local_ba) local_bundle_adjustment();
    finish_keyframe(result);
  }
  // The frame is the keyframe: it takes the pose the bundle adjustment and any loop
  // correction gave the keyframe (its trajectory entry is relative to it), and its points
  // as fusion, culling and loop fusion left them (with the mapping thread, as they are now:
  // the adjusted ones reach `last` at the join).
  f.T_world_camera = keyframes.back().frame.T_world_camera;
  f.map_point = keyframes.back().frame.map_point;
  w.times.mapping_s = seconds_since(mapping_start);
  result.keyframe = true;
}

// The frame's record: keypoint states, the velocity, `last` (a tracked frame) or the guess (a
// lost one), its trajectory entry relative to the reference keyframe, the times.
FrameResult VisualSlam::Impl::record_frame(TrackingFrame& w) {
  FrameData& f = w.f;
  FrameResult& result = w.result;
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
    T_world_last_tracked = last.T_world_camera;
    have_last = true;
    const KeyFrame& ref = keyframes[static_cast<std::size_t>(reference_keyframe)];
    relative.emplace_back(reference_keyframe, ref.frame.T_world_camera.inverse() * last.T_world_camera);
    result.T_world_camera = last.T_world_camera;
  } else {
    // Keep the last tracked frame and its points for the next attempt; report the guess. A
    // keyframe the IMU carried (map_carried_view) is the next frame's `last` instead: its points
    // are the ones in view.
    const KeyFrame& ref = keyframes[static_cast<std::size_t>(std::max(reference_keyframe, 0))];
    relative.emplace_back(ref.id, ref.frame.T_world_camera.inverse() * f.T_world_camera);
    result.T_world_camera = f.T_world_camera;
    if (result.carried_by_imu && result.keyframe) {
      last = std::move(f);
      have_last = true;
      have_velocity = false;
    } else if (have_last) {
      last.T_world_camera = f.T_world_camera;
      have_velocity = false;
    }
  }
  result.segment = segment;
  result.times = w.times;
  result.times.total_s = seconds_since(w.start);
  ++frames;
  return std::move(result);
}

// The Atlas for one camera (ORB-SLAM3 Tracking::Track: a map lost for good is set aside and the
// next frames initialise a new one). A lost frame that did not relocalise is fed to the two-view
// initialisation (initialisation.cpp two_view_map), the first of them as its reference; when two
// views reconstruct, they start a new map segment. Its first keyframe is put where tracking was
// lost and its unit is a guess, the median depth of the last reference keyframe's points
// (ORB-SLAM2 KeyFrame::ComputeSceneMedianDepth), so that an unmerged segment is drawn near its
// place at about the right size; the Sim(3) of a merge (loop_closing.cpp) corrects both. The
// segment's first keyframe then holds its gauge (anchors_segment) until a merge.
void VisualSlam::Impl::start_monocular_segment(FrameData& f, FrameResult& result, FrameTimes& times) {
  if (lost_frames == options.new_map_after_lost_frames) have_init_reference = false;  // a fresh reference for this loss
  const std::optional<double> last_depth = reference_keyframe >= 0 ? median_point_depth(reference_keyframe) : std::nullopt;
  const double median_depth = last_depth && *last_depth > 0.0 ? *last_depth : 1.0;
  const int previous_segment = segment;
  segment = static_cast<int>(segment_parent.size());
  segment_parent.push_back(segment);
  FrameData attempt = f;
  std::string note;
  int made = 0;
  double ratio = 0.0, init_mapping_s = 0.0;
  if (!two_view_map(attempt, T_world_last_tracked, median_depth, false, note, made, ratio, init_mapping_s)) {
    segment_parent.pop_back();
    segment = previous_segment;
    result.note += "; new map: " + note;
    return;
  }
  f = std::move(attempt);
  const auto mapping_start = Clock::now();
  detect_and_close_loop(result);
  if (!result.loop_closed) merge_with_recent(result);
  f.T_world_camera = keyframes.back().frame.T_world_camera;
  f.map_point = keyframes.back().frame.map_point;
  times.mapping_s += init_mapping_s + seconds_since(mapping_start);
  ++summary->maps_started;
  char buffer[160];
  std::snprintf(buffer, sizeof buffer, "lost for %d frames: new map segment %d started by ", lost_frames, segment);
  result.note = buffer + note + " (its unit a guess: the median depth of the last map's points)";
  result.new_map = true;
  result.keyframe = true;
  result.tracked = true;
  result.health = TrackingHealth::kDegraded;
  result.inliers = made;
  result.inlier_ratio = ratio;
  lost = false;
  lost_frames = 0;
  have_velocity = false;
}

// The median depth of a keyframe's points in its camera (ORB-SLAM2 KeyFrame::ComputeSceneMedianDepth); none without points.
std::optional<double> VisualSlam::Impl::median_point_depth(int kf) const {
  const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
  const core::SE3 T_camera_world = k.frame.T_world_camera.inverse();
  std::vector<double> depths;
  for (const int id : k.frame.map_point) {
    if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) depths.push_back((T_camera_world * points[static_cast<std::size_t>(id)].p_world).z());
  }
  if (depths.empty()) return std::nullopt;
  std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
  return depths[depths.size() / 2];
}

}  // namespace cairn::vslam
