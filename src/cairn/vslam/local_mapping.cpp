// Local mapping after ORB-SLAM2 (LocalMapping.cc, Optimizer::LocalBundleAdjustment): keyframe decision and insertion, triangulation between keyframes, point culling, covisibility, local and global bundle adjustment on the least-squares engine; with an IMU, its factors in the local bundle adjustment (ORB-SLAM3 LocalInertialBA).
// The state and the declarations: slam_state.hpp.

#include "cairn/vslam/slam_state.hpp"

#include "cairn/core/assert.hpp"
#include "cairn/inertial/imu_factors.hpp"

namespace cairn::vslam {

bool VisualSlam::Impl::need_keyframe(const FrameData& f, int inliers) const {
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
  bool c3 = false;  // monocular: turned by a share of the field of view (monocular_keyframe_turn_fov)
  if (kind == io::SequenceKind::kMonocular && options.monocular_keyframe_turn_fov > 0.0 && !keyframes.empty()) {
    const double fov = 2.0 * std::atan(0.5 * static_cast<double>(width) / camera.fx);
    const double turned = Eigen::AngleAxisd(keyframes.back().frame.T_world_camera.rotation_matrix().transpose() * f.T_world_camera.rotation_matrix()).angle();
    c3 = turned > options.monocular_keyframe_turn_fov * fov && inliers > options.lost_below_inliers;
  }
  return c2 || c3 || (c1 && inliers > options.lost_below_inliers);
}

void VisualSlam::Impl::insert_keyframe(FrameData& f, bool starts_segment) {
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
int VisualSlam::Impl::triangulate_new_points(int current, int count) {
  std::vector<std::pair<int, int>> neighbours = covisible(current, 1);
  if (neighbours.size() > static_cast<std::size_t>(count)) neighbours.resize(static_cast<std::size_t>(count));
  const Eigen::Matrix3d K = (Eigen::Matrix3d() << camera.fx, 0, camera.cx, 0, camera.fy, camera.cy, 0, 0, 1).finished();
  const Eigen::Matrix3d K_inv = K.inverse();
  int created = 0;
  for (const auto& [shared, k2_id] : neighbours) created += triangulate_with_neighbour(current, k2_id, K_inv);
  return created;
}

// One neighbour of triangulate_new_points: skipped below the stereo baseline (monocular: a
// baseline below 0.01 x its median scene depth); else the two keyframes' unmatched keypoints
// matched along the epipolar lines, triangulated, checked and made map points. Returns the points.
int VisualSlam::Impl::triangulate_with_neighbour(int current, int k2_id, const Eigen::Matrix3d& K_inv) {
  const double stereo_baseline = bf / camera.fx;
  const KeyFrame& k2 = keyframes[static_cast<std::size_t>(k2_id)];
  const FrameData& f1 = keyframes[static_cast<std::size_t>(current)].frame;
  const FrameData& f2 = k2.frame;
  const Eigen::Vector3d O1 = f1.T_world_camera.translation(), O2 = f2.T_world_camera.translation();
  const core::SE3 T1_cw = f1.T_world_camera.inverse(), T2_cw = f2.T_world_camera.inverse();
  if (kind == io::SequenceKind::kMonocular) {
    // ORB-SLAM2: baseline / the neighbour's median scene depth at least 0.01.
    const std::optional<double> depth = median_point_depth(k2_id);
    if (!depth || (O2 - O1).norm() / *depth < 0.01) return 0;
  } else if ((O2 - O1).norm() < stereo_baseline) {
    return 0;  // ORB-SLAM2: no triangulation below the stereo baseline
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
  const std::vector<int> taken_by = match_along_epipolar_lines(f1, f2, F12, epipole_valid, ex, ey);
  int created = 0;
  for (std::size_t i2 = 0; i2 < f2.size(); ++i2) {
    const int signed_i1 = taken_by[i2];
    if (signed_i1 < 0) continue;
    const auto i1 = static_cast<std::size_t>(signed_i1);
    Eigen::Vector3d X;
    if (!triangulate_match(f1, i1, f2, i2, T1_cw, T2_cw, K_inv, X)) continue;
    if (!consistent_new_point(f1, i1, f2, i2, T1_cw, T2_cw, X)) continue;
    add_triangulated_point(current, i1, k2_id, i2, X);
    ++created;
  }
  return created;
}

// Each unmatched keypoint of f1 against f2's unmatched keypoints at its level +- 1, away from the
// epipole when neither has depth, within 3.84 sigma^2 of its epipolar line (F12); the best
// descriptor within TH_LOW and the ratio test; one-to-one, the closer descriptor winning.
// Returns, per keypoint of f2, the keypoint of f1 matched to it (-1: none).
std::vector<int> VisualSlam::Impl::match_along_epipolar_lines(const FrameData& f1, const FrameData& f2, const Eigen::Matrix3d& F12, bool epipole_valid,
                                                              double ex, double ey) const {
  std::vector<int> taken_by(f2.size(), -1);
  std::vector<int> taken_distance(f2.size(), 256);
  for (std::size_t i1 = 0; i1 < f1.size(); ++i1) {
    if (f1.map_point[i1] >= 0) continue;
    const Eigen::Vector3d x1(f1.undistorted[i1].x(), f1.undistorted[i1].y(), 1.0);
    const Eigen::Vector3d line = F12.transpose() * x1;  // epipolar line in image 2: x2^T (F12^T x1) = 0
    const double line_norm2 = line.x() * line.x() + line.y() * line.y();
    if (!(line_norm2 > 0.0)) continue;
    BestTwo m;
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
      m.offer(vision::descriptor_distance(f1.descriptors.ptr(static_cast<int>(i1)), f2.descriptors.ptr(static_cast<int>(i2))),
              static_cast<int>(i2));
    }
    // TH_LOW, and a ratio test along the epipolar band: without ORB-SLAM2's bag-of-words
    // nodes the band holds many look-alikes (repeated texture, forward motion).
    if (m.index < 0 || m.best > options.max_descriptor_distance / 2 || m.best > options.triangulation_match_ratio * m.second) continue;
    const int best = m.best, best_i2 = m.index;
    if (best >= taken_distance[static_cast<std::size_t>(best_i2)]) continue;
    taken_by[static_cast<std::size_t>(best_i2)] = static_cast<int>(i1);
    taken_distance[static_cast<std::size_t>(best_i2)] = best;
  }
  return taken_by;
}

// The point of the match (i1 of f1, i2 of f2): triangulated (linear, Hartley & Zisserman 12.2)
// when the rays' parallax beats the stereo parallax, else the view with the better stereo depth
// unprojected; false with too little parallax either way or a degenerate solution.
bool VisualSlam::Impl::triangulate_match(const FrameData& f1, std::size_t i1, const FrameData& f2, std::size_t i2, const core::SE3& T1_cw,
                                         const core::SE3& T2_cw, const Eigen::Matrix3d& K_inv, Eigen::Vector3d& X) const {
  const double stereo_baseline = bf / camera.fx;
  const Eigen::Vector3d xn1 = K_inv * Eigen::Vector3d(f1.undistorted[i1].x(), f1.undistorted[i1].y(), 1.0);
  const Eigen::Vector3d xn2 = K_inv * Eigen::Vector3d(f2.undistorted[i2].x(), f2.undistorted[i2].y(), 1.0);
  const Eigen::Vector3d ray1 = f1.T_world_camera.rotation_matrix() * xn1, ray2 = f2.T_world_camera.rotation_matrix() * xn2;
  const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
  const bool stereo1 = f1.depth[i1] > 0, stereo2 = f2.depth[i2] > 0;
  const double cos_stereo1 = stereo1 ? std::cos(2.0 * std::atan2(stereo_baseline / 2.0, f1.depth[i1])) : 2.0;
  const double cos_stereo2 = stereo2 ? std::cos(2.0 * std::atan2(stereo_baseline / 2.0, f2.depth[i2])) : 2.0;
  const double cos_stereo = std::min(cos_stereo1, cos_stereo2);
  if (cos_rays < cos_stereo && cos_rays > 0.0 && (stereo1 || stereo2 || cos_rays < 0.9998)) {
    // Linear triangulation: A X = 0 from x cross (P X) = 0 in both views.
    const Eigen::Matrix<double, 3, 4> P1 = T1_cw.matrix3x4(), P2 = T2_cw.matrix3x4();
    Eigen::Matrix4d A;
    A.row(0) = xn1.x() * P1.row(2) - P1.row(0);
    A.row(1) = xn1.y() * P1.row(2) - P1.row(1);
    A.row(2) = xn2.x() * P2.row(2) - P2.row(0);
    A.row(3) = xn2.y() * P2.row(2) - P2.row(1);
    const Eigen::Vector4d h = Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
    if (std::abs(h(3)) < 1e-12) return false;
    X = h.head<3>() / h(3);
  } else if (stereo1 && cos_stereo1 < cos_stereo2) {
    X = unproject(f1, i1);
  } else if (stereo2 && cos_stereo2 < cos_stereo1) {
    X = unproject(f2, i2);
  } else {
    return false;  // too little parallax either way
  }
  return true;
}

// A new point X of the match (i1 of f1, i2 of f2) is kept when in front of both cameras, within
// the chi^2 thresholds in both, and at consistent scales (distance ratio within 1.5 x scale
// factor of the octave ratio).
bool VisualSlam::Impl::consistent_new_point(const FrameData& f1, std::size_t i1, const FrameData& f2, std::size_t i2, const core::SE3& T1_cw,
                                            const core::SE3& T2_cw, const Eigen::Vector3d& X) const {
  const double ratio_factor = 1.5 * options.orb.scale_factor;
  const Eigen::Vector3d O1 = f1.T_world_camera.translation(), O2 = f2.T_world_camera.translation();
  const bool stereo1 = f1.depth[i1] > 0, stereo2 = f2.depth[i2] > 0;
  if (!((T1_cw * X).z() > 0.0) || !((T2_cw * X).z() > 0.0)) return false;
  if (chi2(f1, i1, T1_cw, X) > (stereo1 ? options.chi2_stereo : options.chi2_mono)) return false;
  if (chi2(f2, i2, T2_cw, X) > (stereo2 ? options.chi2_stereo : options.chi2_mono)) return false;
  const double dist1 = (X - O1).norm(), dist2 = (X - O2).norm();
  if (dist1 <= 0.0 || dist2 <= 0.0) return false;
  const double ratio_dist = dist2 / dist1;
  const double ratio_octave = scales[static_cast<std::size_t>(f1.keypoints[i1].octave)] / scales[static_cast<std::size_t>(f2.keypoints[i2].octave)];
  if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) return false;
  return true;
}

// A map point at X seen by keypoint i1 of keyframe `current` (its first and reference
// keyframe, whose descriptor it takes) and keypoint i2 of keyframe k2_id.
void VisualSlam::Impl::add_triangulated_point(int current, std::size_t i1, int k2_id, std::size_t i2, const Eigen::Vector3d& X) {
  MapPoint mp;
  mp.p_world = X;
  mp.descriptor = keyframes[static_cast<std::size_t>(current)].frame.descriptors.row(static_cast<int>(i1)).clone();
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
}

// ORB-SLAM2 LocalMapping::MapPointCulling (stereo: 3 observations, a stereo one counting 2).
void VisualSlam::Impl::cull_points() {
  const int current = static_cast<int>(keyframes.size()) - 1;
  std::vector<int> keep;
  for (const int id : recent_points) {
    MapPoint& mp = points[static_cast<std::size_t>(id)];
    if (mp.bad) continue;
    // A point of another map segment (tracking was lost, or relocalised elsewhere) is judged by
    // nothing this segment sees: it stays, as it was when its segment stopped.
    if (segment_of(mp.first_keyframe) != segment_of(current)) continue;
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

int VisualSlam::Impl::fuse_into(int kf, const std::vector<int>& ids, double th) {
  FrameData& f = keyframes[static_cast<std::size_t>(kf)].frame;
  const core::SE3 T_cw = f.T_world_camera.inverse();
  const Eigen::Vector3d center = f.T_world_camera.translation();
  int fused = 0;
  for (const int id : ids) {
    if (points[static_cast<std::size_t>(id)].bad || points[static_cast<std::size_t>(id)].observations.count(kf)) continue;
    const MapPoint& mp = points[static_cast<std::size_t>(id)];
    double u, v, ur, z;
    if (!project(T_cw, mp.p_world, u, v, ur, z)) continue;
    const Eigen::Vector3d po = mp.p_world - center;
    const double distance = po.norm();
    if (distance < 0.8 * mp.min_distance || distance > 1.2 * mp.max_distance) continue;
    if (po.dot(mp.normal) < 0.5 * distance) continue;
    const int level = predict_level(mp, distance);
    const double r = th * scales[static_cast<std::size_t>(level)];
    int best = 256, best_j = -1;
    for (const int j : features_in_area(f, u, v, r, level - 1, level)) {
      const auto sj = static_cast<std::size_t>(j);
      const double ex = u - f.undistorted[sj].x(), ey = v - f.undistorted[sj].y();
      double e2 = ex * ex + ey * ey;
      const bool stereo = f.u_right[sj] >= 0;
      if (stereo) e2 += (ur - f.u_right[sj]) * (ur - f.u_right[sj]);
      if (e2 * inv_sigma2[static_cast<std::size_t>(f.keypoints[sj].octave)] > (stereo ? options.chi2_stereo : options.chi2_mono)) continue;
      const int d = vision::descriptor_distance(mp.descriptor.ptr(), f.descriptors.ptr(j));
      if (d < best) {
        best = d;
        best_j = j;
      }
    }
    if (best_j < 0 || best > options.max_descriptor_distance / 2) continue;
    const auto sj = static_cast<std::size_t>(best_j);
    const int held = f.map_point[sj];
    if (held >= 0 && !points[static_cast<std::size_t>(held)].bad) {
      if (held == id) continue;
      // The point with more observations survives (ORB-SLAM2 MapPoint::Replace).
      const bool keep_held = points[static_cast<std::size_t>(held)].observations.size() > mp.observations.size();
      const int survivor = keep_held ? held : id;
      replace_point(keep_held ? id : held, survivor);
      update_descriptor(points[static_cast<std::size_t>(survivor)]);
      update_normal_and_depth(points[static_cast<std::size_t>(survivor)]);
    } else {
      points[static_cast<std::size_t>(id)].observations[kf] = best_j;
      f.map_point[sj] = id;
      ++summary->fusion_observations;
    }
    ++fused;
  }
  return fused;
}

// ORB-SLAM2 LocalMapping::SearchInNeighbors: the targets are the newest keyframe's 10 most
// covisible keyframes (20 for monocular) and each one's 5 most covisible; the newest keyframe's
// points are fused into every target, then every target's points into the newest keyframe,
// then the newest keyframe's points get their descriptors and normals again.
void VisualSlam::Impl::search_in_neighbours(int current) {
  const std::size_t first = kind == io::SequenceKind::kMonocular ? 20 : 10;
  std::vector<int> targets;
  std::set<int> seen{current};
  std::vector<std::pair<int, int>> neighbours = covisible(current, 1);
  if (neighbours.size() > first) neighbours.resize(first);
  for (const auto& [n, kf] : neighbours) {
    if (keyframes[static_cast<std::size_t>(kf)].bad || !seen.insert(kf).second) continue;
    targets.push_back(kf);
  }
  const std::size_t first_count = targets.size();
  for (std::size_t t = 0; t < first_count; ++t) {
    std::vector<std::pair<int, int>> second = covisible(targets[t], 1);
    if (second.size() > 5) second.resize(5);
    for (const auto& [n, kf] : second) {
      if (keyframes[static_cast<std::size_t>(kf)].bad || !seen.insert(kf).second) continue;
      targets.push_back(kf);
    }
  }
  for (const int kf : targets) {
    std::vector<int> ids;
    for (const int id : keyframes[static_cast<std::size_t>(current)].frame.map_point) {
      if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) ids.push_back(id);
    }
    fuse_into(kf, ids, 3.0);
  }
  std::vector<int> candidates;
  std::set<int> added;
  for (const int kf : targets) {
    for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
      if (id >= 0 && !points[static_cast<std::size_t>(id)].bad && added.insert(id).second) candidates.push_back(id);
    }
  }
  fuse_into(current, candidates, 3.0);
  for (const int id : keyframes[static_cast<std::size_t>(current)].frame.map_point) {
    if (id < 0 || points[static_cast<std::size_t>(id)].bad) continue;
    update_descriptor(points[static_cast<std::size_t>(id)]);
    update_normal_and_depth(points[static_cast<std::size_t>(id)]);
  }
}

// ORB-SLAM2 LocalMapping::KeyFrameCulling (Mur-Artal & Tardos, T-RO 2017, Sec. V-E; ORB-SLAM
// T-RO 2015 Sec. VI-E): "discard all the keyframes in the local map whose 90 % of the map points
// have been seen in at least other three keyframes in the same or finer scale". As ORB-SLAM2's
// code: the local keyframes are the newest one's covisible ones (>= min_covisible_points shared);
// with stereo / depth only the keyframe's close points count (0 < depth <= ThDepth); a point is
// examined only when its observation weight (a stereo observation counting 2) exceeds 3, and is
// redundant when >= 3 other keyframes see it at a level <= this keyframe's level + 1; culled when
// redundant > keyframe_culling_redundancy (ORB-SLAM2: 0.9) x counted. Kept: keyframe 0 (the
// gauge), the first keyframe of a segment (the segment's origin and its weak link to the one
// before), keyframes of other segments (judged by nothing this segment sees, as cull_points'
// points) and the candidates of pending loop consistency checks (ORB-SLAM2's SetNotErase). Culling runs on the tracking thread (at the join of the mapping
// thread's bundle adjustment, or within the keyframe's frame), so no relocalisation or loop
// verification is under way while this runs.
void VisualSlam::Impl::cull_keyframes() {
  const int current = static_cast<int>(keyframes.size()) - 1;
  constexpr int kObservers = 3;
  for (const auto& [shared, kf] : covisible(current, options.min_covisible_points)) {
    const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
    if (kf == 0 || k.bad || k.starts_segment || kf == reference_keyframe || segment_of(kf) != segment_of(current) ||
        pending_loop_candidates.count(kf)) {
      continue;
    }
    int counted = 0, redundant = 0;
    for (std::size_t i = 0; i < k.frame.size(); ++i) {
      const int id = k.frame.map_point[i];
      if (id < 0) continue;
      const MapPoint& mp = points[static_cast<std::size_t>(id)];
      if (mp.bad) continue;
      if (kind != io::SequenceKind::kMonocular && (k.frame.depth[i] > close_depth_m || k.frame.depth[i] < 0)) continue;
      ++counted;
      if (observation_weight(mp) <= kObservers) continue;
      const int level = k.frame.keypoints[i].octave;
      int observers = 0;
      for (const auto& [other, idx] : mp.observations) {
        if (other == kf) continue;
        if (keyframes[static_cast<std::size_t>(other)].frame.keypoints[static_cast<std::size_t>(idx)].octave <= level + 1 &&
            ++observers >= kObservers) {
          break;
        }
      }
      if (observers >= kObservers) ++redundant;
    }
    if (redundant > options.keyframe_culling_redundancy * counted) cull_keyframe(kf);
  }
}

// ORB-SLAM2 KeyFrame::SetBadFlag.
void VisualSlam::Impl::cull_keyframe(int kf) {
  KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
  CAIRN_ASSERT(kf > 0 && !k.starts_segment && !k.bad, "keyframe 0 and the first keyframe of a segment are never culled");
  // The parent: the previous good keyframe of the same segment (one exists: its first keyframe is
  // never culled). The loop closer's consecutive chain then runs through the good keyframes only.
  int parent = kf - 1;
  while (parent > 0 && (keyframes[static_cast<std::size_t>(parent)].bad || segment_of(parent) != segment_of(kf))) --parent;
  k.parent = parent;
  k.T_parent_keyframe = keyframes[static_cast<std::size_t>(parent)].frame.T_world_camera.inverse() * k.frame.T_world_camera;
  for (std::size_t i = 0; i < k.frame.size(); ++i) {
    const int id = k.frame.map_point[i];
    if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) erase_observation(id, kf);
  }
  std::fill(k.frame.map_point.begin(), k.frame.map_point.end(), -1);
  if (options.vocabulary) database.erase(static_cast<std::uint32_t>(kf));
  for (auto& [group, count] : consistent_groups) group.erase(kf);
  k.bad = true;
  ++summary->keyframes_culled;
}

// Keyframes sharing at least `min_shared` good points with keyframe `kf`, most first.
std::vector<std::pair<int, int>> VisualSlam::Impl::covisible(int kf, int min_shared) const {
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

// ORB-SLAM2 Optimizer::LocalBundleAdjustment's keyframes: the newest one and its covisible ones,
// the most shared points first, at most max_local_ba_keyframes of them.
std::set<int> VisualSlam::Impl::local_ba_keyframes() const {
  const int current = static_cast<int>(keyframes.size()) - 1;
  std::vector<std::pair<int, int>> ranked = covisible(current, options.min_covisible_points);
  if (ranked.size() > static_cast<std::size_t>(options.max_local_ba_keyframes)) ranked.resize(static_cast<std::size_t>(options.max_local_ba_keyframes));
  std::set<int> local{current};
  for (const auto& [n, kf] : ranked) local.insert(kf);
  return local;
}

// The local bundle adjustment of the newest keyframe started in the background. Nothing that
// adds or removes keyframes, points or observations runs before join_local_mapping: the job reads
// the map as it was at the start.
void VisualSlam::Impl::start_local_mapping() {
  LocalMappingJob& job = mapping_job;
  const int current = static_cast<int>(keyframes.size()) - 1;
  job.local = local_ba_keyframes();
  job.ba = BundleAdjustmentState{};
  collect_inertial_scope(job.local, job.ba);
  job.keyframe = current;
  job.frame_index = keyframes.back().frame.index;
  job.running = true;
  summary->local_mapping_thread = true;
  job.group.run([this] {
    const auto start = Clock::now();
    mapping_job.solved = solve_bundle_adjustment(mapping_job.local, 5, 10, mapping_job.ba);
    mapping_job.seconds = seconds_since(start);
  });
}

// Waits for the job, applies its bundle adjustment, then keyframe culling and loop closing
// (finish_keyframe; loops and merges are reported on `result`, the frame being tracked). The
// last frame, when it is the job's keyframe, takes the keyframe's adjusted pose and points, as
// ORB-SLAM2's UpdateLastFrame re-anchors the last frame on its reference keyframe.
void VisualSlam::Impl::join_local_mapping(FrameResult* result) {
  LocalMappingJob& job = mapping_job;
  if (!job.running) return;
  job.group.wait();
  job.running = false;
  if (job.solved) apply_bundle_adjustment(job.local, job.ba);
  ++summary->local_bas;
  summary->local_ba_s += job.seconds;
  FrameResult unused;
  finish_keyframe(result != nullptr ? *result : unused);
  const KeyFrame& kf = keyframes[static_cast<std::size_t>(job.keyframe)];
  if (have_last && !kf.bad && last.index == job.frame_index) {
    last.T_world_camera = kf.frame.T_world_camera;
    last.map_point = kf.frame.map_point;
    T_world_last_tracked = last.T_world_camera;
    // ... and the IMU's state at that frame the keyframe's adjusted pose and velocity.
    if (have_imu_state && kf.has_imu_state && !job.ba.chain.empty() && imu_state_time == kf.frame.time) {
      imu_state.T_world_body = kf.frame.T_world_camera * options.inertial.T_body_camera.inverse();
      imu_state.v_world_mps = kf.v_world_mps;
    }
  }
  job.ba = BundleAdjustmentState{};
}

// After a keyframe's bundle adjustment: keyframe culling, then loop closing or a merge.
void VisualSlam::Impl::finish_keyframe(FrameResult& result) {
  if (options.keyframe_culling && kind != io::SequenceKind::kMonocular) cull_keyframes();
  detect_and_close_loop(result);
  if (!result.loop_closed) merge_with_recent(result);
}

// ORB-SLAM2 Optimizer::LocalBundleAdjustment, within the keyframe's frame.
void VisualSlam::Impl::local_bundle_adjustment() {
  const auto start = Clock::now();
  const std::set<int> local = local_ba_keyframes();
  BundleAdjustmentState ba;
  collect_inertial_scope(local, ba);
  if (solve_bundle_adjustment(local, 5, 10, ba)) apply_bundle_adjustment(local, ba);
  ++summary->local_bas;
  summary->local_ba_s += seconds_since(start);
}

// Bundle adjustment on the engine of the keyframes `local` (free, but anchors_segment's) and every
// point they see, the other keyframes that see those points fixed; `first` LM iterations with
// Huber, chi^2 outliers removed, `second` more without the kernel, outlier observations erased.
void VisualSlam::Impl::bundle_adjustment(const std::set<int>& local, int first, int second_iterations) {
  BundleAdjustmentState ba;
  if (solve_bundle_adjustment(local, first, second_iterations, ba)) apply_bundle_adjustment(local, ba);
}

bool VisualSlam::Impl::solve_bundle_adjustment(const std::set<int>& local, int first, int second_iterations, BundleAdjustmentState& ba) const {
  collect_bundle_adjustment_scope(local, ba);
  if (local.size() < 2 && ba.fixed.empty()) return false;
  backend::LeastSquaresProblem problem;
  add_bundle_adjustment_variables(local, ba, problem);
  ba.is_outlier.assign(ba.edges.size(), 0);
  add_bundle_adjustment_factors(ba, problem, true);
  add_inertial_factors(ba, problem);
  backend::LeastSquaresOptions lso;
  lso.linear_solver = backend::LinearSolverType::kSparseSchur;
  lso.max_iterations = first;
  lso.threads = 1;
  backend::solve(problem, lso);
  classify_bundle_adjustment_edges(ba);
  bundle_adjustment_second_pass(ba, lso, second_iterations);
  classify_bundle_adjustment_edges(ba);
  return true;
}

// The bundle adjustment's scope: every good point the keyframes `local` see, and the other
// keyframes that see those points (held fixed).
void VisualSlam::Impl::collect_bundle_adjustment_scope(const std::set<int>& local, BundleAdjustmentState& ba) const {
  std::set<int>& local_points = ba.local_points;
  for (const int kf : local) {
    for (const int id : keyframes[static_cast<std::size_t>(kf)].frame.map_point) {
      if (id >= 0 && !points[static_cast<std::size_t>(id)].bad) local_points.insert(id);
    }
  }
  std::set<int>& fixed = ba.fixed;
  for (const int id : local_points) {
    for (const auto& [kf, idx] : points[static_cast<std::size_t>(id)].observations) {
      if (!local.count(kf)) fixed.insert(kf);
    }
  }
}

// The first pass's variables: the local keyframes' poses (free but anchors_segment's), the fixed
// keyframes' poses, then each point (eliminated by the Schur complement) with its observations.
void VisualSlam::Impl::add_bundle_adjustment_variables(const std::set<int>& local, BundleAdjustmentState& ba, backend::LeastSquaresProblem& problem) const {
  std::map<int, std::array<double, 7>>& pose_values = ba.pose_values;
  std::map<int, int>& pose_var = ba.pose_var;
  auto add_pose = [&](int kf, bool constant) {
    auto& v = pose_values[kf];
    backend::se3_to_values(keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera, v.data());
    pose_var[kf] = problem.add_variable(v.data(), backend::se3_manifold());
    if (constant || anchors_segment(kf)) problem.set_constant(pose_var[kf]);
  };
  for (const int kf : local) add_pose(kf, false);
  for (const int kf : ba.fixed) add_pose(kf, true);
  ba.point_values.reserve(ba.local_points.size());
  for (const int id : ba.local_points) {
    ba.point_values[id] = points[static_cast<std::size_t>(id)].p_world;
  }
  for (const int id : ba.local_points) {
    ba.point_var[id] = problem.add_variable(ba.point_values[id].data(), backend::euclidean_manifold(3), backend::VariableGroup::kEliminate);
    for (const auto& [kf, idx] : points[static_cast<std::size_t>(id)].observations) ba.edges.push_back({id, kf, idx});
  }
}

// One reprojection factor per observation not marked an outlier, scaled by its level's
// information, with Huber at the chi^2 threshold when `robust`.
void VisualSlam::Impl::add_bundle_adjustment_factors(BundleAdjustmentState& ba, backend::LeastSquaresProblem& p, bool robust) const {
  const std::vector<char>& is_outlier = ba.is_outlier;
  for (std::size_t e = 0; e < ba.edges.size(); ++e) {
    if (is_outlier[e]) continue;
    const BundleAdjustmentState::Edge& edge = ba.edges[e];
    const FrameData& f = keyframes[static_cast<std::size_t>(edge.kf)].frame;
    const auto i = static_cast<std::size_t>(edge.idx);
    const bool stereo = f.u_right[i] >= 0;
    backend::FactorLoss loss;
    if (robust) loss = {backend::RobustKernel::kHuber, std::sqrt(stereo ? options.chi2_stereo : options.chi2_mono)};
    p.add_factor(std::make_unique<ScaledFactor>(observation_factor(f, i), 1.0 / scales[static_cast<std::size_t>(f.keypoints[i].octave)]),
                 {ba.pose_var[edge.kf], ba.point_var[edge.point]}, loss);
  }
}

// Each observation marked an outlier when its chi^2 at the current estimate exceeds the
// threshold (stereo or monocular).
void VisualSlam::Impl::classify_bundle_adjustment_edges(BundleAdjustmentState& ba) const {
  using Edge = BundleAdjustmentState::Edge;
  auto edge_chi2 = [&](const Edge& edge, const core::SE3& T_wc, const Eigen::Vector3d& p_world) {
    return chi2(keyframes[static_cast<std::size_t>(edge.kf)].frame, static_cast<std::size_t>(edge.idx), T_wc.inverse(), p_world);
  };
  for (std::size_t e = 0; e < ba.edges.size(); ++e) {
    const Edge& edge = ba.edges[e];
    const FrameData& f = keyframes[static_cast<std::size_t>(edge.kf)].frame;
    const double threshold = f.u_right[static_cast<std::size_t>(edge.idx)] >= 0 ? options.chi2_stereo : options.chi2_mono;
    ba.is_outlier[e] = edge_chi2(edge, backend::se3_from_values(ba.pose_values[edge.kf].data()), ba.point_values[edge.point]) > threshold ? 1 : 0;
  }
}

// The second pass without the outliers and without the robust kernel, from where the first
// ended (ORB-SLAM2 sets the outliers' level to 1 and removes the kernels).
void VisualSlam::Impl::bundle_adjustment_second_pass(BundleAdjustmentState& ba, backend::LeastSquaresOptions& lso, int second_iterations) const {
  backend::LeastSquaresProblem second;
  std::map<int, int> second_pose;
  for (auto& [kf, v] : ba.pose_values) {
    second_pose[kf] = second.add_variable(v.data(), backend::se3_manifold());
    if (ba.fixed.count(kf) || anchors_segment(kf)) second.set_constant(second_pose[kf]);
  }
  std::swap(ba.pose_var, second_pose);
  for (const int id : ba.local_points) {
    ba.point_var[id] = second.add_variable(ba.point_values[id].data(), backend::euclidean_manifold(3), backend::VariableGroup::kEliminate);
  }
  add_bundle_adjustment_factors(ba, second, false);
  add_inertial_factors(ba, second);
  lso.max_iterations = std::max(1, second_iterations);
  if (second_iterations > 0) backend::solve(second, lso);
}

// The outlier observations erased; the local keyframes (but anchors_segment's) and the points
// that are still good take the estimate.
void VisualSlam::Impl::apply_bundle_adjustment(const std::set<int>& local, BundleAdjustmentState& ba) {
  for (std::size_t e = 0; e < ba.edges.size(); ++e) {
    if (ba.is_outlier[e]) erase_observation(ba.edges[e].point, ba.edges[e].kf);
  }
  for (const int kf : local) {
    if (!anchors_segment(kf)) keyframes[static_cast<std::size_t>(kf)].frame.T_world_camera = backend::se3_from_values(ba.pose_values[kf].data());
  }
  if (!ba.chain.empty()) {
    ++summary->inertial_local_bas;
    summary->inertial_local_ba_factors += ba.links.size();
  }
  for (const int kf : ba.chain) {
    KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
    k.v_world_mps = ba.velocity_values[kf];
    k.imu_bias = inertial::bias_from_values(ba.bias_values[kf].data());
  }
  for (const int id : ba.local_points) {
    MapPoint& mp = points[static_cast<std::size_t>(id)];
    if (mp.bad) continue;
    mp.p_world = ba.point_values[id];
    update_normal_and_depth(mp);
  }
}

// The keyframes the IMU joins in a local BA (ORB-SLAM3 LocalInertialBA's temporal window): from
// the newest keyframe back through the good keyframes of its segment, while each is in the local
// window, has a velocity and biases (KeyFrame::has_imu_state) and the IMU readings cover the
// interval to the next; not past a segment's first keyframe. Nothing without an initialised IMU,
// with inertial.local_ba off, or while the monocular scale is judged drifted.
void VisualSlam::Impl::collect_inertial_scope(const std::set<int>& local, BundleAdjustmentState& ba) const {
  const VisualInertialOptions& o = options.inertial;
  const int seg = find(segment);
  if (!o.enabled || !o.local_ba || !imu_initialised || scale_drifted || seg != inertial_segment) return;
  std::vector<int> chain;
  std::vector<inertial::PreintegratedImu> links;
  for (int kf = static_cast<int>(keyframes.size()) - 1; kf >= 0; --kf) {
    const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
    if (k.bad || find(k.segment) != seg) continue;
    if (!local.count(kf) || !k.has_imu_state) break;
    if (!chain.empty()) {
      const KeyFrame& next = keyframes[static_cast<std::size_t>(chain.back())];
      inertial::PreintegratedImu preintegrated(o.noise, k.imu_bias);
      if (!inertial::integrate_interval(imu_samples, k.frame.time, next.frame.time, preintegrated) || !(preintegrated.delta_time_s() > 0.0)) break;
      preintegrated.add_covariance(inertial::hold_error_covariance(imu_samples, k.frame.time, next.frame.time));
      links.push_back(std::move(preintegrated));
    }
    chain.push_back(kf);
    if (k.starts_segment) break;
  }
  if (chain.size() < 2) return;
  std::reverse(chain.begin(), chain.end());
  std::reverse(links.begin(), links.end());
  for (const int kf : chain) {
    const KeyFrame& k = keyframes[static_cast<std::size_t>(kf)];
    ba.velocity_values[kf] = k.v_world_mps;
    ba.bias_values[kf] = inertial::to_values(k.imu_bias);
  }
  ba.oldest_bias_prior = ba.bias_values[chain.front()];
  ba.chain = std::move(chain);
  ba.links = std::move(links);
  ba.gravity_world = gravity_world;
}

// The chain's velocity and bias variables and, between consecutive keyframes, the IMU factor on
// their camera poses ([F] (45) through the camera's extrinsic; SensorPoseImuFactor) and the bias
// random walk ([F] (47)); the oldest keyframe's biases held near their estimate (0.01 rad/s,
// 0.1 m/s^2: ORB-SLAM3 fixes the keyframe before its window instead, whose state cairn does not
// keep). The pose variables are the bundle adjustment's (every chain keyframe is local).
void VisualSlam::Impl::add_inertial_factors(BundleAdjustmentState& ba, backend::LeastSquaresProblem& p) const {
  if (ba.chain.size() < 2) return;
  const VisualInertialOptions& o = options.inertial;
  for (const int kf : ba.chain) {
    ba.velocity_var[kf] = p.add_variable(ba.velocity_values[kf].data(), backend::euclidean_manifold(3));
    ba.bias_var[kf] = p.add_variable(ba.bias_values[kf].data(), backend::euclidean_manifold(6));
  }
  Eigen::Matrix<double, 6, 1> prior_sigma;
  prior_sigma << 0.01, 0.01, 0.01, 0.1, 0.1, 0.1;
  const int oldest = ba.chain.front();
  p.add_factor(std::make_unique<inertial::VectorPriorFactor<6>>(ba.oldest_bias_prior, prior_sigma.cwiseAbs2().asDiagonal().toDenseMatrix()),
               {ba.bias_var[oldest]});
  for (std::size_t k = 0; k + 1 < ba.chain.size(); ++k) {
    const int a = ba.chain[k], b = ba.chain[k + 1];
    p.add_factor(std::make_unique<inertial::SensorPoseImuFactor>(inertial::ImuFactor(ba.links[k], ba.gravity_world), o.T_body_camera),
                 {ba.pose_var[a], ba.velocity_var[a], ba.pose_var[b], ba.velocity_var[b], ba.bias_var[a]},
                 backend::FactorLoss{backend::RobustKernel::kHuber, std::sqrt(16.92)});
    p.add_factor(std::make_unique<inertial::BiasRandomWalkFactor>(o.noise, ba.links[k].delta_time_s()), {ba.bias_var[a], ba.bias_var[b]});
  }
}

}  // namespace cairn::vslam
