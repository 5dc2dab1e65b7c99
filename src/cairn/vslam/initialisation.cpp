// Monocular two-view initialisation after ORB-SLAM2 (Initializer.cc; Mur-Artal et al., T-RO 2015, Sec. IV).
// The state and the declarations: slam_state.hpp.

#include "cairn/vslam/slam_state.hpp"

namespace cairn::vslam {

// Level-0 keypoints of the reference matched to the frame within 100 px (ORB-SLAM2
// SearchForInitialization: TH_LOW, ratio 0.9, one-to-one).
std::vector<std::pair<int, int>> VisualSlam::Impl::match_for_initialisation(const FrameData& a, const FrameData& b) const {
  std::vector<int> owner(b.size(), -1), owner_distance(b.size(), 256);
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.keypoints[i].octave > 0) continue;
    BestTwo m;
    for (const int j : features_in_area(b, a.undistorted[i].x(), a.undistorted[i].y(), 100.0, 0, 0)) {
      m.offer(vision::descriptor_distance(a.descriptors.ptr(static_cast<int>(i)), b.descriptors.ptr(j)), j);
    }
    if (!m.passes(options.max_descriptor_distance / 2, 0.9)) continue;
    if (m.best >= owner_distance[static_cast<std::size_t>(m.index)]) continue;
    owner[static_cast<std::size_t>(m.index)] = static_cast<int>(i);
    owner_distance[static_cast<std::size_t>(m.index)] = m.best;
  }
  std::vector<std::pair<int, int>> out;
  for (std::size_t j = 0; j < b.size(); ++j) {
    if (owner[j] >= 0) out.emplace_back(owner[j], static_cast<int>(j));
  }
  return out;
}

namespace {

// The matches' undistorted pixel coordinates in the two views.
void matched_pixels(const FrameData& a, const FrameData& b, const std::vector<std::pair<int, int>>& matches, std::vector<cv::Point2d>& pa,
                    std::vector<cv::Point2d>& pb) {
  for (const auto& [i, j] : matches) {
    pa.emplace_back(a.undistorted[static_cast<std::size_t>(i)].x(), a.undistorted[static_cast<std::size_t>(i)].y());
    pb.emplace_back(b.undistorted[static_cast<std::size_t>(j)].x(), b.undistorted[static_cast<std::size_t>(j)].y());
  }
}

// The homography and the essential matrix by RANSAC (OpenCV); false, with `note`, when either
// fails.
bool estimate_two_view_models(const std::vector<cv::Point2d>& pa, const std::vector<cv::Point2d>& pb, const cv::Matx33d& K, cv::Mat& H, cv::Mat& E,
                              cv::Mat& mask_e, std::string& note) {
  cv::Mat mask_h;
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
  return true;
}

// ORB-SLAM2's scores of the two models (Initializer::CheckHomography / CheckFundamental): the sum
// of chi^2 margins below 5.991 of the symmetric transfer errors for H, of the distances to the
// epipolar lines below 3.841 for F = K^-T E K^-1.
void score_two_view_models(const std::vector<cv::Point2d>& pa, const std::vector<cv::Point2d>& pb, const cv::Mat& H, const cv::Mat& E,
                           const Eigen::Matrix3d& K_e, double& score_h, double& score_f) {
  Eigen::Matrix3d He, Ee;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      He(r, c) = H.at<double>(r, c);
      Ee(r, c) = E.at<double>(r, c);
    }
  }
  const Eigen::Matrix3d H_inv = He.inverse();
  const Eigen::Matrix3d F = K_e.inverse().transpose() * Ee * K_e.inverse();
  score_h = 0.0;
  score_f = 0.0;
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
}

// The pose hypotheses of the chosen model: the homography's decompositions, or the essential
// matrix's pose from cv::recoverPose.
std::vector<std::pair<cv::Matx33d, cv::Vec3d>> two_view_pose_hypotheses(bool use_h, const cv::Mat& H, const cv::Mat& E, const std::vector<cv::Point2d>& pa,
                                                                        const std::vector<cv::Point2d>& pb, const cv::Matx33d& K, cv::Mat& mask_e) {
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
  return poses;
}

// The matches triangulated (linear, Hartley & Zisserman 12.2) with one pose hypothesis (Rc, tc),
// its translation normalised (R, t get it); `good` keeps the points in front of both cameras
// within 2 px, `parallax` their parallax in degrees. False for a hypothesis without translation.
bool triangulate_two_view_hypothesis(const io::CameraCalibration& camera, const Eigen::Matrix3d& K_e, const cv::Matx33d& Rc, const cv::Vec3d& tc,
                                     const std::vector<cv::Point2d>& pa, const std::vector<cv::Point2d>& pb,
                                     const std::vector<std::pair<int, int>>& matches, Eigen::Matrix3d& R, Eigen::Vector3d& t,
                                     std::vector<std::pair<int, Eigen::Vector3d>>& good, std::vector<double>& parallax) {
  t = Eigen::Vector3d(tc[0], tc[1], tc[2]);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) R(r, c) = Rc(r, c);
  }
  if (t.norm() < 1e-12) return false;
  t.normalize();
  const Eigen::Vector3d O2 = -R.transpose() * t;
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
  return true;
}

}  // namespace

// Two-view reconstruction: the homography and the essential matrix (RANSAC, OpenCV), scored
// as ORB-SLAM2 scores them (sum of chi^2 margins below 5.991 of the symmetric transfer errors
// for H, of the distances to the epipolar lines below 3.841 for F); H when
// S_H / (S_H + S_F) > 0.40, else E; the pose from cv::recoverPose / the homography's
// decompositions (the one with most points in front); points triangulated, kept in front of
// both cameras within 2 px; success with >= 50 points seen at >= 1 degree of parallax.
// `note` says which model and why it failed.
bool VisualSlam::Impl::reconstruct_two_views(const FrameData& a, const FrameData& b, const std::vector<std::pair<int, int>>& matches, core::SE3& T_b_a,
                           std::vector<std::pair<int, Eigen::Vector3d>>& points_a, std::string& note) const {
  std::vector<cv::Point2d> pa, pb;
  matched_pixels(a, b, matches, pa, pb);
  const cv::Matx33d K(camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1);
  cv::Mat H, E, mask_e;
  if (!estimate_two_view_models(pa, pb, K, H, E, mask_e, note)) return false;
  const Eigen::Matrix3d K_e = (Eigen::Matrix3d() << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1).finished();
  double score_h = 0.0, score_f = 0.0;
  score_two_view_models(pa, pb, H, E, K_e, score_h, score_f);
  const bool use_h = score_h / (score_h + score_f) > 0.40;
  const std::vector<std::pair<cv::Matx33d, cv::Vec3d>> poses = two_view_pose_hypotheses(use_h, H, E, pa, pb, K, mask_e);
  // Triangulate with every pose; keep the one with most good points.
  std::size_t best_good = 0, second_good = 0;
  std::vector<std::pair<int, Eigen::Vector3d>> best_points;
  Eigen::Matrix3d best_R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d best_t = Eigen::Vector3d::Zero();
  double best_parallax_deg = 0.0;
  for (const auto& [Rc, tc] : poses) {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<std::pair<int, Eigen::Vector3d>> good;
    std::vector<double> parallax;
    if (!triangulate_two_view_hypothesis(camera, K_e, Rc, tc, pa, pb, matches, R, t, good, parallax)) continue;
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

// Feeds one frame to the two-view initialisation (ORB-SLAM2 Tracking::MonocularInitialization):
// the first frame with > 100 features becomes the reference; a later one with >= 100 matches to
// it that reconstructs (reconstruct_two_views) makes a map of two keyframes, otherwise it becomes
// the reference when it has too few matches. The reference keyframe is put at T_world_reference
// and the points scaled so that their median depth in it is `median_depth`: the scale is not
// observable with one camera. The new keyframes belong to `segment` (the caller's current one),
// the first starting it; both get their bag of words, the first goes into the database and the
// second only when `add_second_to_database` (a caller that queries with it adds it then). On
// success f is the second keyframe (pose and points), reference_keyframe is it, and the
// reference frame's trajectory entry is keyframe 0's of the new map; `made` counts its points.
bool VisualSlam::Impl::two_view_map(FrameData& f, const core::SE3& T_world_reference, double median_depth, bool add_second_to_database,
                                    std::string& note, int& made, double& inlier_ratio, double& mapping_s) {
  if (!have_init_reference) {
    if (f.size() > 100) {
      init_reference = f;
      have_init_reference = true;
      note = "monocular initialisation: reference frame";
    } else {
      note = "monocular initialisation: too few features (" + std::to_string(f.size()) + ")";
    }
    return false;
  }
  const std::vector<std::pair<int, int>> matches = match_for_initialisation(init_reference, f);
  if (matches.size() < 100) {
    note = "monocular initialisation: " + std::to_string(matches.size()) + " matches to the reference (< 100): this frame is the new reference";
    if (f.size() > 100) init_reference = f;
    return false;
  }
  core::SE3 T_f_ref;
  std::vector<std::pair<int, Eigen::Vector3d>> reconstructed;
  std::string model;
  if (!reconstruct_two_views(init_reference, f, matches, T_f_ref, reconstructed, model)) {
    note = "monocular initialisation: " + model;
    return false;
  }
  std::vector<double> depths;
  for (const auto& [i, X] : reconstructed) depths.push_back(X.z());
  std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
  const double scale = median_depth / depths[depths.size() / 2];
  init_reference.T_world_camera = T_world_reference;
  f.T_world_camera = T_world_reference * core::SE3(T_f_ref.so3(), T_f_ref.translation() * scale).inverse();
  std::fill(init_reference.map_point.begin(), init_reference.map_point.end(), -1);
  std::fill(init_reference.outlier.begin(), init_reference.outlier.end(), 0);
  std::fill(f.map_point.begin(), f.map_point.end(), -1);
  std::fill(f.outlier.begin(), f.outlier.end(), 0);
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
    mp.p_world = T_world_reference * (X * scale);
    mp.descriptor = k0.frame.descriptors.row(i).clone();
    mp.first_keyframe = mp.reference_keyframe = k0.id;
    mp.observations[k0.id] = i;
    mp.observations[k1.id] = j;
    points.push_back(std::move(mp));
    const int id = static_cast<int>(points.size()) - 1;
    k0.frame.map_point[static_cast<std::size_t>(i)] = id;
    k1.frame.map_point[static_cast<std::size_t>(j)] = id;
    update_normal_and_depth(points.back());
    update_descriptor(points.back());
    ++summary->map_points;
  }
  if (options.vocabulary) {
    for (KeyFrame* kf : {&k0, &k1}) kf->bow = options.vocabulary->transform(kf->frame.descriptors, nullptr, &kf->nodes, bow_levels_up());
    database.add(static_cast<std::uint32_t>(k0.id), k0.bow);
    if (add_second_to_database) database.add(static_cast<std::uint32_t>(k1.id), k1.bow);
  }
  const auto mapping_start = Clock::now();
  bundle_adjustment({k0.id, k1.id}, 20, 0);  // ORB-SLAM2: a global BA of the two keyframes (the first held)
  mapping_s = seconds_since(mapping_start);
  f.T_world_camera = keyframes.back().frame.T_world_camera;
  f.map_point = keyframes.back().frame.map_point;
  // The reference frame's trajectory entry becomes the new map's first keyframe's.
  relative[init_reference.index] = {k0.id, core::SE3()};
  reference_keyframe = k1.id;
  have_init_reference = false;
  made = static_cast<int>(reconstructed.size());
  inlier_ratio = static_cast<double>(reconstructed.size()) / static_cast<double>(matches.size());
  note = "monocular initialisation with frame " + std::to_string(init_reference.index) + ": " + model;
  return true;
}

FrameResult VisualSlam::Impl::initialise_monocular(FrameData f, FrameResult result, FrameTimes times, Clock::time_point start, Clock::time_point tracking_start) {
  result.health = TrackingHealth::kLost;
  result.tracked = false;
  std::string note;
  int made = 0;
  double ratio = 0.0;
  const bool ok = two_view_map(f, core::SE3(), 1.0, true, note, made, ratio, times.mapping_s);
  result.note = note;
  if (!ok) {
    relative.emplace_back(-1, core::SE3());
    times.tracking_s = seconds_since(tracking_start);
    result.times = times;
    result.times.total_s = seconds_since(start);
    ++frames;
    return result;
  }
  result.tracked = true;
  result.health = TrackingHealth::kOk;
  result.keyframe = true;
  result.inliers = made;
  result.inlier_ratio = ratio;
  // Scale: the median depth of the points in the reference is 1 (ORB-SLAM2).
  result.note += "; scale unobservable (median depth set to 1)";
  last = std::move(f);
  T_world_last_tracked = last.T_world_camera;
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

}  // namespace cairn::vslam
