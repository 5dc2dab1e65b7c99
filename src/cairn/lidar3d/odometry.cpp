#include "cairn/lidar3d/odometry.hpp"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Geometry>
#include <chrono>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "cairn/core/threads.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"

namespace cairn::lidar3d {
namespace {

using core::Clock;
using core::seconds_since;

// KISS-ICP's model error of a pose deviation (Vizzo et al. 2023, eq. 3): the largest
// displacement it causes on a point within max_range.
double model_error(const core::SE3& deviation, double max_range_m) {
  const double theta = deviation.so3().log().norm();
  return deviation.translation().norm() + 2.0 * max_range_m * std::sin(0.5 * theta);
}

}  // namespace

struct LidarOdometry::Arena {
  explicit Arena(int threads) : arena(core::arena_concurrency(threads)) {}
  tbb::task_arena arena;
};

bool LidarOdometryOptions::is_valid(std::string* error) const {
  core::Problems problems;
  auto fail = [&](const std::string& message) { problems.add(message); };
  if (!(max_range_m > 0.0) || !std::isfinite(max_range_m)) fail("max_range_m must be > 0");
  if (!(min_range_m >= 0.0) || !(min_range_m < max_range_m)) fail("min_range_m must be in [0, max_range_m)");
  if (!std::isfinite(vertical_angle_correction_rad) || std::abs(vertical_angle_correction_rad) > 0.1) {
    fail("vertical_angle_correction_rad must be within +-0.1 rad");
  }
  if (!(sweep_period_s > 0.0) || !std::isfinite(sweep_period_s)) fail("sweep_period_s must be > 0");
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) fail("voxel_size_m must be > 0");
  if (max_points_per_voxel < 1) fail("max_points_per_voxel must be >= 1");
  if (!(initial_threshold_m > 0.0) || !std::isfinite(initial_threshold_m)) fail("initial_threshold_m must be > 0");
  if (!(min_motion_m >= 0.0) || !std::isfinite(min_motion_m)) fail("min_motion_m must be >= 0");
  if (registration.max_iterations < 1) fail("registration.max_iterations must be >= 1");
  if (!(registration.convergence_step > 0.0)) fail("registration.convergence_step must be > 0");
  if (!(registration.degenerate_min_eigenvalue >= 0.0 && registration.degenerate_min_eigenvalue < 1.0 / 3.0)) {
    fail("registration.degenerate_min_eigenvalue must be in [0, 1/3)");
  }
  if (threads < 0) fail("threads must be >= 0 (0 = all)");
  if (std::string nested; !loam.is_valid(&nested)) fail(nested);
  if (min_scan_points < 0) fail("min_scan_points must be >= 0");
  if (!(lost_min_correspondence_fraction >= 0.0 && lost_min_correspondence_fraction <= 1.0)) {
    fail("lost_min_correspondence_fraction must be in [0, 1]");
  }
  if (!(lost_max_rms_voxels > 0.0 && std::isfinite(lost_max_rms_voxels))) fail("lost_max_rms_voxels must be a finite number > 0");
  if (!(lost_rms_max_correspondence_fraction >= 0.0 && lost_rms_max_correspondence_fraction <= 1.0)) {
    fail("lost_rms_max_correspondence_fraction must be in [0, 1]");
  }
  if (!(degraded_min_correspondence_fraction >= lost_min_correspondence_fraction &&
        degraded_min_correspondence_fraction <= 1.0)) {
    fail("degraded_min_correspondence_fraction must be in [lost_min_correspondence_fraction, 1]");
  }
  return problems.report(error);
}

Eigen::Vector3d correct_vertical_angle(const Eigen::Vector3d& p, double correction_rad) {
  return correct_vertical_angle(p, std::cos(correction_rad), std::sin(correction_rad));
}

// Rodrigues' formula about the unit axis k = (y, -x, 0) / r, r = |(x, y)|: k . p = 0, so
// p' = p cos + (k x p) sin with k x p = (-x z / r, -y z / r, r).
Eigen::Vector3d correct_vertical_angle(const Eigen::Vector3d& p, double cos_correction, double sin_correction) {
  // sqrt, not std::hypot: glibc's hypot guards against overflow (irrelevant for ranges in metres)
  // and cost 0.6 ms per KITTI scan of 120,000 points.
  const double r = std::sqrt(p.x() * p.x() + p.y() * p.y());
  if (!(r > 0.0)) return p;
  const double lift = p.z() * sin_correction / r;
  return {p.x() * (cos_correction - lift), p.y() * (cos_correction - lift), p.z() * cos_correction + r * sin_correction};
}

LidarOdometryOptions preset_options(std::string_view name) {
  LidarOdometryOptions options;
  if (name == "default") return options;
  if (name == "kitti") {
    options.vertical_angle_correction_rad = 0.205 * std::numbers::pi / 180.0;
    options.deskew = DeskewMode::kOff;
    options.rings_from_kitti_order = true;  // for --front-end loam
    options.front_end = FrontEnd::kDense;  // measured better on the real KITTI key frames
    return options;
  }
  throw std::invalid_argument("unknown preset '" + std::string(name) + "' (expected default or kitti)");
}

std::string_view to_string(FrontEnd front_end) {
  switch (front_end) {
    case FrontEnd::kAuto: return "auto";
    case FrontEnd::kDense: return "dense";
    case FrontEnd::kLoamFeatures: return "loam";
  }
  return "?";
}

std::string_view to_string(DeskewMode mode) {
  switch (mode) {
    case DeskewMode::kOff: return "off";
    case DeskewMode::kPointTimes: return "point-times";
    case DeskewMode::kAzimuth: return "azimuth";
  }
  return "?";
}

LidarOdometry::LidarOdometry(const LidarOdometryOptions& options)
    : options_(options),
      map_(VoxelHashMapOptions{options.voxel_size_m, options.max_points_per_voxel}),
      edge_map_(VoxelHashMapOptions{options.voxel_size_m, options.max_points_per_voxel}),
      plane_map_(VoxelHashMapOptions{options.voxel_size_m, options.max_points_per_voxel}) {
  std::string error;
  if (!options_.is_valid(&error)) throw std::invalid_argument("LidarOdometryOptions: " + error);
  arena_ = std::make_unique<Arena>(options_.threads);
}

LidarOdometry::~LidarOdometry() = default;

// The state one add_scan call shares between its stages.
struct LidarOdometry::ScanWork {
  double time_s = 0.0;  ///< the scan's stamp
  bool from_file = false;  ///< deskew with the file's per-point times
  bool deskew = false;
  bool loam = false;  ///< the LOAM front end (else dense)
  /// In range, corrected for the vertical angle, then deskewed; with their times and rings.
  std::vector<Eigen::Vector3d> points;
  std::vector<float> point_time;
  std::vector<std::uint16_t> point_ring;
  double tau_0 = 0.0, tau_mid = 0.0;  ///< the stamp's and the sweep middle's instants in the sweep
  double t_mid = 0.0;                 ///< time of the sweep's middle, where the scan is registered
  std::size_t n = 0;                  ///< poses before this scan
  Eigen::Matrix<double, 6, 1> velocity = Eigen::Matrix<double, 6, 1>::Zero();
  core::SE3 T_pred;
  std::vector<Eigen::Vector3d> frame, source;  ///< subsampled at 0.5 v (map) and 1.5 v (dense registration)
  LoamFeatures features;
  double sigma = 0.0;  ///< adaptive threshold
  bool too_few_points = false;
  bool lost = false;
  bool map_empty = false;
  core::SE3 T_world_sensor;  ///< at the sweep's middle
  const MotionPrior* prior = nullptr;  ///< an external prediction (add_scan's), or null
};

OdometryScanResult LidarOdometry::add_scan(const io::PointCloud& cloud, double time_s, const MotionPrior* prior) {
  if (!std::isfinite(time_s) || (!stamps_.empty() && !(time_s > stamps_.back()))) {
    throw std::invalid_argument("LidarOdometry::add_scan: scan times must be finite and strictly increasing");
  }
  const auto start = Clock::now();
  OdometryScanResult result;
  result.time_s = time_s;
  result.segment = segment_;
  result.points_read = cloud.size();
  ScanWork work;
  work.time_s = time_s;
  work.prior = prior;

  choose_point_times(cloud, work, result);
  choose_front_end(cloud);
  work.loam = front_end_ == FrontEnd::kLoamFeatures;
  crop_and_correct(cloud, work);
  result.points_in_range = work.points.size();
  sweep_instants(work);
  predict(work);
  preprocess(work);
  result.times.preprocess_s = seconds_since(start);

  work.sigma = adaptive_threshold();
  result.threshold_sigma_m = work.sigma;
  const auto register_start = Clock::now();
  register_to_map(work, result);
  result.times.register_s = seconds_since(register_start);

  const auto map_start = Clock::now();
  start_segment_if_lost(work, result);
  report_pose(work, result);
  update_map(work, result);
  result.times.map_s = seconds_since(map_start);
  record(work);
  result.times.total_s = seconds_since(start);
  return result;
}

LidarOdometry::PreparedScan LidarOdometry::prepare_scan(const io::PointCloud& cloud, double time_s,
                                                       const Eigen::Matrix<double, 6, 1>& velocity_per_s) const {
  if (!std::isfinite(time_s)) throw std::invalid_argument("LidarOdometry::prepare_scan: the scan time must be finite");
  OdometryScanResult checks;
  ScanWork work;
  work.time_s = time_s;
  work.velocity = velocity_per_s;
  choose_point_times(cloud, work, checks);
  crop_and_correct(cloud, work);  // work.loam stays false: no rings, no features
  sweep_instants(work);
  PreparedScan prepared;
  prepared.registered_time_s = work.t_mid;
  prepared.point_times_unusable = checks.point_times_unusable;
  arena_->arena.execute([&] {
    if (work.deskew && !velocity_per_s.isZero()) deskew_to_sweep_middle(work);
    prepared.frame_sensor = voxel_downsample(work.points, 0.5 * options_.voxel_size_m);
  });
  prepared.T_registered_stamp = core::SE3::exp(velocity_per_s * (work.tau_0 - work.tau_mid));
  return prepared;
}

// Step 2's times: the file's per-point times where usable (DeskewMode::kPointTimes), the
// azimuth's (kAzimuth), or none.
void LidarOdometry::choose_point_times(const io::PointCloud& cloud, ScanWork& work, OdometryScanResult& result) const {
  bool have_time = cloud.time_s.size() == cloud.size() && !cloud.time_s.empty();
  if (have_time) {
    // Times that cannot be offsets within one sweep from the stamp (absolute times, another unit)
    // would move the points anywhere: such a scan is used without deskew, and counted.
    const auto [lo, hi] = std::minmax_element(cloud.time_s.begin(), cloud.time_s.end());
    const double span = static_cast<double>(*hi) - static_cast<double>(*lo);
    const double limit = 2.0 * options_.sweep_period_s;
    if (!std::isfinite(span) || span > limit || std::abs(static_cast<double>(*lo)) > limit ||
        std::abs(static_cast<double>(*hi)) > limit) {
      have_time = false;
      result.point_times_unusable = options_.deskew == DeskewMode::kPointTimes;
    }
  }
  work.from_file = options_.deskew == DeskewMode::kPointTimes && have_time;
  work.deskew = work.from_file || options_.deskew == DeskewMode::kAzimuth;
}

// FrontEnd::kAuto decides once, at the first scan: LOAM's features when it has rings.
void LidarOdometry::choose_front_end(const io::PointCloud& cloud) {
  if (front_end_ == FrontEnd::kAuto) {
    front_end_ = options_.front_end != FrontEnd::kAuto ? options_.front_end
                 : (cloud.ring.size() == cloud.size() && cloud.size() > 0) || options_.rings_from_kitti_order
                     ? FrontEnd::kLoamFeatures
                     : FrontEnd::kDense;
  }
}

// The ring of each point, for the LOAM front end: the file's, or recovered from KITTI's point
// order into `recovered_rings`. Throws std::invalid_argument when there is neither.
const std::vector<std::uint16_t>* LidarOdometry::rings_of(const io::PointCloud& cloud, const ScanWork& work,
                                                          std::vector<std::uint16_t>& recovered_rings) const {
  const std::vector<std::uint16_t>* rings = &cloud.ring;
  if (work.loam && cloud.ring.size() != cloud.size()) {
    if (!options_.rings_from_kitti_order) {
      throw std::invalid_argument("the LOAM front end needs a ring per point (a ring field, or rings from KITTI's point order)");
    }
    io::PointCloud copy;
    copy.points = cloud.points;
    io::recover_kitti_ring_and_time(copy, options_.sweep_period_s);
    recovered_rings = std::move(copy.ring);
    rings = &recovered_rings;
  }
  return rings;
}

// Step 3's range crop [min_range_m, max_range_m], with the vertical-angle correction (p turned
// about p x z), keeping each point's time (step 2) and ring (LOAM).
void LidarOdometry::crop_and_correct(const io::PointCloud& cloud, ScanWork& work) const {
  const double min2 = options_.min_range_m * options_.min_range_m;
  const double max2 = options_.max_range_m * options_.max_range_m;
  std::vector<std::uint16_t> recovered_rings;
  const std::vector<std::uint16_t>* rings = rings_of(cloud, work, recovered_rings);
  std::vector<Eigen::Vector3d>& points = work.points;
  std::vector<float>& point_time = work.point_time;
  std::vector<std::uint16_t>& point_ring = work.point_ring;
  points.reserve(cloud.size());
  if (work.deskew) point_time.reserve(cloud.size());
  if (work.loam) point_ring.reserve(cloud.size());
  const double correction = options_.vertical_angle_correction_rad;
  const double cos_correction = std::cos(correction), sin_correction = std::sin(correction);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    Eigen::Vector3d p = cloud.points[i].cast<double>();
    const double r2 = p.squaredNorm();
    if (r2 < min2 || r2 > max2) continue;
    if (correction != 0.0) p = correct_vertical_angle(p, cos_correction, sin_correction);
    points.push_back(p);
    if (work.loam) point_ring.push_back((*rings)[i]);
    if (work.deskew) {
      point_time.push_back(work.from_file ? cloud.time_s[i]
                                          : static_cast<float>((std::numbers::pi - std::atan2(p.y(), p.x())) /
                                                               (2.0 * std::numbers::pi) * options_.sweep_period_s));
    }
  }
}

// Point times: tau_i in the sweep, the stamp's own tau_0, and the middle of the sweep tau_mid
// where the scan is registered. Registering at the middle keeps the deskew's mean displacement
// zero, so an error of the velocity does not shift the registered pose (with tau_0 = 0 it
// shifts it by half a sweep of that error, the next velocity inherits it with the opposite
// sign, and the estimate oscillates: measured on the simulated street, 1.6 m steps). The pose
// at the stamp is reported (after registration), the pose at the middle kept for prediction.
void LidarOdometry::sweep_instants(ScanWork& work) const {
  if (work.deskew && !work.point_time.empty()) {
    if (work.from_file) {
      const auto [lo, hi] = std::minmax_element(work.point_time.begin(), work.point_time.end());
      work.tau_mid = 0.5 * (static_cast<double>(*lo) + static_cast<double>(*hi));
    } else {
      work.tau_0 = work.tau_mid = 0.5 * options_.sweep_period_s;  // KITTI stamps facing forward
    }
  }
  work.t_mid = work.time_s + (work.tau_mid - work.tau_0);
  if (!times_.empty() && !(work.t_mid > times_.back())) work.t_mid = times_.back() + (work.time_s - stamps_.back());
}

// 1. Constant-velocity prediction from the last two poses (twist per second, at sweep middles).
void LidarOdometry::predict(ScanWork& work) const {
  const std::size_t n = work.n = poses_.size();
  if (n >= 2) {
    work.velocity = (poses_[n - 2].inverse() * poses_[n - 1]).log() / (times_[n - 1] - times_[n - 2]);
  }
  if (n >= 1) work.T_pred = poses_[n - 1] * core::SE3::exp(work.velocity * (work.t_mid - times_[n - 1]));
  if (work.prior != nullptr) work.T_pred = work.prior->at(work.t_mid);
}

// 2-3. Deskew to the sweep's middle, subsample; then LOAM's features, or the dense front end's
// points subsampled again at 1.5 v.
void LidarOdometry::preprocess(ScanWork& work) const {
  arena_->arena.execute([&] {
    if (work.deskew && work.prior != nullptr && !work.point_time.empty()) {
      deskew_with_prior(work);
    } else if (work.deskew && work.n >= 2) {
      deskew_to_sweep_middle(work);
    }
    work.frame = voxel_downsample(work.points, 0.5 * options_.voxel_size_m);
    if (work.loam) {
      work.features = extract_loam_features(work.points, work.point_ring, options_.loam);
    } else {
      work.source = voxel_downsample(work.frame, 1.5 * options_.voxel_size_m);
    }
  });
}

// 2. Deskew (KISS-ICP Sec. III-A): p taken at tau moves to exp(xi (tau - tau_mid)) p.
void LidarOdometry::deskew_to_sweep_middle(ScanWork& work) const {
  std::vector<Eigen::Vector3d>& points = work.points;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        points[i] = core::SE3::exp(work.velocity * (static_cast<double>(work.point_time[i]) - work.tau_mid)) * points[i];
                      }
                    });
}

// 2. Deskew with an external prior: p taken at t moves to T(t_mid)^-1 T(t) p, T the prior's pose.
void LidarOdometry::deskew_with_prior(ScanWork& work) const {
  std::vector<Eigen::Vector3d>& points = work.points;
  const core::SE3 T_mid_world = work.T_pred.inverse();
  const double sweep_start_s = work.time_s - work.tau_0;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096),
                    [&](const tbb::blocked_range<std::size_t>& range) {
                      for (std::size_t i = range.begin(); i != range.end(); ++i) {
                        const double t = sweep_start_s + static_cast<double>(work.point_time[i]);
                        points[i] = T_mid_world * (work.prior->at(t) * points[i]);
                      }
                    });
}

// 4. Adaptive threshold (KISS-ICP Sec. III-C, eq. 3-4): the RMS of the model errors so far.
double LidarOdometry::adaptive_threshold() const {
  return model_error_samples_ > 0 ? std::sqrt(model_error_sse_ / static_cast<double>(model_error_samples_))
                                  : options_.initial_threshold_m;
}

// 5. Registration to the local map from the prediction, unless the map is empty or the scan has
// too few points; then its health and the threshold's model error.
void LidarOdometry::register_to_map(ScanWork& work, OdometryScanResult& result) {
  work.T_world_sensor = work.T_pred;
  work.too_few_points = work.points.size() < static_cast<std::size_t>(options_.min_scan_points);
  work.lost = work.too_few_points && work.n > 0;
  work.map_empty = work.loam ? (edge_map_.empty() && plane_map_.empty()) : map_.empty();
  if (work.map_empty || work.too_few_points) return;
  arena_->arena.execute([&] {
    if (work.loam) {
      result.registration = register_loam(work);
    } else {
      result.registration = register_dense(work);
    }
  });
  assess_health(work, result);
  if (!work.lost) update_model_error(work);
}

// LOAM: sharp points against the line map, flat points against the plane map, degenerate
// directions always from the prediction.
RegistrationResult LidarOdometry::register_loam(const ScanWork& work) const {
  RegistrationOptions registration = options_.registration;
  registration.remap_degenerate_directions = true;
  return register_features(edge_map_, plane_map_, work.features.sharp, work.features.flat, work.T_pred,
                           3.0 * work.sigma, work.sigma / 3.0, registration);
}

// Dense (KISS-ICP): the points subsampled at 1.5 v against the voxel-hash map.
RegistrationResult LidarOdometry::register_dense(const ScanWork& work) const {
  return register_scan(map_, work.source, work.T_pred, 3.0 * work.sigma, work.sigma / 3.0, options_.registration);
}

// 6. Health of the registration: lost (then the prediction stands), degraded, or ok; a scan not
// lost takes the registered pose.
void LidarOdometry::assess_health(ScanWork& work, OdometryScanResult& result) const {
  const RegistrationResult& reg = result.registration;
  const double fraction =
      reg.source_points > 0 ? static_cast<double>(reg.correspondences) / static_cast<double>(reg.source_points) : 0.0;
  // A fit that explains few points badly is a wrong pose (e.g. the same street seen from the
  // other direction), not a weak one.
  const bool untrustworthy_fit = !work.loam && fraction < options_.lost_rms_max_correspondence_fraction &&
                                 reg.rms_m > options_.lost_max_rms_voxels * options_.voxel_size_m;
  work.lost = fraction < options_.lost_min_correspondence_fraction || reg.correspondences < 6 || untrustworthy_fit;
  if (work.lost) return;
  work.T_world_sensor = reg.T_map_sensor;
  if (reg.degenerate_directions > 0) {
    result.health = Health::kDegraded;
    result.degenerate_axis = name_direction(reg.weakest_direction, work.T_world_sensor.so3(), reg.characteristic_length_m);
  } else if (fraction < options_.degraded_min_correspondence_fraction || !reg.converged) {
    result.health = Health::kDegraded;
  }
}

// 4. The threshold's sample (KISS-ICP eq. 3): the model error of the deviation T_pred^-1 T_est,
// when above min_motion_m.
void LidarOdometry::update_model_error(const ScanWork& work) {
  const double error = model_error(work.T_pred.inverse() * work.T_world_sensor, options_.max_range_m);
  if (error > options_.min_motion_m) {
    model_error_sse_ += error * error;
    ++model_error_samples_;
  }
}

// 6. A lost scan starts a new segment from the predicted pose.
void LidarOdometry::start_segment_if_lost(const ScanWork& work, OdometryScanResult& result) {
  if (!work.lost) return;
  result.health = Health::kLost;
  // A new segment, unless the map is already empty (still blind since the last lost scan).
  if (!work.map_empty) {
    map_.clear();
    edge_map_.clear();
    plane_map_.clear();
    ++segment_;
  }
  result.segment = segment_;
}

// The pose at the stamp: from the middle back (or on) by the new velocity.
void LidarOdometry::report_pose(const ScanWork& work, OdometryScanResult& result) const {
  const std::size_t n = work.n;
  result.T_world_sensor = work.T_world_sensor;
  result.T_world_registered = work.T_world_sensor;
  result.registered_time_s = work.t_mid;
  if (work.tau_mid != work.tau_0 && work.prior != nullptr) {
    // The prior's motion from the middle to the stamp.
    result.T_world_sensor = work.T_world_sensor * (work.T_pred.inverse() * work.prior->at(work.time_s));
  } else if (work.tau_mid != work.tau_0 && n >= 1) {
    const Eigen::Matrix<double, 6, 1> new_velocity =
        (poses_[n - 1].inverse() * work.T_world_sensor).log() / (work.t_mid - times_[n - 1]);
    result.T_world_sensor = work.T_world_sensor * core::SE3::exp(new_velocity * (work.tau_0 - work.tau_mid));
  }
}

// 5. The scan's map points join the map (none when it had too few points) and voxels beyond
// max_range_m of the sensor leave it.
void LidarOdometry::update_map(ScanWork& work, OdometryScanResult& result) {
  const Eigen::Matrix3d R = work.T_world_sensor.rotation_matrix();
  const Eigen::Vector3d t = work.T_world_sensor.translation();
  if (work.too_few_points) work.frame.clear();
  last_frame_sensor_ = work.frame;
  for (Eigen::Vector3d& p : work.frame) p = R * p + t;
  if (work.loam) {
    update_loam_maps(work, R, t, result);
  } else {
    update_dense_map(work, t, result);
  }
}

// LOAM: less-sharp points join the line map, less-flat points the plane map.
void LidarOdometry::update_loam_maps(ScanWork& work, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                     OdometryScanResult& result) {
  LoamFeatures& features = work.features;
  if (work.too_few_points) features = {};
  for (Eigen::Vector3d& p : features.less_sharp) p = R * p + t;
  for (Eigen::Vector3d& p : features.less_flat) p = R * p + t;
  edge_map_.add_points(features.less_sharp);
  plane_map_.add_points(features.less_flat);
  edge_map_.remove_far_from(t, options_.max_range_m);
  plane_map_.remove_far_from(t, options_.max_range_m);
  result.map_points_added = features.less_sharp.size() + features.less_flat.size();
  result.local_map_points = edge_map_.num_points() + plane_map_.num_points();
}

// Dense: the scan's points subsampled at 0.5 v join the voxel-hash map.
void LidarOdometry::update_dense_map(const ScanWork& work, const Eigen::Vector3d& t, OdometryScanResult& result) {
  map_.add_points(work.frame);
  map_.remove_far_from(t, options_.max_range_m);
  result.map_points_added = work.frame.size();
  result.local_map_points = map_.num_points();
}

// The scan's pose at the sweep's middle, that time and its stamp, for the next prediction.
void LidarOdometry::record(const ScanWork& work) {
  poses_.push_back(work.T_world_sensor);
  times_.push_back(work.t_mid);
  stamps_.push_back(work.time_s);
}

}  // namespace cairn::lidar3d
