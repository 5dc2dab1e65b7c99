#include "cairn/lidar3d/localization.hpp"

#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "cairn/core/problems.hpp"
#include "cairn/core/threads.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/lidar3d/gicp.hpp"
#include "cairn/lidar3d/registration.hpp"
#include "cairn/lidar3d/scan_context.hpp"
#include "cairn/lidar3d/voxel_hash_map.hpp"

namespace cairn::lidar3d {
namespace {

using core::Clock;
using core::seconds_since;
using Points = std::vector<Eigen::Vector3d>;

/// A scan's points as matched against the map, and where the odometry put them.
struct ScanInput {
  std::size_t index = 0;
  double time_s = 0.0;
  double registered_time_s = 0.0;   ///< the instant of frame_sensor (the sweep's middle)
  /// Whether the odometry registered this scan; false when tracking prepared it alone (lean
  /// tracking): T_odom_registered and odometry_health then say nothing.
  bool odometry_step = true;
  Points frame_sensor;              ///< the odometry's points (half its voxel), registered instant
  Points source_sensor;             ///< thinned to source_voxel_m
  std::shared_ptr<const GicpCloud> source;  ///< null when too few points to match
  core::SE3 T_odom_registered;
  core::SE3 T_registered_stamp;     ///< from the registered instant to the scan's stamp
  core::Health odometry_health = core::Health::kOk;
  /// The odometry's first scan (it was just started): T_odom_registered is the identity and says
  /// nothing about the motion since the last scan.
  bool odometry_fresh = false;
};

/// A match of one scan against the map at a guess (see the file comment).
struct MapMatch {
  core::SE3 T_map_sensor;  ///< registered instant
  bool converged = false;
  double fitness = 0.0;
  double inlier_rmse_m = 0.0;
  double translation_degeneracy = 0.0;
  std::string weakest_axis;
  /// How well the scan fits there, for comparing places: fitness less the inlier RMSE in units of
  /// the correspondence distance (a look-alike fits fewer points, and those farther).
  double score(double max_correspondence_m) const { return converged ? fitness - inlier_rmse_m / max_correspondence_m : 0.0; }
};

struct Hypothesis {
  int id = 0;
  core::SE3 T_map_odom;
  std::vector<std::size_t> support;  ///< scans
  int misses = 0;
  bool from_prior = false;
  bool supported_now = false;        ///< by the current scan
  /// T_map_odom no longer holds: the odometry lost track since the last support.
  bool needs_anchor = false;
  MapMatch last;
  std::shared_ptr<const GicpCloud> last_cloud;  ///< the scan of `last`
  std::size_t last_scan = 0;
  /// Per scan since it was created (at most hypothesis_drop_window_scans): how far its score fell
  /// short of the best hypothesis' on that scan.
  std::vector<double> deficits;
};

constexpr std::size_t kMinMatchPoints = 20;
constexpr std::size_t kDegeneracyPoints = 800;

std::string fixed(double value, int digits) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
  return buffer;
}

bool agrees(const core::SE3& a, const core::SE3& b, double max_m, double max_rad) {
  const core::SE3 d = a.inverse() * b;
  return d.translation().norm() <= max_m && d.so3().log().norm() <= max_rad;
}

}  // namespace

std::string_view to_string(Localization3dState state) {
  return state == Localization3dState::kTracking ? "tracking" : "searching";
}

bool Localizer3dOptions::is_valid(std::string* why) const {
  core::Problems p;
  if (threads < 0) p.add("threads must be >= 0");
  p.require_positive(source_voxel_m, "source_voxel_m");
  p.require_positive(target_voxel_m, "target_voxel_m");
  p.require_positive(max_correspondence_m, "max_correspondence_m");
  p.require_positive(coarse_correspondence_m, "coarse_correspondence_m");
  if (max_iterations < 1) p.add("max_iterations must be >= 1");
  if (tracking_max_iterations < 1) p.add("tracking_max_iterations must be >= 1");
  if (sparse_stride < 1) p.add("sparse_stride must be >= 1");
  p.require_positive(step_tolerance, "step_tolerance");
  const auto unit = [&](double v, const char* name) {
    if (!(v >= 0.0 && v <= 1.0)) p.add(std::string(name) + " must be in [0, 1]");
  };
  unit(verification_min_fitness, "verification_min_fitness");
  unit(ok_min_fitness, "ok_min_fitness");
  unit(tracking_min_fitness, "tracking_min_fitness");
  unit(max_descriptor_distance, "max_descriptor_distance");
  unit(rival_score_margin, "rival_score_margin");
  p.require_positive(ok_max_rmse_m, "ok_max_rmse_m");
  if (!(tracking_min_fitness <= ok_min_fitness)) p.add("tracking_min_fitness must not exceed ok_min_fitness");
  p.require_positive(verification_max_rmse_m, "verification_max_rmse_m");
  if (!(min_translation_degeneracy >= 0.0 && min_translation_degeneracy < 1.0 / 3.0)) {
    p.add("min_translation_degeneracy must be in [0, 1/3)");
  }
  if (lost_after_failures < 1) p.add("lost_after_failures must be >= 1");
  if (candidates < 1) p.add("candidates must be >= 1");
  if (places_verified < 1) p.add("places_verified must be >= 1");
  p.require_positive(separation_m, "separation_m");
  if (confirmations < 1) p.add("confirmations must be >= 1");
  p.require_positive(agreement_m, "agreement_m");
  p.require_positive(agreement_rad, "agreement_rad");
  if (hypothesis_max_misses < 1) p.add("hypothesis_max_misses must be >= 1");
  p.require_positive(hypothesis_drop_deficit, "hypothesis_drop_deficit");
  if (hypothesis_drop_window_scans < 1) p.add("hypothesis_drop_window_scans must be >= 1");
  if (max_hypotheses < 1) p.add("max_hypotheses must be >= 1");
  if (check_every_n_scans < 1) p.add("check_every_n_scans must be >= 1");
  p.require_positive(max_acceleration_mps2, "max_acceleration_mps2");
  if (!(jump_margin_m >= 0.0)) p.add("jump_margin_m must be >= 0");
  for (const double yaw : retry_yaw_offsets_rad) {
    if (!std::isfinite(yaw)) p.add("retry_yaw_offsets_rad must be finite");
  }
  for (const double o : polish_offsets_m) {
    if (!std::isfinite(o)) p.add("polish_offsets_m must be finite");
  }
  return p.report(why);
}

LidarOdometryOptions Localizer3d::odometry_options(const SavedSensorModel& sensor, int threads) {
  LidarOdometryOptions o;
  o.front_end = sensor.front_end;
  o.rings_from_kitti_order = sensor.rings_from_kitti_order;
  o.min_range_m = sensor.min_range_m;
  o.max_range_m = sensor.max_range_m;
  o.deskew = sensor.deskew;
  o.vertical_angle_correction_rad = sensor.vertical_angle_correction_rad;
  o.sweep_period_s = sensor.sweep_period_s;
  o.voxel_size_m = sensor.voxel_size_m;
  o.max_points_per_voxel = sensor.max_points_per_voxel;
  o.threads = threads;
  return o;
}

struct Localizer3d::Impl {
  Impl(SavedMap3D m, const Localizer3dOptions& o)
      : map(std::move(m)),
        options(o),
        odometry(std::make_unique<LidarOdometry>(odometry_options(map.sensor, o.threads))),
        target_map(VoxelHashMapOptions{map.sensor.voxel_size_m, map.sensor.max_points_per_voxel}),
        database(search_options(map.scan_context, o)),
        arena(core::arena_concurrency(o.threads)) {}

  static ScanContextOptions search_options(ScanContextOptions sc, const Localizer3dOptions& o) {
    sc.exclude_recent = 0;  // the query is never one of the map's keyframes
    sc.candidates = o.candidates;
    return sc;
  }

  SavedMap3D map;
  Localizer3dOptions options;
  std::unique_ptr<LidarOdometry> odometry;  ///< replaced by a fresh one whenever a search starts
  VoxelHashMap target_map;            ///< point-to-plane: coarse matching and the degeneracy
  std::optional<GicpCloud> target;    ///< GICP target and the nearest points of the fitness
  ScanContextDatabase database;
  mutable tbb::task_arena arena;  // execute() is not const

  Localization3dState state = Localization3dState::kSearching;
  core::SE3 T_map_odom;               ///< tracking
  /// The last two matched poses (registered instants) and their times: the localiser's own
  /// constant-velocity prediction when the odometry lost track.
  std::vector<std::pair<double, core::SE3>> recent_poses;
  int failures = 0;
  std::size_t tracked_scans = 0;
  std::vector<Hypothesis> hypotheses;
  int next_hypothesis = 0;
  std::size_t searching_since = 0;
  std::size_t rivals_died = 0;
  std::size_t scans = 0;
  double last_time_s = -std::numeric_limits<double>::infinity();

  // ---- setup -------------------------------------------------------------------------------

  void build(Localizer3dSummary& summary) {
    Points points;
    points.reserve(map.points_world.size());
    for (const Eigen::Vector3f& p : map.points_world) points.push_back(p.cast<double>());
    target_map.add_points(points);
    Points thinned = voxel_downsample(points, options.target_voxel_m);
    summary.target_points = thinned.size();
    target.emplace(std::move(thinned), std::move(points));
    // Every target covariance now, not on first use: tracking moves into unused parts of the map
    // with every scan, and their covariances cost 1.5 ms per KITTI key frame there (0.15 s here
    // for the 198,000 points of the KITTI test's map, on 2 threads).
    arena.execute([&] { target->compute_covariances(); });
    for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
      database.add(static_cast<int>(k), scan_context_from_descriptor(map.keyframes[k].scan_context));
    }
    summary.map_keyframes = map.keyframes.size();
    summary.map_points = map.points_world.size();
  }

  // ---- stages of add_scan --------------------------------------------------------------------

  /// The scan's points and motion: one odometry step, or, when tracking has a velocity of its
  /// own (lean tracking, Localizer3dOptions::odometry_while_tracking), the scan prepared alone and
  /// deskewed by that velocity.
  ScanInput prepare(const io::PointCloud& cloud, double time_s, Localization3dResult& result) {
    const auto start = Clock::now();
    ScanInput in;
    in.index = scans;
    in.time_s = time_s;
    if (lean_tracking()) {
      LidarOdometry::PreparedScan prepared = odometry->prepare_scan(cloud, time_s, velocity_per_s());
      in.odometry_step = false;
      in.registered_time_s = prepared.registered_time_s;
      in.frame_sensor = std::move(prepared.frame_sensor);
      in.T_registered_stamp = prepared.T_registered_stamp;
    } else {
      const OdometryScanResult od = odometry->add_scan(cloud, time_s);
      in.registered_time_s = od.registered_time_s;
      in.frame_sensor = odometry->last_frame_points();
      in.T_odom_registered = od.T_world_registered;
      in.T_registered_stamp = od.T_world_registered.inverse() * od.T_world_sensor;
      in.odometry_health = od.health;
      in.odometry_fresh = odometry->scans() == 1;
    }
    in.source_sensor = voxel_downsample(in.frame_sensor, options.source_voxel_m);
    if (in.source_sensor.size() >= kMinMatchPoints) in.source = std::make_shared<const GicpCloud>(in.source_sensor, in.frame_sensor);
    result.odometry_step = in.odometry_step;
    result.odometry_health = in.odometry_health;
    result.odometry_s = seconds_since(start);
    return in;
  }

  /// Tracking without the odometry: the localiser's own last two matched poses give the velocity.
  bool lean_tracking() const {
    return state == Localization3dState::kTracking && !options.odometry_while_tracking && recent_poses.size() >= 2;
  }

  /// The twist per second between the last two matched poses (zero without two).
  Eigen::Matrix<double, 6, 1> velocity_per_s() const {
    if (recent_poses.size() < 2) return Eigen::Matrix<double, 6, 1>::Zero();
    const auto& [t0, T0] = recent_poses.front();
    const auto& [t1, T1] = recent_poses.back();
    return t1 > t0 ? Eigen::Matrix<double, 6, 1>((T0.inverse() * T1).log() / (t1 - t0)) : Eigen::Matrix<double, 6, 1>::Zero();
  }

  /// `max_iterations` (0: options.max_iterations) bounds each GICP.
  MapMatch match(const ScanInput& in, const core::SE3& guess, bool coarse_first, int max_iterations = 0) const {
    MapMatch m;
    m.T_map_sensor = guess;
    if (!in.source) return m;
    arena.execute([&] {
      GicpOptions g;
      g.max_iterations = max_iterations > 0 ? max_iterations : options.max_iterations;
      g.translation_tolerance_m = options.step_tolerance;
      g.rotation_tolerance_rad = options.step_tolerance;
      g.sparse_stride = options.sparse_stride;
      core::SE3 start = guess;
      if (coarse_first) {
        g.max_correspondence_m = options.coarse_correspondence_m;
        start = register_gicp(*target, *in.source, guess, g).T_target_source;
      }
      g.max_correspondence_m = options.max_correspondence_m;
      const GicpResult r = register_gicp(*target, *in.source, start, g);
      m.T_map_sensor = r.T_target_source;
      m.converged = r.converged;
      m.fitness = r.fitness;
      m.inlier_rmse_m = r.inlier_rmse_m;
      measure_degeneracy(in, m);
    });
    return m;
  }

  /// The translation degeneracy of one point-to-plane linearisation at the match
  /// (registration.hpp), and the weakest axis when it is degenerate. (Fitness and inlier RMSE are
  /// GICP's own, at its last linearisation: within its tolerances of the result when it converged.)
  /// The normals' moment is a mean, so it is taken over at most kDegeneracyPoints source points
  /// spread evenly through the scan (all of them cost 2.5 ms per KITTI scan, a third of tracking).
  void measure_degeneracy(const ScanInput& in, MapMatch& m) const {
    const std::size_t stride = std::max<std::size_t>(1, (in.source_sensor.size() + kDegeneracyPoints - 1) / kDegeneracyPoints);
    Points sample;
    sample.reserve(in.source_sensor.size() / stride + 1);
    for (std::size_t i = 0; i < in.source_sensor.size(); i += stride) sample.push_back(in.source_sensor[i]);
    RegistrationOptions one;
    one.max_iterations = 1;
    const RegistrationResult r = register_scan(target_map, sample, m.T_map_sensor, options.max_correspondence_m,
                                               options.max_correspondence_m / 3.0, one);
    m.translation_degeneracy = r.translation_degeneracy;
    if (r.characteristic_length_m > 0.0 && r.translation_degeneracy < options.min_translation_degeneracy) {
      m.weakest_axis = name_direction(r.weakest_direction, m.T_map_sensor.so3(), r.characteristic_length_m);
    }
  }

  /// The place of candidate `c` matched from the descriptor's guess: the scan at the keyframe with
  /// the descriptor's yaw, and the same guess moved half-way to each neighbouring keyframe (a scan
  /// between two mapped ones is as far from either; along a straight street the match may not
  /// pull it there from the keyframe). The best verified start wins, by score.
  MapMatch match_place(const ScanInput& in, const LoopCandidate& c) const {
    const auto id = static_cast<std::size_t>(c.id);
    const core::SE3 T_keyframe_query(core::SO3::exp(Eigen::Vector3d(0.0, 0.0, c.match.yaw_rad)), c.match.t_candidate_query);
    const core::SE3 guess = map.keyframes[id].T_world_sensor * T_keyframe_query;
    MapMatch best = match(in, guess, true);
    for (const std::size_t n : {id - 1, id + 1}) {
      if (n >= map.keyframes.size()) continue;  // id - 1 wraps for the first keyframe
      const Eigen::Vector3d step = 0.5 * (map.keyframes[n].T_world_sensor.translation() - map.keyframes[id].T_world_sensor.translation());
      if (step.norm() > 0.5 * options.separation_m || step.norm() < 0.5 * options.max_correspondence_m) continue;
      const MapMatch m = match(in, core::SE3(guess.so3(), guess.translation() + step), true);
      const bool better = verification_failure(m).empty() &&
                          (!verification_failure(best).empty() || m.score(options.max_correspondence_m) > best.score(options.max_correspondence_m));
      if (better) best = m;
    }
    return best;
  }

  /// "" when `m` passes verification, else why not.
  std::string verification_failure(const MapMatch& m) const {
    if (!m.converged) return "not converged";
    if (m.fitness < options.verification_min_fitness) return "fitness";
    if (m.inlier_rmse_m > options.verification_max_rmse_m) return "rmse";
    if (m.translation_degeneracy < options.min_translation_degeneracy) return "degenerate";
    return "";
  }

  /// Scan Context's places for this scan, each matched from the descriptor's guess and recorded.
  std::vector<LocalizationAttempt3d> search_places(const ScanInput& in, bool while_tracking, Localizer3dSummary& summary) {
    std::vector<LocalizationAttempt3d> attempts;
    if (!in.source) return attempts;
    ++summary.descriptor_queries;
    const ScanContext context = make_scan_context(in.frame_sensor, database.options());
    const std::vector<LoopCandidate> candidates = database.query(context, std::numeric_limits<int>::min() / 2);
    std::vector<Eigen::Vector3d> places;
    for (const LoopCandidate& c : candidates) {
      if (static_cast<int>(places.size()) >= options.places_verified) break;
      if (c.match.distance > options.max_descriptor_distance) continue;
      const SavedKeyframe3D& kf = map.keyframes[static_cast<std::size_t>(c.id)];
      const Eigen::Vector3d at = kf.T_world_sensor.translation();
      const bool seen = std::any_of(places.begin(), places.end(),
                                    [&](const Eigen::Vector3d& p) { return (p - at).norm() <= options.separation_m; });
      if (seen) continue;
      places.push_back(at);
      const MapMatch m = match_place(in, c);
      LocalizationAttempt3d a;
      a.scan = in.index;
      a.keyframe = c.id;
      a.descriptor_distance = c.match.distance;
      a.descriptor_yaw_rad = c.match.yaw_rad;
      a.while_tracking = while_tracking;
      a.fitness = m.fitness;
      a.inlier_rmse_m = m.inlier_rmse_m;
      a.translation_degeneracy = m.translation_degeneracy;
      a.T_map_sensor = m.T_map_sensor;
      const std::string failure = verification_failure(m);
      a.decision = failure.empty() ? "verified" : failure;
      ++summary.places_matched;
      if (failure.empty()) ++summary.places_verified;
      attempts.push_back(std::move(a));
    }
    return attempts;
  }

  /// Each hypothesis matched at its prediction; supported when the match verifies there.
  void follow_hypotheses(const ScanInput& in) {
    for (Hypothesis& h : hypotheses) {
      h.supported_now = false;
      if (in.odometry_health == core::Health::kLost) h.needs_anchor = true;  // T_odom jumped
      if (h.needs_anchor) {
        ++h.misses;
        continue;
      }
      // A fresh odometry predicts no motion: coarse to fine from there, and the scans' own
      // motion (motion_agrees) instead of the prediction as the check.
      const core::SE3 predicted = h.T_map_odom * in.T_odom_registered;
      const MapMatch m = match(in, predicted, in.odometry_fresh);
      const bool consistent = in.odometry_fresh ? motion_agrees(h, in, m.T_map_sensor)
                                                : agrees(m.T_map_sensor, predicted, options.agreement_m, options.agreement_rad);
      if (verification_failure(m).empty() && consistent) {
        support(h, m, in);
      } else {
        ++h.misses;
      }
    }
  }

  void support(Hypothesis& h, const MapMatch& m, const ScanInput& in) const {
    h.support.push_back(in.index);
    h.T_map_odom = m.T_map_sensor * in.T_odom_registered.inverse();
    h.needs_anchor = false;
    h.misses = 0;
    h.supported_now = true;
    h.last = m;
    h.last_cloud = in.source;
    h.last_scan = in.index;
  }

  /// Whether the scan's motion since the hypothesis' last support is what the two places imply:
  /// the scan registered onto that scan (GICP) from the motion between the places ends within the
  /// agreement of it. What the odometry's prediction checks, when the odometry cannot (lost track,
  /// or the first scans of a run, where it has no velocity yet).
  bool motion_agrees(const Hypothesis& h, const ScanInput& in, const core::SE3& T_map_sensor) const {
    if (h.last_cloud == nullptr || in.source == nullptr || h.last_scan == in.index) return false;
    const core::SE3 guess = h.last.T_map_sensor.inverse() * T_map_sensor;
    GicpOptions g;
    g.max_correspondence_m = options.max_correspondence_m;
    g.max_iterations = options.max_iterations;
    GicpResult r;
    arena.execute([&] { r = register_gicp(*h.last_cloud, *in.source, guess, g); });
    return r.converged && r.fitness >= options.tracking_min_fitness &&
           agrees(r.T_target_source, guess, options.agreement_m, options.agreement_rad);
  }

  static MapMatch as_match(const LocalizationAttempt3d& a) {
    MapMatch m;
    m.T_map_sensor = a.T_map_sensor;
    m.converged = true;  // verified
    m.fitness = a.fitness;
    m.inlier_rmse_m = a.inlier_rmse_m;
    m.translation_degeneracy = a.translation_degeneracy;
    return m;
  }

  /// The verified places of a searching scan: support for the hypothesis they agree with, or new
  /// hypotheses.
  void absorb_places(const ScanInput& in, std::vector<LocalizationAttempt3d>& attempts, Localizer3dSummary& summary) {
    for (LocalizationAttempt3d& a : attempts) {
      if (a.decision != "verified") continue;
      // The place of a hypothesis this scan already supports (within separation_m: the same
      // place): the better fit of the two is kept (a match from the odometry's prediction can
      // settle a little along a street).
      auto same = std::find_if(hypotheses.begin(), hypotheses.end(), [&](const Hypothesis& h) {
        return h.supported_now && agrees(h.last.T_map_sensor, a.T_map_sensor, options.separation_m, std::numbers::pi);
      });
      if (same != hypotheses.end()) {
        const MapMatch m = as_match(a);
        const bool better = m.score(options.max_correspondence_m) > same->last.score(options.max_correspondence_m);
        a.decision += (better ? ", refines hypothesis " : ", same place as hypothesis ") + std::to_string(same->id);
        if (better) {
          same->last = m;
          same->T_map_odom = a.T_map_sensor * in.T_odom_registered.inverse();
        }
        continue;
      }
      auto agreeing = std::find_if(hypotheses.begin(), hypotheses.end(), [&](const Hypothesis& h) {
        return (!h.needs_anchor && agrees(a.T_map_sensor, h.T_map_odom * in.T_odom_registered, options.agreement_m, options.agreement_rad)) ||
               motion_agrees(h, in, a.T_map_sensor);
      });
      if (agreeing != hypotheses.end()) {
        a.decision += ", supports hypothesis " + std::to_string(agreeing->id);
        if (!agreeing->supported_now) support(*agreeing, as_match(a), in);
        continue;
      }
      if (static_cast<int>(hypotheses.size()) >= options.max_hypotheses) {
        a.decision += ", ignored: max_hypotheses alive";
        ++summary.hypotheses_ignored;
        continue;
      }
      Hypothesis h;
      h.id = next_hypothesis++;
      support(h, as_match(a), in);
      hypotheses.push_back(h);
      ++summary.hypotheses;
      a.decision += ", new hypothesis " + std::to_string(h.id);
    }
  }

  /// Each hypothesis' shortfall against the best one on this scan (a miss scores 0), kept over
  /// the last hypothesis_drop_window_scans scans (2D's hypothesis_drop_deficit, slam2d/localization.hpp).
  void compare_hypotheses() {
    double best = 0.0;
    for (const Hypothesis& h : hypotheses) {
      if (h.supported_now) best = std::max(best, h.last.score(options.max_correspondence_m));
    }
    for (Hypothesis& h : hypotheses) {
      h.deficits.push_back(best - (h.supported_now ? h.last.score(options.max_correspondence_m) : 0.0));
      if (static_cast<int>(h.deficits.size()) > options.hypothesis_drop_window_scans) h.deficits.erase(h.deficits.begin());
    }
  }

  bool falls_short(const Hypothesis& h) const {
    double sum = 0.0;
    for (const double d : h.deficits) sum += d;
    return sum >= options.hypothesis_drop_deficit;
  }

  void drop_hypotheses(Localizer3dSummary& summary) {
    const auto dead = [&](const Hypothesis& h) { return h.misses >= options.hypothesis_max_misses || falls_short(h); };
    const std::size_t before = hypotheses.size();
    hypotheses.erase(std::remove_if(hypotheses.begin(), hypotheses.end(), dead), hypotheses.end());
    summary.hypotheses_dropped += before - hypotheses.size();
    rivals_died += before - hypotheses.size();
  }

  /// A search starts with a fresh odometry: after a kidnapping the old one's local map holds the
  /// place it came from and its velocity is wrong, and it deskews every scan with that velocity
  /// (measured in the simulated street: scans deskewed so fitted the map best 1.5 m off for 40
  /// scans after a kidnapping). Hypotheses then need the scans' own motion (motion_agrees) to be
  /// carried on; a prior is kept as a pose (re-anchored at the next scan's match).
  void start_search(const ScanInput& in, const std::vector<std::pair<MapMatch, bool>>& seeds, Localizer3dSummary& summary) {
    odometry = std::make_unique<LidarOdometry>(odometry->options());
    state = Localization3dState::kSearching;
    searching_since = in.index;
    rivals_died = 0;
    hypotheses.clear();
    recent_poses.clear();
    // Each seed (this scan's pose there; supported or a prior) becomes a hypothesis in the fresh
    // odometry's frame, whose first scan, the next one, is its origin: T_map_odom is where this
    // scan is, the next scan's match starts there.
    for (const auto& [m, supported] : seeds) {
      Hypothesis h;
      h.id = next_hypothesis++;
      h.T_map_odom = m.T_map_sensor;
      h.from_prior = !supported;
      h.last = m;
      h.last_cloud = in.source;
      h.last_scan = in.index;
      if (supported) h.support = {in.index};
      hypotheses.push_back(h);
      ++summary.hypotheses;
    }
  }

  void search(const ScanInput& in, Localization3dResult& result, Localizer3dSummary& summary) {
    auto start = Clock::now();
    follow_hypotheses(in);
    result.tracking_s += seconds_since(start);
    start = Clock::now();
    std::vector<LocalizationAttempt3d> attempts = search_places(in, false, summary);
    absorb_places(in, attempts, summary);
    result.search_s += seconds_since(start);
    summary.max_search_s = std::max(summary.max_search_s, result.search_s);
    for (LocalizationAttempt3d& a : attempts) summary.attempts.push_back(std::move(a));
    compare_hypotheses();
    drop_hypotheses(summary);
    result.live_hypotheses = static_cast<int>(hypotheses.size());
    accept_if_confirmed(in, result, summary);
  }

  void accept_if_confirmed(const ScanInput& in, Localization3dResult& result, Localizer3dSummary& summary) {
    const auto confirmed = [&](const Hypothesis& h) {
      return h.supported_now && static_cast<int>(h.support.size()) >= options.confirmations;
    };
    const auto it = std::find_if(hypotheses.begin(), hypotheses.end(), confirmed);
    if (it == hypotheses.end()) {
      result.reason = hypotheses.empty() ? "searching: no verified place" : "searching: " + std::to_string(hypotheses.size()) + " hypotheses, none confirmed";
      return;
    }
    if (hypotheses.size() > 1) {
      ++summary.scans_ambiguous;
      result.reason = "ambiguous: " + std::to_string(hypotheses.size()) + " places explain the scans";
      return;
    }
    Hypothesis h = *it;
    polish(in, h);
    Relocalisation3d r;
    r.scan = in.index;
    r.time_s = in.time_s;
    r.T_map_sensor = h.last.T_map_sensor * in.T_registered_stamp;
    r.searching_since_scan = searching_since;
    r.from_prior = h.from_prior;
    r.support_scans = h.support;
    r.rival_hypotheses = rivals_died;
    summary.relocalisations.push_back(r);
    state = Localization3dState::kTracking;
    T_map_odom = h.T_map_odom;
    recent_poses.clear();
    remember_pose(in.registered_time_s, h.last.T_map_sensor);
    failures = 0;
    tracked_scans = 0;
    hypotheses.clear();
    result.relocalised = true;
    report_match(h.last, in, result);
    result.reason = "relocalised (" + std::to_string(h.support.size()) + " scans agree)";
  }

  /// Before a hypothesis is accepted: its pose matched again from starts moved along and across
  /// the sensor (polish_offsets_m), coarse to fine; the best score wins. Along a street a match
  /// can settle a metre or two off where the scan fits best (measured in the simulated street:
  /// an accepted pose 1.5 m off with fitness 0.94, inlier RMSE 0.21 m, where the true pose gives
  /// 1.0 and 0.13 m).
  void polish(const ScanInput& in, Hypothesis& h) const {
    for (const double offset : options.polish_offsets_m) {
      for (int axis = 0; axis < 2; ++axis) {
        const core::SE3 start = h.last.T_map_sensor * core::SE3(core::SO3(), offset * Eigen::Vector3d::Unit(axis));
        const MapMatch m = match(in, start, true);
        if (verification_failure(m).empty() && m.score(options.max_correspondence_m) > h.last.score(options.max_correspondence_m)) {
          h.last = m;
        }
      }
    }
    h.T_map_odom = h.last.T_map_sensor * in.T_odom_registered.inverse();
  }

  /// The health test of a match: converged, fitness and inlier RMSE within the `ok` bounds
  /// (degeneracy aside).
  bool fits_ok(const MapMatch& m) const {
    return m.converged && m.fitness >= options.ok_min_fitness && m.inlier_rmse_m <= options.ok_max_rmse_m;
  }

  void report_match(const MapMatch& m, const ScanInput& in, Localization3dResult& result) const {
    result.localised = true;
    result.state = Localization3dState::kTracking;
    result.T_map_sensor = m.T_map_sensor * in.T_registered_stamp;
    result.fitness = m.fitness;
    result.inlier_rmse_m = m.inlier_rmse_m;
    result.translation_degeneracy = m.translation_degeneracy;
    result.degenerate_axis = m.weakest_axis;
    const bool ok = m.fitness >= options.ok_min_fitness && m.inlier_rmse_m <= options.ok_max_rmse_m && m.weakest_axis.empty();
    result.health = ok ? core::Health::kOk : core::Health::kDegraded;
  }

  void remember_pose(double time_s, const core::SE3& T_map_sensor) {
    recent_poses.emplace_back(time_s, T_map_sensor);
    if (recent_poses.size() > 2) recent_poses.erase(recent_poses.begin());
  }

  /// Where the scan is expected: through the odometry, or, in lean tracking and when the odometry
  /// lost track on this scan (its pose jumped), by the localiser's own last motion carried on
  /// (constant velocity).
  core::SE3 predict(const ScanInput& in) const {
    const bool own = !in.odometry_step || in.odometry_health == core::Health::kLost;
    if (!own || recent_poses.empty()) return T_map_odom * in.T_odom_registered;
    const auto& [t1, T1] = recent_poses.back();
    return T1 * core::SE3::exp(velocity_per_s() * (in.registered_time_s - t1));
  }

  /// The starts of a retry: the prediction and the prediction turned about the map's vertical by
  /// each of retry_yaw_offsets_rad, ordered by how many of (at most 400 of) the scan's points find
  /// a map point within max_correspondence_m there, most first, the prediction first among equals
  /// (a fraction of a millisecond each, where a GICP from a wrong yaw costs tens).
  std::vector<core::SE3> retry_starts(const ScanInput& in, const core::SE3& predicted) const {
    std::vector<std::pair<std::size_t, core::SE3>> turned;
    const std::size_t stride = std::max<std::size_t>(1, (in.source_sensor.size() + 399) / 400);
    const double max2 = options.max_correspondence_m * options.max_correspondence_m;
    std::vector<double> yaws = {0.0};
    yaws.insert(yaws.end(), options.retry_yaw_offsets_rad.begin(), options.retry_yaw_offsets_rad.end());
    for (const double yaw : yaws) {
      const core::SE3 start(core::SO3::exp(Eigen::Vector3d(0.0, 0.0, yaw)) * predicted.so3(), predicted.translation());
      std::size_t near = 0;
      for (std::size_t i = 0; i < in.source_sensor.size(); i += stride) {
        std::size_t index = 0;
        double d2 = 0.0;
        if (target->nearest(start * in.source_sensor[i], max2, &index, &d2)) ++near;
      }
      turned.emplace_back(near, start);
    }
    std::stable_sort(turned.begin(), turned.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    std::vector<core::SE3> starts;
    for (const auto& [near, start] : turned) starts.push_back(start);
    return starts;
  }

  void track(const ScanInput& in, Localization3dResult& result, Localizer3dSummary& summary) {
    const auto start = Clock::now();
    const core::SE3 predicted = predict(in);
    const bool coarse_first = in.odometry_step && in.odometry_health == core::Health::kLost;
    MapMatch m = match(in, predicted, coarse_first, coarse_first ? 0 : options.tracking_max_iterations);
    if (!coarse_first && !fits_ok(m)) {
      // The prediction may be off by more than the correspondence distance (a turn whose rate
      // changed between sparse scans): coarse to fine from it and from it turned by each of
      // retry_yaw_offsets_rad, in retry_starts' order, until one fits `ok`; the best score wins.
      for (const core::SE3& from : retry_starts(in, predicted)) {
        const MapMatch retry = match(in, from, true);
        if (retry.score(options.max_correspondence_m) > m.score(options.max_correspondence_m)) m = retry;
        if (fits_ok(m)) break;
      }
    }
    result.tracking_s += seconds_since(start);
    if (m.converged && m.fitness >= options.tracking_min_fitness) {
      if (implausible_jump(in, m, result)) {
        ++summary.implausible_jumps;
        start_search(in, {}, summary);
        result.health = core::Health::kLost;
        return;
      }
      accept_tracked(m, in, result);
      check_for_rivals(in, m, result, summary);
      return;
    }
    ++summary.tracking_failures;
    if (++failures >= options.lost_after_failures) {
      MapMatch dead_reckoned;
      dead_reckoned.T_map_sensor = predicted;
      start_search(in, {{dead_reckoned, false}}, summary);
      result.health = core::Health::kLost;
      result.reason = "lost: " + std::to_string(failures) + " scans in a row do not fit the map";
      return;
    }
    result.localised = true;
    result.state = Localization3dState::kTracking;
    result.dead_reckoning = true;
    result.health = core::Health::kDegraded;
    result.T_map_sensor = predicted * in.T_registered_stamp;
    result.fitness = m.fitness;
    result.reason = "dead reckoning: fitness " + fixed(m.fitness, 2) + " below " + fixed(options.tracking_min_fitness, 2);
  }

  /// Whether the matched pose lies farther from where the last two poses' constant velocity puts
  /// it than an acceleration of max_acceleration_mps2 allows (plus jump_margin_m): the scans
  /// jumped (a kidnapping the odometry followed, e.g. onto a look-alike bay of a garage), so the
  /// tracked pose is no longer trusted.
  bool implausible_jump(const ScanInput& in, const MapMatch& m, Localization3dResult& result) const {
    if (recent_poses.size() < 2) return false;
    const auto& [t0, T0] = recent_poses.front();
    const auto& [t1, T1] = recent_poses.back();
    if (!(t1 > t0)) return false;
    const core::SE3 expected = T1 * core::SE3::exp(velocity_per_s() * (in.registered_time_s - t1));
    const double dt = in.registered_time_s - t1;
    const double limit = options.jump_margin_m + 0.5 * options.max_acceleration_mps2 * dt * dt;
    const double off = (m.T_map_sensor.translation() - expected.translation()).norm();
    if (off <= limit) return false;
    result.reason = "lost: the scan moved " + fixed(off, 1) + " m from where constant velocity puts it (at most " +
                    fixed(limit, 1) + " m): a kidnapping?";
    return true;
  }

  void accept_tracked(const MapMatch& m, const ScanInput& in, Localization3dResult& result) {
    if (in.odometry_step) T_map_odom = m.T_map_sensor * in.T_odom_registered.inverse();
    failures = 0;
    remember_pose(in.registered_time_s, m.T_map_sensor);
    report_match(m, in, result);
    result.reason = result.health == core::Health::kOk ? "tracking"
                    : !m.weakest_axis.empty()          ? "tracking, degenerate along " + m.weakest_axis
                                                       : "tracking, fitness " + fixed(m.fitness, 2) + ", inlier RMSE " +
                                                             fixed(m.inlier_rmse_m, 2) + " m";
  }

  /// The tracking check, every check_every_n_scans scans and on every scan whose match is not
  /// `ok`: the global search. A verified place that fits clearly better than the tracked pose
  /// (score by `rival_score_margin`) corrects it when it lies within separation_m (the match
  /// had slid along a street), and ends tracking when it lies farther (a kidnapping the odometry
  /// did not notice; both places then become hypotheses).
  void check_for_rivals(const ScanInput& in, const MapMatch& tracked, Localization3dResult& result, Localizer3dSummary& summary) {
    const bool due = ++tracked_scans % static_cast<std::size_t>(options.check_every_n_scans) == 0;
    if (!due && result.health == core::Health::kOk) return;
    const auto start = Clock::now();
    ++summary.tracking_checks;
    std::vector<LocalizationAttempt3d> attempts = search_places(in, true, summary);
    const LocalizationAttempt3d* rival = nullptr;
    const LocalizationAttempt3d* correction = nullptr;
    const double tracked_score = tracked.score(options.max_correspondence_m);
    for (LocalizationAttempt3d& a : attempts) {
      if (a.decision != "verified") continue;
      const bool near = agrees(a.T_map_sensor, tracked.T_map_sensor, options.separation_m, std::numbers::pi);
      const double score = as_match(a).score(options.max_correspondence_m);
      const bool better = score > tracked_score + options.rival_score_margin;
      const bool same = agrees(a.T_map_sensor, tracked.T_map_sensor, options.agreement_m, options.agreement_rad);
      if (same || !better) {
        a.decision += same ? ", agrees with tracking" : ", fits no better than tracking";
      } else if (near) {
        a.decision += ", corrects tracking";
        if (correction == nullptr || score > as_match(*correction).score(options.max_correspondence_m)) correction = &a;
      } else {
        a.decision += ", rival: ends tracking";
        if (rival == nullptr || score > as_match(*rival).score(options.max_correspondence_m)) rival = &a;
      }
    }
    result.search_s += seconds_since(start);
    if (rival == nullptr && correction != nullptr) {
      ++summary.tracking_corrections;
      accept_tracked(as_match(*correction), in, result);
      result.reason = "tracking corrected by " + fixed((correction->T_map_sensor.translation() - tracked.T_map_sensor.translation()).norm(), 1) +
                      " m: a verified place fits better";
    }
    if (rival != nullptr) {
      ++summary.tracking_contradicted;
      start_search(in, {{tracked, true}, {as_match(*rival), true}}, summary);
      result.localised = false;
      result.state = Localization3dState::kSearching;
      result.health = core::Health::kLost;
      result.reason = "lost: a place " + fixed((rival->T_map_sensor.translation() - tracked.T_map_sensor.translation()).norm(), 1) +
                      " m away fits better (fitness " + fixed(rival->fitness, 2) + " vs " + fixed(tracked.fitness, 2) + ")";
      result.live_hypotheses = static_cast<int>(hypotheses.size());
    }
    for (LocalizationAttempt3d& a : attempts) summary.attempts.push_back(std::move(a));
  }

  void count(const Localization3dResult& r, Localizer3dSummary& summary) const {
    ++summary.scans;
    (r.health == core::Health::kOk ? summary.scans_ok : r.health == core::Health::kDegraded ? summary.scans_degraded : summary.scans_lost)++;
    if (r.localised) {
      ++summary.scans_localised;
      if (!summary.first_localised_scan) summary.first_localised_scan = r.scan;
    }
    summary.total_s += r.total_s;
    summary.max_scan_s = std::max(summary.max_scan_s, r.total_s);
  }
};

Localizer3d::Localizer3d(SavedMap3D map, const Localizer3dOptions& options) : options_(options) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid localisation options: " + why);
  if (map.points_world.empty()) throw std::invalid_argument("the map holds no points: nothing to localise in");
  if (map.keyframes.empty()) throw std::invalid_argument("the map holds no keyframes: no place to search from");
  const auto start = Clock::now();
  impl_ = std::make_unique<Impl>(std::move(map), options);
  impl_->build(summary_);
  summary_.setup_s = seconds_since(start);
}

Localizer3d::~Localizer3d() = default;

const SavedMap3D& Localizer3d::map() const { return impl_->map; }
Localization3dState Localizer3d::state() const { return impl_->state; }

Localization3dResult Localizer3d::add_scan(const io::PointCloud& cloud, double time_s) {
  Impl& m = *impl_;
  if (!(time_s > m.last_time_s) || !std::isfinite(time_s)) {
    throw std::invalid_argument("scan times must be finite and strictly increasing (" + std::to_string(time_s) + " after " +
                                std::to_string(m.last_time_s) + ")");
  }
  const auto start = Clock::now();
  Localization3dResult result;
  result.scan = m.scans;
  result.time_s = time_s;
  const ScanInput in = m.prepare(cloud, time_s, result);
  m.last_time_s = time_s;
  if (m.state == Localization3dState::kTracking) {
    m.track(in, result, summary_);
  } else {
    m.search(in, result, summary_);
  }
  if (!result.localised) result.health = core::Health::kLost;
  result.total_s = seconds_since(start);
  m.count(result, summary_);
  ++m.scans;
  return result;
}

}  // namespace cairn::lidar3d
