// Loop closing after ORB-SLAM2 (LoopClosing.cc) and the merging of map segments after ORB-SLAM3 (Campos et al. 2021): bag-of-words candidates with consistency, SE(3) verification, essential-graph correction (in 4 DoF for a visual-inertial map), point fusion.
// The state and the declarations: slam_state.hpp.

#include "cairn/vslam/slam_state.hpp"

#include <Eigen/Geometry>
#include <array>
#include <cstdio>
#include <limits>
#include <optional>
#include <random>

#include "cairn/backend/relative_pose_factor.hpp"
#include "cairn/backend/sim3_factors.hpp"
#include "cairn/backend/yaw_translation.hpp"

namespace cairn::vslam {

// Replaces point `old_id` by `new_id` everywhere (ORB-SLAM2 MapPoint::Replace): its
// observations move to the new point where the keyframe does not see that one already.
void VisualSlam::Impl::replace_point(int old_id, int new_id) {
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

// The points of the candidate and its 10 most covisible keyframes projected into the probe at
// its pose (3 px x 2.5 or 4 x level scale), then the motion-only BA: the loop's inlier matches,
// at least loop_min_matches (ORB-SLAM2 ComputeSim3: 40) for the loop to stand.
bool VisualSlam::Impl::match_candidate_neighbourhood(int candidate, FrameData& probe, LoopRecord& record) {
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

// Geometric verification of a loop candidate (stereo / RGB-D: SE(3), ORB-SLAM2 ComputeSim3
// with the scale fixed): the keyframe's keypoints matched to the candidate's points, a PnP
// RANSAC pose, the motion-only BA, then the points of the candidate and its covisible
// keyframes projected at that pose and the BA again. `probe` gets the keyframe at the pose
// the candidate's part of the map gives it, with its matches to that part.
bool VisualSlam::Impl::verify_loop(int current, int candidate, LoopRecord& record, FrameData& probe, bool drift_guard) {
  if (kind == io::SequenceKind::kMonocular) return verify_loop_sim3(current, candidate, record, probe, drift_guard);
  probe = keyframes[static_cast<std::size_t>(current)].frame;
  std::fill(probe.map_point.begin(), probe.map_point.end(), -1);
  std::fill(probe.outlier.begin(), probe.outlier.end(), 0);
  const KeyFrame& query = keyframes[static_cast<std::size_t>(current)];
  const int matches = match_to_keyframe(probe, query.nodes.size() == probe.size() ? &query.nodes : nullptr, keyframes[static_cast<std::size_t>(candidate)]);
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
  if (!match_candidate_neighbourhood(candidate, probe, record)) return false;
  // The correction the loop asks for, against the drift the keyframes between the two could
  // have gathered (cairn's guard against look-alike places, as slam2d's loop windows: a true
  // loop moves the keyframe by what odometry drifted, an aliased one by the distance between
  // the look-alikes). Within one segment only: a merge has no such bound.
  const core::SE3 change = keyframes[static_cast<std::size_t>(current)].frame.T_world_camera.inverse() * probe.T_world_camera;
  record.correction_m = change.translation().norm();
  record.correction_deg = Eigen::AngleAxisd(change.rotation_matrix()).angle() * 180.0 / 3.14159265358979323846;
  if (drift_guard && segment_of(candidate) == segment_of(current)) {
    const double travelled = travelled_between(candidate, current);
    const double allowed_m = options.loop_drift_floor_m + options.loop_drift_fraction * travelled;
    const double allowed_deg = options.loop_drift_floor_deg + options.loop_drift_deg_per_m * travelled;
    if (record.correction_m > allowed_m || record.correction_deg > allowed_deg) {
      record.reason = "correction " + std::to_string(record.correction_m) + " m / " + std::to_string(record.correction_deg) +
                      " deg exceeds the drift possible over the " + std::to_string(travelled) + " m travelled since the candidate (" +
                      std::to_string(allowed_m) + " m / " + std::to_string(allowed_deg) + " deg): a look-alike place";
      return false;
    }
  }
  return true;
}

namespace {

// A match of the Sim(3) verification with a point on both sides: the keypoint in the keyframe,
// the keypoint of the point in the candidate, the candidate's point, and the two points in
// their cameras' frames (x1 = S_12 x2 when the similarity holds).
struct Sim3Pair {
  std::size_t i, j;  // keypoint in the keyframe, keypoint of the point in the candidate
  int point;         // the candidate's point
  Eigen::Vector3d x1, x2;
};

// The probe's matches to the candidate's points where the keyframe's keypoint holds a good point
// of its own (another than the match's), with both points in their cameras' frames.
std::vector<Sim3Pair> sim3_pairs(const std::vector<MapPoint>& points, int candidate, const FrameData& probe, const FrameData& query_frame,
                                 const core::SE3& T1_cw, const core::SE3& T2_cw) {
  std::vector<Sim3Pair> pairs;
  for (std::size_t i = 0; i < probe.size(); ++i) {
    const int theirs = probe.map_point[i], own = query_frame.map_point[i];
    if (theirs < 0 || own < 0 || own == theirs || points[static_cast<std::size_t>(own)].bad) continue;
    const auto it = points[static_cast<std::size_t>(theirs)].observations.find(candidate);
    if (it == points[static_cast<std::size_t>(theirs)].observations.end()) continue;
    pairs.push_back({i, static_cast<std::size_t>(it->second), theirs, T1_cw * points[static_cast<std::size_t>(own)].p_world,
                     T2_cw * points[static_cast<std::size_t>(theirs)].p_world});
  }
  return pairs;
}

// RANSAC over the pairs (300 iterations of 3, seeded by the two keyframes), Horn's closed form
// with scale as Umeyama 1991 writes it; an inlier's projections both within chi^2 9.21 of their
// keypoints; the best set refitted. best gets S_12, best_in the inliers; returns their count.
int sim3_ransac(const io::CameraCalibration& camera, const std::vector<double>& inv_sigma2, const FrameData& query_frame, const FrameData& other_frame,
                const std::vector<Sim3Pair>& pairs, int current, int candidate, core::Sim3& best, std::vector<char>& best_in) {
  const auto pixel_error2 = [&](const FrameData& f, std::size_t k, const Eigen::Vector3d& x) {
    if (!(x.z() > 1e-9)) return std::numeric_limits<double>::infinity();
    const double du = camera.fx * x.x() / x.z() + camera.cx - f.undistorted[k].x();
    const double dv = camera.fy * x.y() / x.z() + camera.cy - f.undistorted[k].y();
    return (du * du + dv * dv) * inv_sigma2[static_cast<std::size_t>(f.keypoints[k].octave)];
  };
  const auto count_inliers = [&](const core::Sim3& S12, std::vector<char>& in) {
    const core::Sim3 S21 = S12.inverse();
    int n = 0;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      in[k] = pixel_error2(query_frame, pairs[k].i, S12 * pairs[k].x2) < 9.21 && pixel_error2(other_frame, pairs[k].j, S21 * pairs[k].x1) < 9.21;
      n += in[k] ? 1 : 0;
    }
    return n;
  };
  const auto fit = [&](const std::vector<std::size_t>& use, core::Sim3& S12) {
    Eigen::Matrix3Xd src(3, static_cast<Eigen::Index>(use.size())), dst(3, static_cast<Eigen::Index>(use.size()));
    for (std::size_t k = 0; k < use.size(); ++k) {
      src.col(static_cast<Eigen::Index>(k)) = pairs[use[k]].x2;
      dst.col(static_cast<Eigen::Index>(k)) = pairs[use[k]].x1;
    }
    const Eigen::Matrix4d M = Eigen::umeyama(src, dst, true);
    if (!M.allFinite() || !(M.topLeftCorner<3, 3>().determinant() > 1e-12)) return false;
    S12 = core::Sim3::from_matrix(M);
    return true;
  };
  std::mt19937 rng(static_cast<std::uint32_t>(current) * 7919u + static_cast<std::uint32_t>(candidate));
  std::uniform_int_distribution<std::size_t> pick(0, pairs.size() - 1);
  std::vector<char> in(pairs.size());
  int best_count = 0;
  for (int iteration = 0; iteration < 300; ++iteration) {
    std::vector<std::size_t> sample{pick(rng), pick(rng), pick(rng)};
    if (sample[0] == sample[1] || sample[0] == sample[2] || sample[1] == sample[2]) continue;
    core::Sim3 S12;
    if (!fit(sample, S12)) continue;
    const int n = count_inliers(S12, in);
    if (n > best_count) {
      best_count = n;
      best = S12;
      best_in = in;
    }
  }
  if (best_count >= 3) {
    std::vector<std::size_t> use;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (best_in[k]) use.push_back(k);
    }
    core::Sim3 refit;
    if (fit(use, refit)) {
      const int n = count_inliers(refit, in);
      if (n >= best_count) {
        best_count = n;
        best = refit;
        best_in = in;
      }
    }
  }
  return best_count;
}

}  // namespace

// Monocular verification: Sim(3), the scale having drifted (ORB-SLAM2 LoopClosing::ComputeSim3
// and Sim3Solver; Mur-Artal & Tardos, T-RO 2015, Sec. VII-B). The keyframe's keypoints are
// matched to the candidate's points by descriptor; where the keypoint holds a point of its own,
// the pair gives two 3D points, one in each camera's frame. RANSAC (300 iterations, 3 pairs,
// Horn's closed form with scale as Umeyama 1991 writes it) finds S_12 with x1 = S_12 x2; a pair
// is an inlier when both projections (x2 into image 1 by S_12, x1 into image 2 by S_12^-1)
// fall within chi^2 9.21 of the keypoints (ORB-SLAM2's threshold). The best set is refitted.
// Then the candidate's neighbourhood is projected at the similarity's rigid equivalent (R,
// t / s) and the motion-only BA run as for SE(3). The drift guard bounds the rotation only: the
// map's unit drifts, so a distance bound would mean nothing.
bool VisualSlam::Impl::verify_loop_sim3(int current, int candidate, LoopRecord& record, FrameData& probe, bool drift_guard) {
  const KeyFrame& query = keyframes[static_cast<std::size_t>(current)];
  const KeyFrame& other = keyframes[static_cast<std::size_t>(candidate)];
  probe = query.frame;
  std::fill(probe.map_point.begin(), probe.map_point.end(), -1);
  std::fill(probe.outlier.begin(), probe.outlier.end(), 0);
  const int matches = match_to_keyframe(probe, query.nodes.size() == probe.size() ? &query.nodes : nullptr, other);
  if (matches < options.loop_min_pnp_inliers) {
    record.reason = std::to_string(matches) + " descriptor matches to the candidate's points (< " + std::to_string(options.loop_min_pnp_inliers) + ")";
    return false;
  }
  const core::SE3 T1_cw = query.frame.T_world_camera.inverse(), T2_cw = other.frame.T_world_camera.inverse();
  const std::vector<Sim3Pair> pairs = sim3_pairs(points, candidate, probe, query.frame, T1_cw, T2_cw);
  const auto pair_count = static_cast<int>(pairs.size());
  if (pair_count < options.loop_min_pnp_inliers) {
    record.reason = std::to_string(pair_count) + " matches with a point on both sides (< " + std::to_string(options.loop_min_pnp_inliers) + ")";
    return false;
  }
  std::vector<char> best_in;
  core::Sim3 best;
  const int best_count = sim3_ransac(camera, inv_sigma2, query.frame, other.frame, pairs, current, candidate, best, best_in);
  record.pnp_inliers = best_count;
  if (best_count < options.loop_min_pnp_inliers) {
    record.reason = "Sim(3) RANSAC: " + std::to_string(best_count) + " inliers of " + std::to_string(pair_count) + " (< " +
                    std::to_string(options.loop_min_pnp_inliers) + ")";
    return false;
  }
  record.scale = best.scale();
  // The keyframe in the candidate's map: S_1w = S_12 S_2w, whose rigid equivalent (R, t / s) is
  // the camera pose the projection and the BA start from.
  const core::Sim3 S1w = best * core::Sim3(T2_cw);
  probe.T_world_camera = core::SE3(S1w.so3(), S1w.translation() / S1w.scale()).inverse();
  std::fill(probe.map_point.begin(), probe.map_point.end(), -1);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    if (best_in[k]) probe.map_point[pairs[k].i] = pairs[k].point;
  }
  if (!match_candidate_neighbourhood(candidate, probe, record)) return false;
  return sim3_within_drift(current, candidate, record, probe, drift_guard);
}

// The Sim(3) verification's correction (in the map's drifting unit) and, with drift_guard within
// one segment, its rotation against the drift the keyframes between could have gathered; false
// (with record.reason) beyond it: a look-alike place.
bool VisualSlam::Impl::sim3_within_drift(int current, int candidate, LoopRecord& record, const FrameData& probe, bool drift_guard) const {
  const KeyFrame& query = keyframes[static_cast<std::size_t>(current)];
  const core::SE3 change = query.frame.T_world_camera.inverse() * probe.T_world_camera;
  record.correction_m = change.translation().norm();  // in the map's (drifting) unit
  record.correction_deg = Eigen::AngleAxisd(change.rotation_matrix()).angle() * 180.0 / 3.14159265358979323846;
  if (drift_guard && segment_of(candidate) == segment_of(current)) {
    const double travelled = travelled_between(candidate, current);
    const double allowed_deg = options.loop_drift_floor_deg + options.loop_drift_deg_per_m * travelled;
    if (record.correction_deg > allowed_deg) {
      record.reason = "correction " + std::to_string(record.correction_deg) + " deg exceeds the rotation drift possible over the " +
                      std::to_string(travelled) + " map units travelled since the candidate (" + std::to_string(allowed_deg) +
                      " deg): a look-alike place";
      return false;
    }
  }
  return true;
}

// The uniqueness test of a loop or merge. ORB-SLAM2's DetectLoop / ComputeSim3 close the loop
// with the first consistent candidate that verifies; two look-alike places (identical rooms)
// both verify, and the drift bound above only catches a look-alike within the segment being
// tracked, not a merge and not a candidate the drift could reach. So every other keyframe the
// database proposed is verified as well (the same verification, without the drift bound): if
// one verifies at another place (distinct_places: farther apart than drift between the two
// could explain, or in another unmerged segment), the view is explained in two places and the
// loop is refused. The same rule as a relocalisation's (tracking.cpp relocalisation_rival,
// where it is argued) and the 2D localiser's (slam2d/localization.cpp other_fitting_place).
std::string VisualSlam::Impl::loop_rival(int current, int candidate, const LoopRecord& record, const FrameData& probe,
                                         const std::vector<int>& rivals) {
  for (const int rival : rivals) {
    // A rival in the querying keyframe's own segment, when the candidate lies in another, is the
    // segment seeing itself: not comparable with the merge.
    if (rival == candidate || rival == current) continue;
    if (segment_of(rival) == segment_of(current) && segment_of(candidate) != segment_of(current)) continue;
    LoopRecord other;
    FrameData other_probe;
    if (!verify_loop(current, rival, other, other_probe, false)) continue;
    if (!distinct_places(candidate, probe.T_world_camera, rival, other_probe.T_world_camera)) continue;
    char where[64];
    if (segment_of(rival) == segment_of(candidate)) {
      std::snprintf(where, sizeof where, "%.2f m from this one's",
                    (probe.T_world_camera.inverse() * other_probe.T_world_camera).translation().norm());
    } else {
      std::snprintf(where, sizeof where, "in map segment %d", segment_of(rival));
    }
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, "ambiguous: keyframe %d verifies too (%d inlier matches against %d) at a place %s", rival,
                  other.matches, record.matches, where);
    return buffer;
  }
  return "";
}

// Loop correction (ORB-SLAM2 CorrectLoop, stereo: SE(3)): the pose graph of every keyframe
// (consecutive keyframes, covisibility edges of >= 100 shared points, the loop edge; unit
// information as ORB-SLAM2's essential graph; keyframe 0 fixed) optimised on the back end;
// points follow their reference keyframe; the keyframe's loop matches fuse its points into the
// old ones; then a global bundle adjustment. Monocular: the same over Sim(3) (correct_poses_sim3).
// With an IMU (corrects_in_four_dof): in 4 DoF, every keyframe keeping its gravity direction
// (correct_poses_4dof), the scale of a monocular-inertial map held; the IMU's states follow.
void VisualSlam::Impl::correct_loop(int current, int candidate, const FrameData& probe, double scale) {
  std::vector<core::SE3> old_poses(keyframes.size());
  for (std::size_t k = 0; k < keyframes.size(); ++k) old_poses[k] = keyframes[k].frame.T_world_camera;
  const bool four_dof = corrects_in_four_dof(current, candidate);
  const bool similarity = kind == io::SequenceKind::kMonocular && !four_dof;
  if (four_dof) {
    correct_poses_4dof(current, candidate, probe);
    ++summary->loops_corrected_in_4dof;
  } else if (similarity) {
    correct_poses_sim3(current, candidate, probe, scale);
  } else {
    correct_poses_se3(current, candidate, probe);
  }
  move_inertial_states(old_poses, similarity);
  // A merge joins the two segments (the older keeps its id) before the global bundle
  // adjustment, so that the younger one's first keyframe no longer holds a gauge of its own.
  const int a = segment_of(current), b = segment_of(candidate);
  if (a != b) segment_parent[static_cast<std::size_t>(std::max(a, b))] = std::min(a, b);
  fuse_loop_and_adjust(current, probe);
}

// The essential graph's edges over the good keyframes (ORB-SLAM2 OptimizeEssentialGraph, without
// the spanning tree: consecutive keyframes stand in for it), each (a, b, weight): consecutive
// keyframes, and every earlier keyframe sharing >= 100 points. Into the first keyframe of a
// segment the consecutive link is only the motion model's guess across the lost stretch: a
// weight of 1e-6 keeps the graph connected without holding the segments where the guess put
// them. Both corrections measure the edges on the uncorrected poses.
std::vector<std::tuple<int, int, double>> VisualSlam::Impl::essential_graph_edges(const std::vector<int>& good) const {
  std::vector<std::tuple<int, int, double>> edges;
  // The consecutive chain runs within each segment (keyframes of two unmerged segments may
  // alternate after a relocalisation back into the older one: their relative pose means
  // nothing); a keyframe whose previous one lies in another segment is also linked to it at
  // 1e-6, which keeps the graph connected.
  std::map<int, int> last_of_segment;
  for (std::size_t g = 0; g < good.size(); ++g) {
    const int k = good[g];
    const int seg = segment_of(k);
    const auto it = last_of_segment.find(seg);
    if (it != last_of_segment.end()) edges.emplace_back(it->second, k, keyframes[static_cast<std::size_t>(k)].starts_segment ? 1e-6 : 1.0);
    if (g > 0 && (it == last_of_segment.end() || it->second != good[g - 1])) edges.emplace_back(good[g - 1], k, 1e-6);
    last_of_segment[seg] = k;
  }
  for (std::size_t g = 0; g < good.size(); ++g) {
    const int k = good[g];
    const int previous = g > 0 ? good[g - 1] : -1;
    for (const auto& [shared, other] : covisible(k, 100)) {
      if (other < previous) edges.emplace_back(other, k, 1.0);
    }
  }
  return edges;
}

void VisualSlam::Impl::correct_poses_se3(int current, int candidate, const FrameData& probe) {
  const std::size_t n = keyframes.size();
  std::vector<core::SE3> old_poses(n);
  for (std::size_t k = 0; k < n; ++k) old_poses[k] = keyframes[k].frame.T_world_camera;
  const core::SE3 T_loop = probe.T_world_camera;
  io::PoseGraph3D graph;
  // Culled keyframes are not in the graph; the chain below joins the good ones around them.
  std::vector<int> good;
  for (std::size_t k = 0; k < n; ++k) {
    if (keyframes[k].bad) continue;
    good.push_back(static_cast<int>(k));
    graph.vertices.push_back({static_cast<std::int64_t>(k), old_poses[k]});
  }
  auto add_edge = [&](int a, int b, const core::SE3& T_a_b, double weight = 1.0) {
    io::GraphEdge<core::SE3> e;
    e.from = a;
    e.to = b;
    e.T_from_to = T_a_b;
    e.information *= weight;
    graph.edges.push_back(e);
  };
  for (const auto& [a, b, weight] : essential_graph_edges(good)) {
    add_edge(a, b, old_poses[static_cast<std::size_t>(a)].inverse() * old_poses[static_cast<std::size_t>(b)], weight);
  }
  add_edge(candidate, current, old_poses[static_cast<std::size_t>(candidate)].inverse() * T_loop);
  graph.fixed.push_back(0);
  backend::Problem3D problem = backend::make_problem(graph, "vslam essential graph");
  backend::OptimizerOptions solver;
  solver.max_iterations = 20;
  solver.function_tolerance = 1e-9;
  solver.threads = 1;
  backend::optimize(problem, solver);
  for (const int k : good) keyframes[static_cast<std::size_t>(k)].frame.T_world_camera = problem.T_world_pose[static_cast<std::size_t>(problem.index_of(k))];
  follow_keyframe_correction(old_poses);
}

// Points and the last frame follow their reference keyframe's rigid correction.
void VisualSlam::Impl::follow_keyframe_correction(const std::vector<core::SE3>& old_poses) {
  for (MapPoint& mp : points) {
    if (mp.bad) continue;
    const auto r = static_cast<std::size_t>(mp.reference_keyframe);
    mp.p_world = keyframes[r].frame.T_world_camera * (old_poses[r].inverse() * mp.p_world);
  }
  if (reference_keyframe >= 0) {
    const auto r = static_cast<std::size_t>(reference_keyframe);
    last.T_world_camera = keyframes[r].frame.T_world_camera * (old_poses[r].inverse() * last.T_world_camera);
  }
}

// A visual-inertial map closing a loop within itself: the IMU initialised for the segment, its
// monocular scale not judged drifted, both keyframes in that segment, the option on. Roll and
// pitch are then observable (gravity), and the correction must not change them.
bool VisualSlam::Impl::corrects_in_four_dof(int current, int candidate) const {
  return options.inertial.enabled && options.inertial.four_dof_loops && imu_initialised && !scale_drifted &&
         gravity_world.norm() > 0.0 && segment_of(current) == inertial_segment && segment_of(candidate) == inertial_segment;
}

// The essential graph of correct_poses_se3 with every keyframe on a yaw-about-gravity and
// translation manifold (backend/yaw_translation.hpp; ORB-SLAM3 Optimizer::
// OptimizeEssentialGraph4DoF, VINS-Mono's 4-DoF pose graph, Qin et al. T-RO 2018 Sec. VIII-B):
// the edges keep their 6-DoF residuals, the keyframes move only in yaw and position, so each
// keeps its gravity direction; the loop's own roll and pitch stay in its residual. Keyframe 0 is
// fixed; a monocular-inertial map is metric, so no scale is estimated.
void VisualSlam::Impl::correct_poses_4dof(int current, int candidate, const FrameData& probe) {
  const std::size_t n = keyframes.size();
  std::vector<core::SE3> old_poses(n);
  for (std::size_t k = 0; k < n; ++k) old_poses[k] = keyframes[k].frame.T_world_camera;
  std::vector<int> good;
  for (std::size_t k = 0; k < n; ++k) {
    if (!keyframes[k].bad) good.push_back(static_cast<int>(k));
  }
  const backend::YawTranslationManifold manifold(-gravity_world);
  std::vector<std::array<double, 7>> values(n);
  std::vector<int> var(n, -1);
  backend::LeastSquaresProblem problem;
  for (const int k : good) {
    backend::se3_to_values(old_poses[static_cast<std::size_t>(k)], values[static_cast<std::size_t>(k)].data());
    var[static_cast<std::size_t>(k)] = problem.add_variable(values[static_cast<std::size_t>(k)].data(), manifold);
  }
  problem.set_constant(var[static_cast<std::size_t>(good.front())]);
  auto add_edge = [&](int a, int b, const core::SE3& T_a_b, double weight) {
    backend::PoseEdge<core::SE3> edge;
    edge.T_i_j = T_a_b;
    edge.sqrt_information *= std::sqrt(weight);
    problem.add_factor(std::make_unique<backend::YawTranslationAdapter>(std::make_unique<backend::RelativePoseFactor>(edge),
                                                                        std::vector<const backend::YawTranslationManifold*>{&manifold, &manifold}),
                       {var[static_cast<std::size_t>(a)], var[static_cast<std::size_t>(b)]});
  };
  for (const auto& [a, b, weight] : essential_graph_edges(good)) {
    add_edge(a, b, old_poses[static_cast<std::size_t>(a)].inverse() * old_poses[static_cast<std::size_t>(b)], weight);
  }
  add_edge(candidate, current, old_poses[static_cast<std::size_t>(candidate)].inverse() * probe.T_world_camera, 1.0);
  backend::LeastSquaresOptions lso;
  lso.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  lso.max_iterations = 20;
  lso.function_tolerance = 1e-9;
  lso.threads = 1;
  if (!backend::solve(problem, lso).is_solution_usable()) return;
  for (const int k : good) keyframes[static_cast<std::size_t>(k)].frame.T_world_camera = backend::se3_from_values(values[static_cast<std::size_t>(k)].data());
  follow_keyframe_correction(old_poses);
}

// After a correction the IMU's states follow: each keyframe's velocity turns as the keyframe
// turned, and the state at the last frame takes that frame's corrected pose, its velocity turned
// as its reference keyframe turned. A Sim(3) correction changes a monocular map's unit: there
// the states are dropped (the next inertial estimate gives them again).
void VisualSlam::Impl::move_inertial_states(const std::vector<core::SE3>& old_poses, bool similarity) {
  if (!options.inertial.enabled) return;
  for (std::size_t k = 0; k < old_poses.size(); ++k) {
    KeyFrame& kf = keyframes[k];
    if (!kf.has_imu_state) continue;
    if (similarity) {
      kf.has_imu_state = false;
    } else {
      kf.v_world_mps = (kf.frame.T_world_camera.so3() * old_poses[k].so3().inverse()) * kf.v_world_mps;
    }
  }
  if (!have_imu_state) return;
  if (similarity || reference_keyframe < 0 || !have_last || !(imu_state_time == last.time)) {
    have_imu_state = false;
    return;
  }
  const auto r = static_cast<std::size_t>(reference_keyframe);
  imu_state.T_world_body = last.T_world_camera * options.inertial.T_body_camera.inverse();
  imu_state.v_world_mps = (keyframes[r].frame.T_world_camera.so3() * old_poses[r].so3().inverse()) * imu_state.v_world_mps;
}

// What the stages of correct_poses_sim3 share.
struct VisualSlam::Impl::Sim3Correction {
  std::vector<core::SE3> old_poses;  // every keyframe's pose before the correction
  core::Sim3 S_cw_corrected;         // the keyframe's corrected similarity
  std::vector<core::Sim3> before;    // S_world_keyframe the graph starts from
  std::vector<core::Sim3> after;     // S_world_keyframe the graph ends at
  std::vector<int> connected;        // keyframes given a corrected similarity before the graph
  int held = 0;                      // the graph's fixed keyframe
  std::vector<int> corrected_by;     // per point, the keyframe that moved it before the graph (-1: none)
};

// Monocular loop correction over Sim(3) (ORB-SLAM2 LoopClosing::CorrectLoop and
// Optimizer::OptimizeEssentialGraph; Strasdat, Montiel & Davison, RSS 2010). The keyframe's
// corrected similarity S_cw = (s R', s t'), with (R', t') the rigid pose the verification found
// in the candidate's map and s the Sim(3) scale, is passed to its covisible keyframes through
// their rigid poses relative to it (S_kw = T_kc S_cw), and their points follow (X' = S_kw^-1
// T_kw X). The essential graph over Sim(3) (variables S_world_keyframe, backend/sim3_factors.hpp;
// consecutive keyframes and covisibility edges of >= 100 points with the uncorrected relative
// poses, the loop edge candidate -> keyframe with the corrected ones, unit information, the
// candidate fixed as in ORB-SLAM2; in a merge the younger segment is moved whole instead, and
// the older side's keyframe is fixed) then spreads the correction, scale included; each keyframe
// takes the rigid part (R, t) of its similarity, each point moves with the keyframe that
// corrected it or its reference: X' = S_after S_before^-1 X, and each frame's pose relative to
// its reference keyframe is scaled with it.
void VisualSlam::Impl::correct_poses_sim3(int current, int candidate, const FrameData& probe, double scale) {
  Sim3Correction c;
  const std::size_t n = keyframes.size();
  c.old_poses.resize(n);
  for (std::size_t k = 0; k < n; ++k) c.old_poses[k] = keyframes[k].frame.T_world_camera;
  const core::SE3 T_cw_found = probe.T_world_camera.inverse();
  c.S_cw_corrected = core::Sim3(T_cw_found.so3(), scale * T_cw_found.translation(), scale);
  c.before.resize(n);
  for (std::size_t k = 0; k < n; ++k) c.before[k] = core::Sim3(c.old_poses[k]);
  c.held = candidate;
  spread_loop_similarity(current, candidate, c);
  move_points_before_graph(c);
  optimise_sim3_essential_graph(current, candidate, c);
  apply_sim3_correction(c);
}

// The corrected similarity given, before the graph, to the keyframes around the loop: in a merge
// the younger segment's keyframes, moved whole; else the keyframe and its covisible keyframes.
void VisualSlam::Impl::spread_loop_similarity(int current, int candidate, Sim3Correction& c) const {
  const std::size_t n = keyframes.size();
  const std::vector<core::SE3>& old_poses = c.old_poses;
  const core::Sim3& S_cw_corrected = c.S_cw_corrected;
  std::vector<core::Sim3>& before = c.before;
  std::vector<int>& connected = c.connected;
  const core::SE3& T_wc = old_poses[static_cast<std::size_t>(current)];
  if (segment_of(candidate) != segment_of(current)) {
    // A merge (ORB-SLAM3 LoopClosing::MergeLocal): the younger segment (the larger id; the older
    // holds keyframe 0 or was there first), in its own frame and unit, is moved whole by the
    // similarity between the two maps' frames, then the graph spreads what remains. M maps the
    // current keyframe's world into the candidate's (S_cw_corrected^-1 T_cw), or the reverse.
    const bool move_current = segment_of(current) > segment_of(candidate);
    const int moved = move_current ? segment_of(current) : segment_of(candidate);
    const core::Sim3 M = move_current ? S_cw_corrected.inverse() * core::Sim3(T_wc.inverse()) : core::Sim3(T_wc) * S_cw_corrected;
    if (!move_current) c.held = current;
    for (std::size_t k = 0; k < n; ++k) {
      if (keyframes[k].bad || segment_of(static_cast<int>(k)) != moved) continue;
      connected.push_back(static_cast<int>(k));
      before[k] = M * core::Sim3(old_poses[k]);
    }
  } else {
    connected.push_back(current);
    for (const auto& [shared, k] : covisible(current, options.min_covisible_points)) {
      if (!keyframes[static_cast<std::size_t>(k)].bad && k != candidate) connected.push_back(k);
    }
    for (const int k : connected) {
      const core::Sim3 S_kw = core::Sim3(old_poses[static_cast<std::size_t>(k)].inverse() * T_wc) * S_cw_corrected;
      before[static_cast<std::size_t>(k)] = S_kw.inverse();
    }
  }
}

// The points of the connected keyframes follow them (X' = S_kw^-1 T_kw X), each with the first
// connected keyframe that sees it.
void VisualSlam::Impl::move_points_before_graph(Sim3Correction& c) {
  std::vector<int>& corrected_by = c.corrected_by;
  corrected_by.assign(points.size(), -1);
  for (const int k : c.connected) {
    for (const int id : keyframes[static_cast<std::size_t>(k)].frame.map_point) {
      if (id < 0 || points[static_cast<std::size_t>(id)].bad || corrected_by[static_cast<std::size_t>(id)] >= 0) continue;
      MapPoint& mp = points[static_cast<std::size_t>(id)];
      mp.p_world = c.before[static_cast<std::size_t>(k)] * (c.old_poses[static_cast<std::size_t>(k)].inverse() * mp.p_world);
      corrected_by[static_cast<std::size_t>(id)] = k;
    }
  }
}

// The essential graph over Sim(3) (backend/sim3_factors.hpp): its edges with the uncorrected
// relative poses, the loop edge candidate -> keyframe with the corrected ones, unit information,
// c.held fixed; each good keyframe takes the rigid part of its optimised similarity (c.after).
void VisualSlam::Impl::optimise_sim3_essential_graph(int current, int candidate, Sim3Correction& c) {
  const std::size_t n = keyframes.size();
  const std::vector<core::SE3>& old_poses = c.old_poses;
  const std::vector<core::Sim3>& before = c.before;
  std::vector<int> good;
  for (std::size_t k = 0; k < n; ++k) {
    if (!keyframes[k].bad) good.push_back(static_cast<int>(k));
  }
  backend::LeastSquaresProblem problem;
  std::vector<std::array<double, 8>> values(n);
  std::vector<int> var(n, -1);
  for (const int k : good) {
    backend::sim3_to_values(before[static_cast<std::size_t>(k)], values[static_cast<std::size_t>(k)].data());
    var[static_cast<std::size_t>(k)] = problem.add_variable(values[static_cast<std::size_t>(k)].data(), backend::sim3_manifold());
  }
  problem.set_constant(var[static_cast<std::size_t>(c.held)]);
  const auto add_edge = [&](int a, int b, const core::Sim3& S_a_b, double weight) {
    const backend::Sim3SquareRootInformation L = std::sqrt(weight) * backend::Sim3SquareRootInformation::Identity();
    problem.add_factor(std::make_unique<backend::Sim3RelativeFactor>(S_a_b, L), {var[static_cast<std::size_t>(a)], var[static_cast<std::size_t>(b)]});
  };
  for (const auto& [a, b, weight] : essential_graph_edges(good)) {
    add_edge(a, b, core::Sim3(old_poses[static_cast<std::size_t>(a)].inverse() * old_poses[static_cast<std::size_t>(b)]), weight);
  }
  add_edge(candidate, current, before[static_cast<std::size_t>(candidate)].inverse() * before[static_cast<std::size_t>(current)], 1.0);
  backend::LeastSquaresOptions lso;
  lso.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  lso.max_iterations = 20;
  lso.threads = 1;
  backend::solve(problem, lso);
  c.after = before;
  for (const int k : good) {
    c.after[static_cast<std::size_t>(k)] = backend::sim3_from_values(values[static_cast<std::size_t>(k)].data());
    keyframes[static_cast<std::size_t>(k)].frame.T_world_camera = c.after[static_cast<std::size_t>(k)].to_se3();
  }
}

// After the graph: each point moves with the keyframe that corrected it or its reference
// (X' = S_after S_before^-1 X), frames' poses relative to their reference keyframes are scaled,
// and the last frame moves with its reference keyframe.
void VisualSlam::Impl::apply_sim3_correction(const Sim3Correction& c) {
  const std::vector<core::SE3>& old_poses = c.old_poses;
  const std::vector<core::Sim3>& before = c.before;
  const std::vector<core::Sim3>& after = c.after;
  for (std::size_t id = 0; id < points.size(); ++id) {
    MapPoint& mp = points[id];
    if (mp.bad) continue;
    const auto r = static_cast<std::size_t>(c.corrected_by[id] >= 0 ? c.corrected_by[id] : mp.reference_keyframe);
    if (keyframes[r].bad) continue;
    mp.p_world = after[r] * (before[r].inverse() * mp.p_world);
    update_normal_and_depth(mp);
  }
  // Around keyframe k the map is now after[k] applied to its old camera coordinates, so a
  // frame's pose relative to its reference keyframe is scaled by after[k]'s scale as well (the
  // trajectory composes keyframe poses with these; ORB-SLAM2 leaves them unscaled).
  for (auto& [r, T_r_frame] : relative) {
    if (r < 0 || keyframes[static_cast<std::size_t>(r)].bad) continue;
    T_r_frame = core::SE3(T_r_frame.so3(), after[static_cast<std::size_t>(r)].scale() * T_r_frame.translation());
  }
  if (reference_keyframe >= 0) {
    const auto r = static_cast<std::size_t>(reference_keyframe);
    // The last frame's pose is in the old world, as the points were before the correction: it
    // moves as they did, by after[r] applied to its old camera coordinates (before[r] is the
    // corrected start of a keyframe that took the loop's similarity, not its old pose).
    const auto move = [&](const core::SE3& T) { return (after[r] * core::Sim3(old_poses[r].inverse() * T)).to_se3(); };
    last.T_world_camera = move(last.T_world_camera);
    T_world_last_tracked = move(T_world_last_tracked);
  }
}

// After either correction: the keyframe's keypoints matched to the old part of the map take its
// points (ORB-SLAM2 CorrectLoop's fusion of the loop matches), then a global bundle adjustment.
void VisualSlam::Impl::fuse_loop_and_adjust(int current, const FrameData& probe) {
  std::vector<int> good;
  for (std::size_t k = 0; k < keyframes.size(); ++k) {
    if (!keyframes[k].bad) good.push_back(static_cast<int>(k));
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
    all.insert(good.begin(), good.end());
    bundle_adjustment(all, 10, 10);
    ++summary->global_bas;
    summary->global_ba_s += seconds_since(start);
  }
}

// One loop or merge candidate (record.candidate; record.merge says whether it lies in another
// segment): verified, tested for uniqueness against `rivals`, and when it stands the map is
// corrected and the two segments joined (the older one keeps its id). The record gets its
// decision and reason (accepted: its matches and `accepted_reason`); accepted and ambiguous
// records go into the summary here, rejected ones are the caller's (a loop query keeps them
// all, a merge attempt only the closest).
VisualSlam::Impl::LoopOutcome VisualSlam::Impl::try_loop(int current, LoopRecord& record, const std::vector<int>& rivals,
                                                         const char* accepted_reason, FrameResult& result) {
  const int candidate = static_cast<int>(record.candidate);
  FrameData probe;
  if (!verify_loop(current, candidate, record, probe)) {
    record.decision = "rejected";
    return LoopOutcome::kRejected;
  }
  const std::string rival = loop_rival(current, candidate, record, probe, rivals);
  if (!rival.empty()) {
    record.decision = "rejected";
    record.reason = rival;
    summary->loops.push_back(record);
    ++summary->loops_ambiguous;
    return LoopOutcome::kAmbiguous;
  }
  record.decision = "accepted";
  record.reason = std::to_string(record.matches) + accepted_reason;
  correct_loop(current, candidate, probe, record.scale);
  if (record.merge) ++summary->maps_merged;
  summary->loops.push_back(record);
  ++summary->loops_accepted;
  result.loop_closed = true;
  return LoopOutcome::kAccepted;
}

// DetectLoop's candidates and their consistency: the database's results scoring at least
// min_score and sharing at least 80 % of the best one's words (not of the querying keyframe's
// segment when too_early), each with its covisibility group, consistent when the group shares a
// keyframe with a group of the previous query (consistent_groups, which it replaces, as it does
// pending_loop_candidates). Returns (score, candidate, consistency) of those consistent for
// loop_consistency keyframes, best score first.
std::vector<std::tuple<double, int, int>> VisualSlam::Impl::consistent_loop_candidates(int current, const std::vector<vision::BowDatabase::Result>& results,
                                                                                      double min_score, bool too_early) {
  int max_common = 0;
  for (const auto& r : results) max_common = std::max(max_common, r.common_words);
  std::vector<std::pair<std::set<int>, int>> groups;
  std::set<int> candidates_seen;
  std::vector<std::tuple<double, int, int>> consistent;  // score, candidate, consistency
  for (const auto& r : results) {
    if (r.score < min_score || r.common_words < 0.8 * max_common) continue;
    const int candidate = static_cast<int>(r.id);
    if (too_early && segment_of(candidate) == segment_of(current)) continue;
    candidates_seen.insert(candidate);
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
  pending_loop_candidates = std::move(candidates_seen);
  std::sort(consistent.begin(), consistent.end(), std::greater<>());
  return consistent;
}

// ORB-SLAM2 LoopClosing::DetectLoop: candidates from the database scoring at least as well as
// the keyframe's worst covisible neighbour and sharing at least 80 % of the best candidate's
// words, kept only when their covisibility group was also a candidate group for the previous
// loop_consistency - 1 keyframes; then verified, best score first.
void VisualSlam::Impl::detect_and_close_loop(FrameResult& result) {
  if (!options.vocabulary) return;
  const auto start = Clock::now();
  const int current = static_cast<int>(keyframes.size()) - 1;
  KeyFrame& kf = keyframes[static_cast<std::size_t>(current)];
  kf.bow = options.vocabulary->transform(kf.frame.descriptors, nullptr, &kf.nodes, bow_levels_up());
  // Loops within a segment wait for enough keyframes since the start and the last loop; a
  // merge with another segment may come at any keyframe.
  const bool too_early = current < 2 * options.loop_min_keyframes_apart || current < last_loop_keyframe + options.loop_min_keyframes_apart;
  bool other_segments = false;
  for (const KeyFrame& other : keyframes) other_segments = other_segments || (!other.bad && segment_of(other.id) != segment_of(current));
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
  std::vector<int> proposed;  // every keyframe the database returned: the rivals of the uniqueness test
  for (const auto& r : results) proposed.push_back(static_cast<int>(r.id));
  const std::vector<std::tuple<double, int, int>> consistent = consistent_loop_candidates(current, results, min_score, too_early);
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
    const LoopOutcome outcome = try_loop(current, record, proposed, " inlier matches to the candidate's neighbourhood", result);
    if (outcome == LoopOutcome::kRejected) {
      summary->loops.push_back(record);
      continue;
    }
    if (outcome == LoopOutcome::kAccepted) {
      last_loop_keyframe = current;
      consistent_groups.clear();
      pending_loop_candidates.clear();
    }
    break;
  }
  if (!result.loop_closed) verify_revisit(current, neighbours);
  summary->loop_s += seconds_since(start);
}

// A return that tracking closed by itself. ORB-SLAM2's DetectLoop leaves out the keyframes
// covisible with the query: when tracking the local map has already matched the old place's
// points (TUM fr1/desk: the keyframe at frame 97 shares about 100 points with frame 23's), there is
// no loop left to correct and nothing is reported. cairn reports it, verified: an old keyframe
// of the same segment (outside the last loop_min_keyframes_apart) that shares points with this
// one, and that some keyframe in between did not see (the place went out of view and came
// back), is verified as a loop candidate is (verify_loop, the drift bound included) and
// recorded with decision "revisit" and the correction the verification found; the map is left
// as it is. One candidate per keyframe (the one sharing most points), each old keyframe tried
// once, and none within loop_min_keyframes_apart keyframes of the last verified revisit. Not
// for monocular runs.
void VisualSlam::Impl::verify_revisit(int current, const std::vector<std::pair<int, int>>& neighbours) {
  // Monocular: the Sim(3) verification needs matches whose two sides are different points, and
  // a revisit's matches are the same points; there is nothing it could verify.
  if (kind == io::SequenceKind::kMonocular) return;
  if (last_revisit_keyframe >= 0 && current < last_revisit_keyframe + options.loop_min_keyframes_apart) return;
  int best = -1, best_shared = 0;
  for (const auto& [shared, k] : neighbours) {
    if (k > current - options.loop_min_keyframes_apart || shared <= best_shared || keyframes[static_cast<std::size_t>(k)].bad ||
        segment_of(k) != segment_of(current) || revisit_tried.count(k) > 0) {
      continue;
    }
    std::set<int> saw_it;
    for (const auto& [n, j] : covisible(k, options.min_covisible_points)) saw_it.insert(j);
    bool left_view = false;
    for (int j = k + 1; j < current && !left_view; ++j) {
      left_view = !keyframes[static_cast<std::size_t>(j)].bad && segment_of(j) == segment_of(current) && saw_it.count(j) == 0;
    }
    if (!left_view) continue;
    best = k;
    best_shared = shared;
  }
  if (best < 0) return;
  revisit_tried.insert(best);  // one verification per old keyframe, whatever its outcome
  const KeyFrame& kf = keyframes[static_cast<std::size_t>(current)];
  const KeyFrame& old = keyframes[static_cast<std::size_t>(best)];
  LoopRecord record;
  record.keyframe = static_cast<std::size_t>(current);
  record.candidate = static_cast<std::size_t>(best);
  record.frame = kf.frame.index;
  record.candidate_frame = old.frame.index;
  record.score = kf.bow.empty() || old.bow.empty() ? -1.0 : vision::Vocabulary::score(kf.bow, old.bow);
  FrameData probe;
  if (verify_loop(current, best, record, probe)) {
    char buffer[256];
    std::snprintf(buffer, sizeof buffer,
                  "joined by tracking (%d points shared); verified with %d inlier matches, %.3f m / %.2f deg from the tracked pose: "
                  "nothing to correct",
                  best_shared, record.matches, record.correction_m, record.correction_deg);
    record.decision = "revisit";
    record.reason = buffer;
    ++summary->revisits_verified;
    last_revisit_keyframe = current;
  } else {
    record.decision = "rejected";
    record.reason = "a revisit joined by tracking (" + std::to_string(best_shared) + " points shared) that did not verify: " + record.reason;
  }
  summary->loops.push_back(record);
}

// A young map segment (its first `merge_recent_keyframes_of_new_map` keyframes) tries to merge
// with the keyframes tracked last before it started, the place where tracking was lost (cairn's,
// as slam2d merges segments near the estimate; ORB-SLAM3 relies on place recognition alone):
// the newest keyframe verified against each of the 8 most recent keyframes of the other
// segments, as a loop is verified. Needs no vocabulary. The candidates are near in time, so a
// look-alike elsewhere is not among them.
void VisualSlam::Impl::merge_with_recent(FrameResult& result) {
  if (options.merge_recent_keyframes_of_new_map <= 0) return;
  const int current = static_cast<int>(keyframes.size()) - 1;
  const int own = segment_of(current);
  int age = 0;
  for (const KeyFrame& k : keyframes) age += segment_of(k.id) == own ? 1 : 0;
  if (age > options.merge_recent_keyframes_of_new_map) return;
  std::vector<int> candidates;
  for (int k = current - 1; k >= 0 && candidates.size() < 8; --k) {
    if (segment_of(k) != own && !keyframes[static_cast<std::size_t>(k)].bad) candidates.push_back(k);
  }
  if (candidates.empty()) return;
  const auto start = Clock::now();
  // The rivals of the uniqueness test: the other recent keyframes, and with a vocabulary the
  // keyframes the database ranks best for this one (a look-alike of the place tracking was lost
  // in may be elsewhere in the map).
  std::vector<int> rivals = candidates;
  const KeyFrame& kf = keyframes[static_cast<std::size_t>(current)];
  if (options.vocabulary && !kf.bow.empty()) {
    std::vector<std::uint32_t> exclude;
    for (const KeyFrame& k : keyframes) {
      if (segment_of(k.id) == own) exclude.push_back(static_cast<std::uint32_t>(k.id));
    }
    for (const auto& r : database.query(kf.bow, 20, exclude)) rivals.push_back(static_cast<int>(r.id));
  }
  std::optional<LoopRecord> best_rejected;
  for (const int candidate : candidates) {
    LoopRecord record;
    record.keyframe = static_cast<std::size_t>(current);
    record.candidate = static_cast<std::size_t>(candidate);
    record.frame = keyframes[static_cast<std::size_t>(current)].frame.index;
    record.candidate_frame = keyframes[static_cast<std::size_t>(candidate)].frame.index;
    record.score = -1.0;  // proposed by recency, not by the bag of words
    record.merge = true;
    ++summary->merge_attempts;
    if (try_loop(current, record, rivals, " inlier matches to the keyframes tracked last before this segment", result) != LoopOutcome::kRejected) {
      summary->loop_s += seconds_since(start);
      return;
    }
    if (!best_rejected || record.matches + record.pnp_inliers > best_rejected->matches + best_rejected->pnp_inliers) best_rejected = record;
  }
  if (best_rejected) summary->loops.push_back(*best_rejected);  // the closest attempt of this keyframe
  summary->loop_s += seconds_since(start);
}

}  // namespace cairn::vslam
