#include "cairn/lidar3d/slam.hpp"

#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <optional>
#include <stdexcept>

#include "cairn/backend/keyframe_graph.hpp"
#include "cairn/backend/problem.hpp"
#include "cairn/core/threads.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/pose_graph.hpp"
#include "cairn/lidar3d/registration.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {
namespace {

using core::Clock;
using core::seconds_since;

Eigen::Matrix<double, 6, 6> information(double translation_sigma_m, double rotation_sigma_rad) {
  Eigen::Matrix<double, 6, 1> diagonal;
  const double it = 1.0 / (translation_sigma_m * translation_sigma_m);
  const double ir = 1.0 / (rotation_sigma_rad * rotation_sigma_rad);
  diagonal << it, it, it, ir, ir, ir;
  return diagonal.asDiagonal();
}

struct Keyframe {
  std::size_t scan = 0;
  double time_s = 0.0;
  core::SE3 T_odom_sensor;   ///< the odometry's estimate
  core::SE3 T_world_sensor;  ///< the graph's estimate
  int segment = 0;
  double path_m = 0.0;       ///< odometry path length up to this keyframe
  std::vector<Eigen::Vector3d> points_sensor;
};

struct Edge {
  int from = 0;
  int to = 0;
  core::SE3 T_from_to;
  bool loop = false;
  bool weak = false;
  int candidate = -1;  ///< index into summary.candidates for loop edges
  /// Odometry edges: the translation direction (unit, in the `from` keyframe's frame) a scan since
  /// `from` could not see (zero when none), or every direction.
  Vector3 degenerate_direction = Vector3::Zero();
  bool degenerate_everywhere = false;
};

struct Verification {
  core::SE3 T_candidate_query;
  double fitness = 0.0;
  double rms_m = 0.0;
  bool degenerate = false;
};

// A loop candidate's place after verification (search_loops).
struct VerifiedPlace {
  LoopCandidateRecord record;
  Verification v;
  Eigen::Vector3d query_position;  // where the loop puts the query
};

}  // namespace

ScanContextOptions slam_scan_context_options() {
  ScanContextOptions options;
  options.lateral_offsets_m = {-4.0, -2.0, 2.0, 4.0};
  return options;
}

bool LidarSlamOptions::is_valid(std::string* error) const {
  core::Problems problems;
  auto fail = [&](const std::string& message) { problems.add(message); };
  std::string nested;
  if (!odometry.is_valid(&nested)) problems.add(nested);
  if (!scan_context.is_valid(&nested)) problems.add(nested);
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(keyframe_distance_m) || !positive(keyframe_angle_rad)) fail("keyframe_distance_m and keyframe_angle_rad must be > 0");
  if (verification_neighbours < 0) fail("verification_neighbours must be >= 0");
  if (!positive(verification_coarse_threshold_m) || !positive(verification_fine_threshold_m) || !positive(verification_voxel_m)) {
    fail("verification thresholds and voxel must be > 0");
  }
  if (!(loop_min_fitness >= 0.0 && loop_min_fitness <= 1.0)) fail("loop_min_fitness must be in [0, 1]");
  if (!positive(loop_max_rms_m)) fail("loop_max_rms_m must be > 0");
  if (!(loop_gate_translation_m >= 0.0) || !(loop_gate_rotation_rad >= 0.0) || !(loop_gate_drift_per_m >= 0.0) ||
      !(loop_gate_rotation_drift_per_m >= 0.0)) {
    fail("loop gates must be >= 0");
  }
  if (!(loop_uniqueness_separation_m >= 0.0)) fail("loop_uniqueness_separation_m must be >= 0");
  if (loop_places_verified < 1) fail("loop_places_verified must be >= 1");
  if (!(loop_ambiguity_fitness_margin >= 0.0 && loop_ambiguity_fitness_margin <= 1.0)) {
    fail("loop_ambiguity_fitness_margin must be in [0, 1]");
  }
  if (!positive(odometry_translation_sigma_m) || !positive(odometry_rotation_sigma_rad) ||
      !positive(segment_break_translation_sigma_m) || !positive(segment_break_rotation_sigma_rad) ||
      !positive(loop_translation_sigma_m) || !positive(loop_rotation_sigma_rad)) {
    fail("pose-graph sigmas must be > 0");
  }
  nested.clear();
  if (!gnss.is_valid(&nested)) {
    problems.add_all("gnss: ", nested);
  }
  return problems.report(error);
}

struct LidarSlam::Impl {
  explicit Impl(const LidarSlamOptions& o)
      : options(o),
        odometry(o.odometry),
        database(o.scan_context),
        arena(core::arena_concurrency(o.odometry.threads)) {}

  LidarSlamOptions options;
  LidarOdometry odometry;
  ScanContextDatabase database;
  tbb::task_arena arena;
  std::vector<Keyframe> keyframes;
  std::vector<Edge> edges;
  std::vector<core::SE3> scan_T_odom;
  std::vector<double> scan_time_s;
  std::vector<int> scan_anchor;
  std::vector<core::SE3> keyframe_T_odom;  ///< per keyframe, its T_odom_sensor (for placing fixes)
  /// Since the last keyframe: a translation direction the registration could not see (odometry
  /// frame, zero when none), or every one.
  Vector3 degenerate_direction_odom = Vector3::Zero();
  bool degenerate_everywhere = false;
  std::optional<GnssAnchoring> gnss;
  Vector3 up_world = Vector3::UnitZ();
  double path_m = 0.0;

  core::SE3 T_world_from_odom(const core::SE3& T_odom) const {
    const Keyframe& last = keyframes.back();
    return last.T_world_sensor * (last.T_odom_sensor.inverse() * T_odom);
  }

  // The candidate's neighbourhood in its own frame, as a voxel map for ICP.
  VoxelHashMap target_map(int candidate) const {
    VoxelHashMap map(VoxelHashMapOptions{options.verification_voxel_m, 20});
    const int n = static_cast<int>(keyframes.size());
    const core::SE3 T_candidate_world = keyframes[static_cast<std::size_t>(candidate)].T_world_sensor.inverse();
    for (int j = std::max(0, candidate - options.verification_neighbours);
         j <= std::min(n - 1, candidate + options.verification_neighbours); ++j) {
      const Keyframe& kf = keyframes[static_cast<std::size_t>(j)];
      const core::SE3 T = T_candidate_world * kf.T_world_sensor;
      std::vector<Eigen::Vector3d> points;
      points.reserve(kf.points_sensor.size());
      for (const Eigen::Vector3d& p : kf.points_sensor) points.push_back(T * p);
      map.add_points(points);
    }
    return map;
  }

  Verification verify(int query, int candidate, const ScanContextMatch& match) {
    const VoxelHashMap map = target_map(candidate);
    const std::vector<Eigen::Vector3d>& source = keyframes[static_cast<std::size_t>(query)].points_sensor;
    const core::SE3 T_estimate = keyframes[static_cast<std::size_t>(candidate)].T_world_sensor.inverse() *
                                 keyframes[static_cast<std::size_t>(query)].T_world_sensor;
    const core::SE3 T_descriptor(core::SO3::exp(Eigen::Vector3d(0.0, 0.0, match.yaw_rad)), match.t_candidate_query);
    Verification best;
    best.fitness = -1.0;
    for (const core::SE3& start : {T_descriptor, T_estimate}) {
      const double coarse = options.verification_coarse_threshold_m, fine = options.verification_fine_threshold_m;
      RegistrationResult r = register_scan(map, source, start, coarse, coarse / 3.0);
      r = register_scan(map, source, r.T_map_sensor, 2.0 * fine, 2.0 * fine / 3.0);
      r = register_scan(map, source, r.T_map_sensor, fine, fine / 3.0);
      const double fitness =
          r.source_points > 0 ? static_cast<double>(r.correspondences) / static_cast<double>(r.source_points) : 0.0;
      if (fitness > best.fitness) {
        best.T_candidate_query = r.T_map_sensor;
        best.fitness = fitness;
        best.rms_m = r.rms_m;
        best.degenerate = r.degenerate_directions > 0;
      }
    }
    return best;
  }

  // The odometry edge's information; with `degenerate_sigma_m` > 0, loose along a direction the
  // odometry could not see between the keyframes (the IMU, or the constant-velocity guess, carried it).
  Eigen::Matrix<double, 6, 6> odometry_information(const Edge& e, double degenerate_sigma_m) const {
    if (degenerate_sigma_m <= 0.0 || (!e.degenerate_everywhere && e.degenerate_direction.isZero())) {
      return information(options.odometry_translation_sigma_m, options.odometry_rotation_sigma_rad);
    }
    const double s2 = options.odometry_translation_sigma_m * options.odometry_translation_sigma_m;
    const double d2 = std::max(degenerate_sigma_m * degenerate_sigma_m, s2);
    Eigen::Matrix3d translation = e.degenerate_everywhere ? Eigen::Matrix3d(Eigen::Matrix3d::Identity() * d2)
                                                          : Eigen::Matrix3d(Eigen::Matrix3d::Identity() * s2 +
                                                                            (d2 - s2) * e.degenerate_direction * e.degenerate_direction.transpose());
    Eigen::Matrix<double, 6, 6> info = information(options.odometry_translation_sigma_m, options.odometry_rotation_sigma_rad);
    info.topLeftCorner<3, 3>() = translation.inverse();
    return info;
  }

  io::PoseGraph3D graph(double degenerate_sigma_m = 0.0) const {
    io::PoseGraph3D graph;
    for (std::size_t k = 0; k < keyframes.size(); ++k) graph.vertices.push_back({static_cast<std::int64_t>(k), keyframes[k].T_world_sensor});
    for (const Edge& e : edges) {
      io::GraphEdge<core::SE3> edge;
      edge.from = e.from;
      edge.to = e.to;
      edge.T_from_to = e.T_from_to;
      edge.information = e.loop   ? information(options.loop_translation_sigma_m, options.loop_rotation_sigma_rad)
                         : e.weak ? information(options.segment_break_translation_sigma_m, options.segment_break_rotation_sigma_rad)
                                  : odometry_information(e, degenerate_sigma_m);
      graph.edges.push_back(edge);
    }
    graph.fixed.push_back(0);
    return graph;
  }

  void optimize(bool gnc, LidarSlamSummary& summary) {
    if (keyframes.size() < 2) return;
    const auto start = Clock::now();
    backend::Problem3D problem = backend::make_problem(graph(), "slam3d pose graph");
    std::vector<bool> is_loop;
    for (const Edge& edge : edges) is_loop.push_back(edge.loop);
    const backend::KeyframeGraphSolve solve = backend::solve_keyframe_graph(problem, gnc, is_loop, {});
    if (!solve.applied) return;
    if (gnc) {
      std::vector<Edge> kept;
      for (std::size_t e = 0; e < edges.size(); ++e) {
        if (solve.keep[e]) {
          kept.push_back(edges[e]);
        } else {
          summary.candidates[static_cast<std::size_t>(edges[e].candidate)].rejected_by_gnc = true;
          ++summary.loops_rejected_by_gnc;
        }
      }
      edges = std::move(kept);
    }
    for (std::size_t k = 0; k < keyframes.size(); ++k) keyframes[k].T_world_sensor = problem.T_world_pose[k];
    ++summary.optimizations;
    summary.optimization_s += seconds_since(start);
    if (gnss && gnss->aligned()) solve_with_gnss();
  }

  std::vector<core::SE3> keyframe_world_poses() const {
    std::vector<core::SE3> poses;
    poses.reserve(keyframes.size());
    for (const Keyframe& kf : keyframes) poses.push_back(kf.T_world_sensor);
    return poses;
  }

  // The graph with the GNSS factors (gnss_anchoring.hpp), its poses written back.
  void solve_with_gnss() {
    if (keyframes.size() < 2) return;
    backend::Problem3D problem = backend::make_problem(graph(gnss->options().degenerate_edge_sigma_m), "slam3d pose graph");
    gnss->solve(problem);
    for (std::size_t k = 0; k < keyframes.size(); ++k) keyframes[k].T_world_sensor = problem.T_world_pose[k];
  }

  // The fixes up to this scan placed on their keyframes; the alignment tried at a new keyframe
  // until it succeeds, then the graph solved with them every solve_every_keyframes keyframes.
  void anchor_to_gnss(bool new_keyframe) {
    gnss->place_fixes(scan_time_s, scan_T_odom, scan_anchor, keyframe_T_odom);
    if (!new_keyframe) return;
    if (!gnss->aligned() && !gnss->try_align(keyframe_world_poses())) return;
    if (gnss->solve_due(keyframes.size())) solve_with_gnss();
  }

  void note_degeneracy(const RegistrationResult& registration) {
    if (registration.degenerate_directions >= 2) degenerate_everywhere = true;
    if (registration.degenerate_directions == 1) {
      const Vector3 d = registration.weakest_direction.head<3>().normalized();
      if (!degenerate_direction_odom.isZero() && std::abs(d.dot(degenerate_direction_odom)) < 0.9) degenerate_everywhere = true;
      degenerate_direction_odom = d;
    }
  }

  // Odometry path length up to this scan, and the scan's odometry pose (at its stamp).
  void track_path(const core::SE3& T_odom_stamp) {
    if (!scan_T_odom.empty()) path_m += (T_odom_stamp.translation() - scan_T_odom.back().translation()).norm();
    scan_T_odom.push_back(T_odom_stamp);
  }

  // A keyframe: the first scan, one that moved keyframe_distance_m or turned keyframe_angle_rad
  // since the last keyframe, or the first of a new odometry segment.
  bool is_keyframe(const core::SE3& T_odom, int segment) const {
    bool make_keyframe = keyframes.empty();
    if (!make_keyframe) {
      const Keyframe& last = keyframes.back();
      const core::SE3 motion = last.T_odom_sensor.inverse() * T_odom;
      make_keyframe = motion.translation().norm() >= options.keyframe_distance_m ||
                      motion.so3().log().norm() >= options.keyframe_angle_rad || segment != last.segment;
    }
    return make_keyframe;
  }

  // Adds the last scan as a keyframe with the odometry edge from the previous one (weak across a
  // segment break); returns its id.
  int add_keyframe(double time_s, const core::SE3& T_odom, int segment) {
    Keyframe kf;
    kf.scan = scan_T_odom.size() - 1;
    kf.time_s = time_s;
    kf.T_odom_sensor = T_odom;
    kf.T_world_sensor = keyframes.empty() ? T_odom : T_world_from_odom(T_odom);
    kf.segment = segment;
    kf.path_m = path_m;
    kf.points_sensor = odometry.last_frame_points();
    const int id = static_cast<int>(keyframes.size());
    if (!keyframes.empty()) {
      const Keyframe& last = keyframes.back();
      Edge edge{id - 1, id, last.T_odom_sensor.inverse() * T_odom, false, last.segment != kf.segment, -1};
      edge.degenerate_direction = last.T_odom_sensor.so3().inverse() * degenerate_direction_odom;
      edge.degenerate_everywhere = degenerate_everywhere;
      edges.push_back(edge);
    }
    keyframe_T_odom.push_back(kf.T_odom_sensor);
    degenerate_direction_odom.setZero();
    degenerate_everywhere = false;
    keyframes.push_back(std::move(kf));
    return id;
  }

  // The new keyframe's Scan Context, the loop search with it, then its entry in the database.
  void close_loops(int id, LidarSlamSummary& summary) {
    const auto start = Clock::now();
    ScanContext context = make_scan_context(keyframes.back().points_sensor, options.scan_context);
    summary.loop_search_s += seconds_since(start);
    search_loops(id, context, summary);
    database.add(id, std::move(context));
  }

  // Loop closure for keyframe `query`: candidates from the Scan Context database, the distinct
  // places among them verified (steps 1-3) and tested for uniqueness (step 4); an accepted loop
  // adds an edge and the graph is optimised.
  void search_loops(int query, const ScanContext& context, LidarSlamSummary& summary) {
    auto start = Clock::now();
    const std::vector<LoopCandidate> candidates = database.query(context, query);
    ++summary.loop_queries;
    summary.loop_search_s += seconds_since(start);
    if (candidates.empty() || !candidates.front().below_threshold) return;
    start = Clock::now();
    const std::vector<const LoopCandidate*> places = distinct_places(candidates);
    // Verify each place (steps 1-3); the places that pass are then tested for uniqueness (step 4).
    std::vector<VerifiedPlace> verified;
    for (const LoopCandidate* place : places) verified.push_back(verify_place(query, place, places));
    VerifiedPlace* best = choose_unique_place(verified);
    summary.verification_s += seconds_since(start);
    record_loops(query, verified, summary);
    if (best != nullptr && best->record.decision == "accepted") optimize(false, summary);
  }

  // Distinct places among the candidates below the threshold, best first: a candidate within
  // the separation of one already taken is the same place seen from a neighbouring keyframe.
  std::vector<const LoopCandidate*> distinct_places(const std::vector<LoopCandidate>& candidates) const {
    std::vector<const LoopCandidate*> places;
    for (const LoopCandidate& candidate : candidates) {
      if (!candidate.below_threshold || static_cast<int>(places.size()) >= options.loop_places_verified) break;
      const Eigen::Vector3d position = keyframes[static_cast<std::size_t>(candidate.id)].T_world_sensor.translation();
      bool seen = false;
      for (const LoopCandidate* place : places) {
        seen = seen || (keyframes[static_cast<std::size_t>(place->id)].T_world_sensor.translation() - position).norm() <=
                           options.loop_uniqueness_separation_m;
      }
      if (!seen) places.push_back(&candidate);
    }
    return places;
  }

  // One place verified by ICP (steps 1-2) and gated by the odometry (step 3): its record with
  // the decision "passed" or the first test it failed.
  VerifiedPlace verify_place(int query, const LoopCandidate* place, const std::vector<const LoopCandidate*>& places) {
    const Keyframe& q = keyframes[static_cast<std::size_t>(query)];
    const Keyframe& c = keyframes[static_cast<std::size_t>(place->id)];
    VerifiedPlace item;
    LoopCandidateRecord& record = item.record;
    record.query_keyframe = query;
    record.candidate_keyframe = place->id;
    record.query_time_s = q.time_s;
    record.candidate_time_s = c.time_s;
    record.descriptor_distance = place->match.distance;
    record.descriptor_yaw_rad = place->match.yaw_rad;
    record.second_descriptor_distance = places.size() > 1 ? places[place == places[0] ? 1 : 0]->match.distance : 1.0;
    arena.execute([&] { item.v = verify(query, place->id, place->match); });
    const Verification& v = item.v;
    record.T_candidate_query = v.T_candidate_query;
    record.fitness = v.fitness;
    record.rms_m = v.rms_m;
    item.query_position = (c.T_world_sensor * v.T_candidate_query).translation();
    const core::SE3 T_estimate = c.T_world_sensor.inverse() * q.T_world_sensor;
    const core::SE3 difference = T_estimate.inverse() * v.T_candidate_query;
    const double travelled = std::abs(q.path_m - c.path_m);
    record.gate_translation_m = difference.translation().norm();
    record.gate_rotation_rad = difference.so3().log().norm();
    record.gate_limit_m = options.loop_gate_translation_m + options.loop_gate_drift_per_m * travelled;
    const double rotation_limit = options.loop_gate_rotation_rad + options.loop_gate_rotation_drift_per_m * travelled;
    if (v.fitness < options.loop_min_fitness) {
      record.decision = "icp fitness";
    } else if (v.rms_m > options.loop_max_rms_m) {
      record.decision = "icp rms";
    } else if (v.degenerate) {
      record.decision = "icp degenerate";
    } else if (record.gate_translation_m > record.gate_limit_m || record.gate_rotation_rad > rotation_limit) {
      record.decision = "odometry gate";
    } else {
      record.decision = "passed";
    }
    return item;
  }

  // Uniqueness (step 4): two places that both pass, about as well, and put the query in different
  // places make the loop ambiguous (a garage's identical bays within what the odometry allows).
  // Decides every passed place; returns the best passed place, or null.
  VerifiedPlace* choose_unique_place(std::vector<VerifiedPlace>& verified) const {
    VerifiedPlace* best = nullptr;
    for (VerifiedPlace& item : verified) {
      if (item.record.decision == "passed" && (best == nullptr || item.v.fitness > best->v.fitness)) best = &item;
    }
    if (best != nullptr) {
      bool ambiguous = false;
      for (VerifiedPlace& item : verified) {
        if (&item == best || item.record.decision != "passed") continue;
        best->record.second_fitness = std::max(best->record.second_fitness, item.v.fitness);
        if (item.v.fitness > best->v.fitness - options.loop_ambiguity_fitness_margin &&
            (item.query_position - best->query_position).norm() > options.loop_uniqueness_separation_m) {
          ambiguous = true;
        }
      }
      for (VerifiedPlace& item : verified) {
        if (item.record.decision != "passed") continue;
        item.record.decision = ambiguous ? "ambiguous" : &item == best ? "accepted" : "not the best place";
      }
    }
    return best;
  }

  // Every verified place goes into the summary; the accepted one becomes a loop edge.
  void record_loops(int query, std::vector<VerifiedPlace>& verified, LidarSlamSummary& summary) {
    for (VerifiedPlace& item : verified) {
      item.record.accepted = item.record.decision == "accepted";
      summary.candidates.push_back(item.record);
      if (item.record.accepted) {
        edges.push_back({item.record.candidate_keyframe, query, item.v.T_candidate_query, true, false,
                         static_cast<int>(summary.candidates.size() - 1)});
        ++summary.loops_accepted;
      }
    }
  }
};

LidarSlam::LidarSlam(const LidarSlamOptions& options) : options_(options) {
  std::string error;
  if (!options_.is_valid(&error)) throw std::invalid_argument("LidarSlamOptions: " + error);
  impl_ = std::make_unique<Impl>(options_);
}

LidarSlam::~LidarSlam() = default;

SlamScanResult LidarSlam::add_scan(const io::PointCloud& cloud, double time_s, const MotionPrior* prior) {
  Impl& m = *impl_;
  SlamScanResult result;
  result.odometry = m.odometry.add_scan(cloud, time_s, prior);
  result.T_odom_registered = result.odometry.T_world_registered;
  // Keyframes live at the registered instant (their points' frame); scans report their stamp.
  const core::SE3& T_odom = result.odometry.T_world_registered;
  const core::SE3 T_odom_stamp = result.odometry.T_world_sensor;
  m.track_path(T_odom_stamp);
  m.note_degeneracy(result.odometry.registration);
  if (m.is_keyframe(T_odom, result.odometry.segment) && !m.odometry.last_frame_points().empty()) {
    const int id = m.add_keyframe(time_s, T_odom, result.odometry.segment);
    result.keyframe = true;
    summary_.keyframes = m.keyframes.size();
    if (options_.loop_closure) m.close_loops(id, summary_);
  }
  m.scan_anchor.push_back(m.keyframes.empty() ? -1 : static_cast<int>(m.keyframes.size()) - 1);
  m.scan_time_s.push_back(time_s);
  if (m.gnss) m.anchor_to_gnss(result.keyframe);
  if (!m.keyframes.empty()) {
    result.odometry.T_world_sensor = m.T_world_from_odom(T_odom_stamp);
    result.odometry.T_world_registered = m.T_world_from_odom(T_odom);
  }
  return result;
}

void LidarSlam::finish() {
  Impl& m = *impl_;
  if (options_.final_gnc && summary_.loops_accepted > 0) m.optimize(true, summary_);
  if (!m.gnss) return;
  m.gnss->finish();
  if (m.gnss->aligned() || m.gnss->try_align(m.keyframe_world_poses())) m.solve_with_gnss();
}

void LidarSlam::add_gnss(const gnss::GnssFix& fix) {
  if (!impl_->gnss) {
    impl_->gnss.emplace(options_.gnss);
    impl_->gnss->set_world_up(impl_->up_world);
  }
  impl_->gnss->add_fix(fix);
}

void LidarSlam::set_world_up(const Vector3& up_world) {
  impl_->up_world = up_world;
  if (impl_->gnss) impl_->gnss->set_world_up(up_world);
}

const GnssAnchoring* LidarSlam::gnss() const { return impl_->gnss ? &*impl_->gnss : nullptr; }

std::vector<core::SE3> LidarSlam::trajectory() const {
  const Impl& m = *impl_;
  std::vector<core::SE3> out;
  out.reserve(m.scan_T_odom.size());
  for (std::size_t i = 0; i < m.scan_T_odom.size(); ++i) {
    const int a = m.scan_anchor[i];
    if (a < 0) {
      out.push_back(m.scan_T_odom[i]);
      continue;
    }
    const Keyframe& kf = m.keyframes[static_cast<std::size_t>(a)];
    out.push_back(kf.T_world_sensor * (kf.T_odom_sensor.inverse() * m.scan_T_odom[i]));
  }
  return out;
}

FrontEnd LidarSlam::front_end() const { return impl_->odometry.front_end(); }

std::vector<core::SE3> LidarSlam::keyframe_poses() const {
  std::vector<core::SE3> out;
  for (const Keyframe& kf : impl_->keyframes) out.push_back(kf.T_world_sensor);
  return out;
}

std::vector<std::size_t> LidarSlam::keyframe_scans() const {
  std::vector<std::size_t> out;
  for (const Keyframe& kf : impl_->keyframes) out.push_back(kf.scan);
  return out;
}

const std::vector<Eigen::Vector3d>& LidarSlam::keyframe_points(std::size_t k) const {
  return impl_->keyframes.at(k).points_sensor;
}

int LidarSlam::keyframe_segment(std::size_t k) const { return impl_->keyframes.at(k).segment; }

io::PoseGraph3D LidarSlam::pose_graph(std::vector<bool>* is_loop) const {
  if (is_loop != nullptr) {
    is_loop->clear();
    for (const Edge& e : impl_->edges) is_loop->push_back(e.loop);
  }
  return impl_->graph();
}

}  // namespace cairn::lidar3d
