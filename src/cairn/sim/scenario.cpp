#include "cairn/sim/scenario.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/graph_io.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/sim/carmen_log.hpp"
#include "cairn/sim/gnss_outputs.hpp"
#include "cairn/sim/imu_outputs.hpp"
#include "cairn/sim/landmark_files.hpp"
#include "cairn/sim/planar_kinematics.hpp"
#include "cairn/sim/random.hpp"
#include "cairn/sim/ray_cast.hpp"
#include "cairn/sim/render.hpp"
#include "cairn/sim/street_run.hpp"
#include "cairn/sim/world_file.hpp"

namespace cairn::sim {
namespace {

/// Sub-stream numbers for Random::derive_seed: one per consumer of randomness.
enum Stream : std::uint64_t {
  kOdometryStream = 1,
  kLidarStream = 2,
  kLandmarkStream = 3,
  kGraphStream = 4,
  kRelationsStream = 5,
  kImuStream = 6,
  kGnssStream = 7
};

/// Applies the named IMU preset's noise, rates, ranges and bias sigmas (time offset and seed stay).
void apply_imu_preset(const std::string& name, ImuSimulationOptions& imu) {
  const std::optional<ImuSimulationOptions> preset = imu_preset(name);
  if (!preset) return;  // is_valid reports the name
  const double time_offset_s = imu.time_offset_s;
  const std::optional<inertial::ImuBias> initial_bias = imu.initial_bias;
  imu = *preset;
  imu.time_offset_s = time_offset_s;
  imu.initial_bias = initial_bias;
}

/// `period / sample` as a whole number of samples, or 0 when it is not one (to 1e-6).
std::int64_t whole_steps(double period_s, double sample_s) {
  const double ratio = period_s / sample_s;
  const double rounded = std::round(ratio);
  if (rounded < 1.0 || std::abs(ratio - rounded) > 1e-6 * rounded) return 0;
  return static_cast<std::int64_t>(rounded);
}

core::SE3 to_se3(const core::SE2& T) {
  return core::SE3(Quaternion(Eigen::AngleAxisd(T.angle(), Vector3::UnitZ())), Vector3(T.x(), T.y(), 0.0));
}

void write_tum_file(const std::string& path, const std::vector<core::Timestamp>& stamps,
                    const std::vector<core::SE2>& poses) {
  io::Trajectory trajectory;
  trajectory.stamps = stamps;
  for (const auto& T : poses) trajectory.poses.push_back(to_se3(T));
  io::write_tum(path, trajectory);
}

/// The mission ground truth of a finished 2D run (Scenario::is_mission); `path_m` is the driven
/// path up to each ground-truth sample.
MissionTruth mission_truth(const Scenario& scenario, const SimulationResult& result, const std::vector<double>& path_m) {
  MissionTruth truth;
  truth.regions = result.world.regions;
  truth.outside_region = result.world.outside_region;
  truth.doors = result.world.doors;
  truth.few_returns = scenario.few_returns;
  truth.revisit_options = scenario.revisits;
  ScanTruth scans;
  for (std::size_t i = 0; i < result.scan_samples.size(); ++i) {
    const std::size_t k = result.scan_samples[i];
    scans.T_world_body.push_back(result.truth[k].T_world_body);
    // Divided, not multiplied by 1e-9: 134.2 s reads 134.2 in the manifest, not 134.20000000000002.
    scans.times_s.push_back(static_cast<double>(result.truth[k].stamp.nanoseconds()) / 1e9);
    scans.path_m.push_back(path_m[k]);
    scans.returns.push_back(static_cast<int>(std::count_if(result.scans[i].begin(), result.scans[i].end(),
                                                           [&](double r) { return r < scenario.lidar.max_range_m; })));
  }
  std::vector<std::size_t> breaks;
  if (!result.carried_samples.empty()) {
    KidnapEvent event;
    event.first_sample_after = result.carried_samples.front();
    event.last_sample_before = event.first_sample_after - 1;
    // Scans are taken at samples; the first at or after the jump sees the drop place.
    const auto first_scan = std::lower_bound(result.scan_samples.begin(), result.scan_samples.end(), event.first_sample_after);
    event.first_scan_after = static_cast<std::size_t>(first_scan - result.scan_samples.begin());
    event.last_scan_before = event.first_scan_after - 1;
    const TrajectorySample& before = result.truth[event.last_sample_before];
    const TrajectorySample& after = result.truth[event.first_sample_after];
    event.stamp_before = before.stamp;
    event.stamp_after = after.stamp;
    event.T_world_body_before = before.T_world_body;
    event.T_world_body_after = after.T_world_body;
    event.T_odom_body_before = result.odometry.poses[event.last_sample_before];
    event.T_odom_body_after = result.odometry.poses[event.first_sample_after];
    truth.kidnap = event;
    breaks.push_back(event.first_scan_after);
  }
  truth.segments = find_segments(result.world, scans, scenario.few_returns, breaks);
  truth.revisits = find_revisits(scans, scenario.revisits);
  truth.absence = find_absence(truth.segments, scenario.revisits, scans);
  if (scenario.second_session) {
    // The session it pairs with starts where building-yard does, facing its first leg.
    const WorldWithRoute first = building_yard_world(scenario.office, scenario.building_yard);
    const Vector2 leg = first.route[1] - first.route[0];
    truth.session = SessionStart{"building-yard", scenario.session_start.place, result.truth.front().T_world_body,
                                 core::SE2(first.route[0].x(), first.route[0].y(), std::atan2(leg.y(), leg.x()))};
  }
  return truth;
}

/// "problem (found X)" with X the shortest text of `value`.
std::string found(const std::string& problem, double value) {
  std::string text = problem + " (found ";
  io::append_number(text, value);
  return text + ")";
}

/// The rules of the mission scenarios' own settings (kidnap, yard, path, wings, session).
void check_mission(const Scenario& s, std::vector<std::string>& problems) {
  std::string text;
  const bool office_ok = [&] {
    std::vector<std::string> office_problems;
    check_office_options(s.office, "office", office_problems);
    return office_problems.empty();
  }();
  // Doors in a building's outer wall open on the side corridors beside the block: wide enough to
  // drive through 0.3 m clear of the jambs on the corner arcs, and inside the block's height.
  auto check_door = [&](double width_m, const std::string& field) {
    if (!(width_m >= 1.2 && width_m <= s.office.block_depth_m)) {
      problems.push_back(found(field + " must be in [1.2, office.block_depth_m]", width_m));
    }
  };
  // A second floor beside the first (building 2, east wing): reported only when the first is right.
  auto check_second_floor = [&](int rooms_per_row, double width_m, const std::string& prefix) {
    if (!office_ok) return;
    OfficeOptions second = s.office;
    second.rooms_per_row = rooms_per_row;
    second.width_m = width_m;
    check_office_options(second, prefix, problems);
  };
  if (s.is_mission()) {
    if (!s.revisits.is_valid(&text)) problems.push_back("revisits: " + text);
    if (s.few_returns < 1 || s.few_returns > 100000) problems.push_back("segments.few_returns must be in [1, 100000]");
  }
  if (s.world == WorldKind::kBuildingYard || s.world == WorldKind::kOutdoorStretch || s.world == WorldKind::kTwoWings) {
    if (s.trajectory.laps != 1) {
      problems.push_back(s.name + " drives its route once (it ends elsewhere than it starts): trajectory.laps must be 1");
    }
  }
  if (s.world == WorldKind::kBuildingYard) {
    const BuildingYardOptions& y = s.building_yard;
    check_door(y.door_width_m, "building_yard.door_width_m");
    if (!(y.yard_offset_m >= 5.0 && y.yard_offset_m <= 500.0)) {
      problems.push_back(found("building_yard.yard_offset_m must be in [5, 500]", y.yard_offset_m));
    }
    if (y.features < 0 || y.features > 30) problems.push_back("building_yard.features must be in [0, 30]");
    if (s.second_session && office_ok && !OfficeFloor(s.office).place_center(s.session_start.place)) {
      std::string names;
      for (const auto& n : OfficeFloor(s.office).place_names()) names += (names.empty() ? "" : ", ") + n;
      problems.push_back("session.start_place must be one of " + names + " (found '" + s.session_start.place + "')");
    }
  }
  if (s.world == WorldKind::kOutdoorStretch) {
    const OutdoorStretchOptions& o = s.outdoor;
    if (!(o.path_length_m >= 40.0 && o.path_length_m <= 2000.0)) {
      problems.push_back(found("outdoor.path_length_m must be in [40, 2000]", o.path_length_m));
    }
    check_door(o.door_width_m, "outdoor.door_width_m");
    if (o.features < 0 || o.features > 30) problems.push_back("outdoor.features must be in [0, 30]");
    check_second_floor(o.building_2_rooms_per_row, o.building_2_width_m, "building_2");
  }
  if (s.world == WorldKind::kTwoWings) {
    const TwoWingOptions& w = s.wings;
    check_door(w.door_width_m, "long_absence.door_width_m");
    if (!(w.connector_length_m >= 4.0 && w.connector_length_m <= 500.0)) {
      problems.push_back(found("long_absence.connector_length_m must be in [4, 500]", w.connector_length_m));
    }
    if (!(w.connector_width_m >= w.door_width_m && w.connector_width_m <= s.office.block_depth_m)) {
      problems.push_back(found("long_absence.connector_width_m must be in [door_width_m, office.block_depth_m]",
                               w.connector_width_m));
    }
    if (w.away_laps < 1 || w.away_laps > 20) problems.push_back("long_absence.away_laps must be in [1, 20]");
    check_second_floor(w.east_wing_rooms_per_row, w.east_wing_width_m, "east_wing");
  }
  if (s.kidnap_enabled) {
    if (!(s.kidnap.time_s > 0.0)) problems.push_back(found("kidnap.time_s must be > 0", s.kidnap.time_s));
    if (s.kidnap.rings_after < 1 || s.kidnap.rings_after > 5) {
      problems.push_back("kidnap.rings_after must be in [1, 5] (found " + std::to_string(s.kidnap.rings_after) + ")");
    }
    if (office_ok && !OfficeFloor(s.office).place_center(s.kidnap.drop_place)) {
      std::string names;
      for (const auto& n : OfficeFloor(s.office).place_names()) names += (names.empty() ? "" : ", ") + n;
      problems.push_back("kidnap.drop_place must be one of " + names + " (found '" + s.kidnap.drop_place + "')");
    }
  }
}

/// The kidnap must happen while the office laps are driven, far enough from the drop place.
void check_kidnap_time(const Scenario& s, const WorldWithRoute& built, std::vector<std::string>& problems) {
  const TrajectoryOptions options = s.effective_trajectory();
  const std::vector<TrajectorySample> before = generate_trajectory(built.route, options, built.closed_route);
  const double duration_s = before.back().stamp.seconds() - before.front().stamp.seconds();
  if (s.kidnap.time_s >= duration_s - options.sample_period_s) {
    std::string end;
    io::append_number(end, std::floor(duration_s - options.sample_period_s));
    problems.push_back(found("kidnap.time_s must be below " + end + " s, when the office laps (trajectory.laps) end",
                             s.kidnap.time_s));
    return;
  }
  const auto k = static_cast<std::size_t>(std::floor(s.kidnap.time_s / options.sample_period_s + 1e-9));
  const Vector2 picked_up = before[std::min(k, before.size() - 1)].T_world_body.translation();
  const Vector2 drop = *OfficeFloor(s.office).place_center(s.kidnap.drop_place);
  const double jump_m = (drop - picked_up).norm();
  if (jump_m < KidnapOptions::kMinimumJumpM) {
    std::string distance;
    io::append_number(distance, std::round(jump_m * 100.0) / 100.0);
    problems.push_back("kidnap: at kidnap.time_s the robot is only " + distance + " m from the centre of " +
                       s.kidnap.drop_place + "; choose another time or kidnap.drop_place (at least 3 m apart)");
  }
}

/// The simulated IMU's parameters (3D worlds): imu.preset first (apply_assignments applies it
/// before the other imu.* settings, whatever their order).
void add_imu_parameters(Scenario& s, std::vector<Parameter>& out) {
  ImuSimulationOptions& imu = s.imu;
  out.push_back(Parameter{"imu.enabled", "", "simulate the IMU (imu0/, state_groundtruth_estimate0/, lidar0/sensor.yaml)",
                          &s.imu_enabled});
  out.push_back(Parameter{"imu.preset", "", "IMU preset: adis16448 (EuRoC) or consumer-mems (MPU-9250 class); sets noise, "
                          "rate, ranges and bias sigmas (other imu.* settings override it)",
                          &s.imu_preset, imu_preset_names(), [&s] { apply_imu_preset(s.imu_preset, s.imu); }});
  const auto add = [&](const char* name, const char* unit, const char* description, double* field) {
    out.push_back(Parameter{name, unit, description, field});
  };
  add("imu.rate_hz", "Hz", "samples per second", &imu.rate_hz);
  add("imu.gyro_noise_density", "rad/s/sqrt(Hz)", "gyro white noise density (0: none)", &imu.noise.gyro_noise_density);
  add("imu.gyro_random_walk", "rad/s^2/sqrt(Hz)", "gyro bias random walk (0: none)", &imu.noise.gyro_random_walk);
  add("imu.accel_noise_density", "m/s^2/sqrt(Hz)", "accelerometer white noise density (0: none)",
      &imu.noise.accel_noise_density);
  add("imu.accel_random_walk", "m/s^3/sqrt(Hz)", "accelerometer bias random walk (0: none)", &imu.noise.accel_random_walk);
  add("imu.initial_gyro_bias_sigma_rad_s", "rad/s", "sigma of each axis of the drawn initial gyro bias",
      &imu.initial_gyro_bias_sigma_rad_s);
  add("imu.initial_accel_bias_sigma_mps2", "m/s^2", "sigma of each axis of the drawn initial accelerometer bias",
      &imu.initial_accel_bias_sigma_mps2);
  add("imu.gyro_saturation_rad_s", "rad/s", "gyro range: readings clipped to +-this (0: none)", &imu.gyro_saturation_rad_s);
  add("imu.accel_saturation_mps2", "m/s^2", "accelerometer range: readings clipped to +-this (0: none)",
      &imu.accel_saturation_mps2);
  add("imu.time_offset_s", "s", "IMU clock minus true time: imu0/data.csv stamps are true time + this", &imu.time_offset_s);
}

/// The simulated GNSS receiver's parameters (3D worlds).
void add_gnss_parameters(Scenario& s, std::vector<Parameter>& out) {
  GnssReceiverOptions& gnss = s.gnss;
  const auto add = [&](const char* name, const char* unit, const char* description, auto* field) {
    out.push_back(Parameter{name, unit, description, field});
  };
  add("gnss.enabled", "", "simulate the GNSS receiver at the LiDAR's origin (gnss/fixes.csv, gnss/truth.csv)",
      &s.gnss_enabled);
  add("gnss.rate_hz", "Hz", "fixes per second", &gnss.rate_hz);
  add("gnss.sigma_horizontal_m", "m", "Gaussian noise of east and north (> 0)", &gnss.sigma_horizontal_m);
  add("gnss.sigma_vertical_m", "m", "Gaussian noise of up (> 0)", &gnss.sigma_vertical_m);
  add("gnss.outlier_fraction", "", "fraction of fixes that jump (0-1)", &gnss.outlier_fraction);
  add("gnss.outlier_min_m", "m", "smallest jump, in a uniformly random 3D direction", &gnss.outlier_min_m);
  add("gnss.outlier_max_m", "m", "largest jump", &gnss.outlier_max_m);
  add("gnss.world_yaw_deg", "deg", "the world's x axis is this far counter-clockwise from east: T_enu_world = R_z(yaw)",
      &s.gnss_world_yaw_deg);
  add("gnss.dropout_start_s", "s", "start of a window without fixes, seconds from the first stamp (0 and 0: none)",
      &s.gnss_dropout_start_s);
  add("gnss.dropout_end_s", "s", "its end (exclusive)", &s.gnss_dropout_end_s);
}

/// True when `p_world_m` projects on the passage's axis between its entry (0) and its exit
/// (length_m): the rule of find_passage_scans.
bool inside_passage(const Passage3D& passage, const Vector3& p_world_m) {
  const double along_m = passage.axis.dot(p_world_m.head<2>() - passage.entry);
  return along_m >= 0.0 && along_m <= passage.length_m;
}

/// The GNSS receiver of a 3D run: fixes of the LiDAR's origin along the whole ground truth, none
/// inside the world's tunnel. Needs result.truth and result.passage_scans.
SimulatedGnss simulate_scenario_gnss(const Scenario& scenario, std::uint64_t gnss_seed, const SimulationResult& result) {
  GnssReceiverOptions options = scenario.effective_gnss();
  options.seed = gnss_seed;
  if (result.passage_scans && result.passage_scans->passage.kind == "tunnel") {
    options.sky_visible = [tunnel = result.passage_scans->passage](const Vector3& p_world_m) {
      return !inside_passage(tunnel, p_world_m);
    };
  }
  std::vector<core::Timestamp> stamps;
  std::vector<core::SE3> T_world_lidar;
  for (const TrajectorySample& sample : result.truth) {
    stamps.push_back(sample.stamp);
    T_world_lidar.push_back(lidar_pose(sample.T_world_body, scenario.lidar3d));
  }
  return simulate_gnss_receiver(stamps, T_world_lidar, options);
}

/// The GNSS settings' rules (3D worlds with the GNSS on); the receiver's own checks name its fields.
void check_gnss(const Scenario& s, std::vector<std::string>& problems) {
  GnssReceiverOptions receiver = s.effective_gnss();
  receiver.dropouts_s.clear();  // reported below, by the parameters' names
  std::string text;
  if (!receiver.is_valid(&text)) problems.push_back("gnss: " + text);
  if (!(s.gnss_world_yaw_deg >= -360.0 && s.gnss_world_yaw_deg <= 360.0)) {
    problems.push_back(found("gnss.world_yaw_deg must be in [-360, 360]", s.gnss_world_yaw_deg));
  }
  const bool no_dropout = s.gnss_dropout_start_s == 0.0 && s.gnss_dropout_end_s == 0.0;
  if (!no_dropout && !(s.gnss_dropout_start_s >= 0.0 && s.gnss_dropout_start_s < s.gnss_dropout_end_s &&
                       std::isfinite(s.gnss_dropout_end_s))) {
    problems.push_back("gnss.dropout_start_s and gnss.dropout_end_s must be 0 and 0 (no dropout) or satisfy 0 <= start < end");
  }
}

}  // namespace

bool Scenario::is_valid(std::string* why) const {
  std::vector<std::string> problems;
  std::string text;
  if (!trajectory.is_valid(&text)) problems.push_back("trajectory: " + text);
  if (!odometry.is_valid(&text)) problems.push_back("odometry: " + text);
  if (!lidar.is_valid(&text)) problems.push_back("lidar: " + text);
  if (!landmarks.is_valid(&text)) problems.push_back("landmarks: " + text);
  if (!graph.is_valid(&text)) problems.push_back("graph: " + text);
  if (!relations.is_valid(&text)) problems.push_back("relations: " + text);
  if (trajectory.sample_period_s > 0.0) {
    if (whole_steps(lidar.period_s, trajectory.sample_period_s) == 0) {
      problems.push_back("lidar.period_s must be a whole multiple of trajectory.sample_period_s");
    }
    if (whole_steps(odometry_period_s, trajectory.sample_period_s) == 0) {
      problems.push_back("odometry_period_s must be a whole multiple of trajectory.sample_period_s");
    }
    if (whole_steps(landmarks.period_s, trajectory.sample_period_s) == 0) {
      problems.push_back("landmarks.period_s must be a whole multiple of trajectory.sample_period_s");
    }
  }
  if (!(image_pixels_per_m > 0.0 && image_pixels_per_m <= 200.0)) problems.push_back("image_pixels_per_m must be in (0, 200]");
  // `value` must be > `low` and at most 10 km (a world beyond that collapses its walls to points
  // in double precision, 1e308 overflows them); the message names the field and what was found.
  auto above = [&](double value, double low, const std::string& field) {
    if (!(value > low && value <= 1e4)) {
      std::string found;
      io::append_number(found, value);
      std::string bound;
      io::append_number(bound, low);
      problems.push_back(field + " must be in (" + bound + ", 10000] (found " + found + ")");
    }
  };
  switch (world) {
    case WorldKind::kOffice:
      check_office_options(office, "office", problems);
      break;
    case WorldKind::kCorridor:
      above(corridor.width_m, 1.0, "corridor.width_m");
      above(corridor.length_m, 4.0 * corridor.width_m + 4.0, "corridor.length_m");
      above(corridor.block_depth_m, 1.0, "corridor.block_depth_m");
      above(corridor.door_width_m, 0.0, "corridor.door_width_m");
      // A door wider than this opens before the corridor's inner wall begins (sim/world.cpp).
      if (corridor.door_width_m > 3.0) problems.push_back("corridor.door_width_m must be at most 3");
      above(corridor.door_pitch_m, corridor.door_width_m + 0.1, "corridor.door_pitch_m");
      above(corridor.door_recess_m, 0.0, "corridor.door_recess_m");
      break;
    case WorldKind::kOpenHall:
      above(open_hall.route_width_m, 1.0, "open_hall.route_width_m");
      above(open_hall.route_depth_m, 1.0, "open_hall.route_depth_m");
      above(open_hall.width_m, open_hall.route_width_m + 2.0, "open_hall.width_m");
      above(open_hall.depth_m, open_hall.route_depth_m + 2.0, "open_hall.depth_m");
      above(open_hall.pillar_radius_m, 0.0, "open_hall.pillar_radius_m");
      if (open_hall.pillars < 0 || open_hall.pillars > 8) problems.push_back("open_hall.pillars must be in [0, 8]");
      break;
    case WorldKind::kBuildingLoop:
      above(building.building_width_m, 10.0, "building.building_width_m");
      above(building.building_depth_m, 10.0, "building.building_depth_m");
      above(building.street_offset_m, 1.0, "building.street_offset_m");
      if (!(building.trees_per_m >= 0.0 && building.trees_per_m <= 2.0)) problems.push_back("building.trees_per_m must be in [0, 2]");
      break;
    case WorldKind::kLandmarkField:
      above(landmark_field.route_width_m, 1.0, "landmark_field.route_width_m");
      above(landmark_field.route_depth_m, 1.0, "landmark_field.route_depth_m");
      if (landmark_field.landmarks < 1 || landmark_field.landmarks > 100000) {
        problems.push_back("landmark_field.landmarks must be in [1, 100000]");
      }
      if (!(landmark_field.min_distance_from_route_m >= 0.3 &&
            landmark_field.max_distance_from_route_m > landmark_field.min_distance_from_route_m + 0.1)) {
        problems.push_back("landmark_field: need 0.3 <= min_distance_from_route_m < max_distance_from_route_m - 0.1");
      }
      if (!(landmark_field.post_radius_m >= 0.0 && landmark_field.post_radius_m < landmark_field.min_distance_from_route_m - 0.2)) {
        problems.push_back("landmark_field.post_radius_m must be in [0, min_distance_from_route_m - 0.2)");
      }
      break;
    case WorldKind::kBuildingYard:
    case WorldKind::kOutdoorStretch:
    case WorldKind::kTwoWings:
      check_office_options(office, "office", problems);
      break;
    case WorldKind::kStreet3D:
    case WorldKind::kGarage3D:
    case WorldKind::kTunnel3D:
      break;
  }
  check_mission(*this, problems);
  if (world == WorldKind::kStreet3D) {
      above(street.loop_width_m, 2.0 * street.street_half_width_m + 4.0, "street.loop_width_m");
      above(street.loop_depth_m, 2.0 * street.street_half_width_m + 4.0, "street.loop_depth_m");
      above(street.street_half_width_m, 4.0, "street.street_half_width_m");
      above(street.min_building_height_m, 0.0, "street.min_building_height_m");
      above(street.max_building_height_m, street.min_building_height_m, "street.max_building_height_m");
      above(street.pole_spacing_m, 2.0, "street.pole_spacing_m");
      above(street.tree_spacing_m, 2.0, "street.tree_spacing_m");
      if (street.parked_cars < 0 || street.parked_cars > 1000) problems.push_back("street.parked_cars must be in [0, 1000]");
      if (street.moving_cars < 0 || street.moving_cars > 20) problems.push_back("street.moving_cars must be in [0, 20]");
      above(street.moving_car_speed_mps, 0.0, "street.moving_car_speed_mps");
      if (street.reverse_second_lap) {
        if (!(street.reverse_lane_offset_m >= 0.0 && street.reverse_lane_offset_m <= street.street_half_width_m - 3.0)) {
          problems.push_back("street.reverse_lane_offset_m must be in [0, street_half_width_m - 3]");
        }
        if (trajectory.laps != 1) problems.push_back("street.reverse_second_lap drives both laps itself: trajectory.laps must be 1");
      }
  }
  if (world == WorldKind::kGarage3D) {
    if (!(garage.half_width_m >= 8.0 && garage.half_width_m <= 20.0)) problems.push_back("garage.half_width_m must be in [8, 20]");
    if (!(garage.ceiling_height_m >= 2.6 && garage.ceiling_height_m <= 10.0)) problems.push_back("garage.ceiling_height_m must be in [2.6, 10]");
    if (!(garage.bay_pitch_m >= 3.0 && garage.bay_pitch_m <= 30.0)) problems.push_back("garage.bay_pitch_m must be in [3, 30]");
    if (!(garage.length_m >= 4.0 * garage.bay_pitch_m && garage.length_m <= 2000.0)) {
      problems.push_back("garage.length_m must be in [4 bay_pitch_m, 2000]");
    }
    if (!(garage.approach_m >= 10.0 && garage.approach_m <= 200.0)) problems.push_back("garage.approach_m must be in [10, 200]");
  }
  if (world == WorldKind::kTunnel3D) {
    if (!(tunnel.length_m >= 20.0 && tunnel.length_m <= 2000.0)) problems.push_back("tunnel.length_m must be in [20, 2000]");
    if (!(tunnel.half_width_m >= 3.0 && tunnel.half_width_m <= 20.0)) problems.push_back("tunnel.half_width_m must be in [3, 20]");
    if (!(tunnel.height_m >= 3.0 && tunnel.height_m <= 20.0)) problems.push_back("tunnel.height_m must be in [3, 20]");
    if (!(tunnel.approach_m >= 10.0 && tunnel.approach_m <= 200.0)) problems.push_back("tunnel.approach_m must be in [10, 200]");
  }
  if (is_3d()) {
      above(loop_truth.max_distance_m, 0.0, "loops.max_distance_m");
      if (!(loop_truth.min_separation_s >= 0.0 && std::isfinite(loop_truth.min_separation_s))) {
        problems.push_back("loops.min_separation_s must be >= 0");
      }
      if (!lidar3d.is_valid(&text)) problems.push_back("lidar3d: " + text);
      if (lidar3d_model != "vlp16" && lidar3d_model != "hdl64") problems.push_back("lidar3d.model must be vlp16 or hdl64");
      if (lidar3d_format != "kitti" && lidar3d_format != "pcd") problems.push_back("lidar3d.format must be kitti or pcd");
      if (!camera.is_valid(&text)) problems.push_back("camera: " + text);
      if (imu_enabled) {
        if (!imu.is_valid(&text)) problems.push_back("imu: " + text);
        const auto presets = imu_preset_names();
        if (std::find(presets.begin(), presets.end(), imu_preset) == presets.end()) {
          problems.push_back("imu.preset must be adis16448 or consumer-mems");
        }
      }
      if (gnss_enabled) check_gnss(*this, problems);
      if (spin_stop_enabled) {
        if (!spin_stop.is_valid(&text)) problems.push_back("spin: " + text);
        if (trajectory.laps != 1) problems.push_back("spin: the route with a spin stop is driven once: trajectory.laps must be 1");
      }
      if (trajectory.sample_period_s > 0.0) {
        if (whole_steps(lidar3d.period_s, trajectory.sample_period_s) == 0) {
          problems.push_back("lidar3d.period_s must be a whole multiple of trajectory.sample_period_s");
        }
        if (whole_steps(camera.period_s, trajectory.sample_period_s) == 0) {
          problems.push_back("camera.period_s must be a whole multiple of trajectory.sample_period_s");
        }
      }
  }
  // A run of more than 20 km is almost surely a typo in a size, and would fill the memory.
  if (problems.empty()) {
    const WorldWithRoute built = build_world(*this);
    double lap_m = 0.0;
    const std::size_t legs = built.closed_route ? built.route.size() : built.route.size() - 1;
    for (std::size_t i = 0; i < legs; ++i) lap_m += (built.route[(i + 1) % built.route.size()] - built.route[i]).norm();
    if (lap_m * trajectory.laps > 20000.0) {
      problems.push_back("the route is " + std::to_string(static_cast<long>(lap_m * trajectory.laps)) +
                         " m long (laps x lap length): at most 20000 m");
    }
    if (problems.empty() && kidnap_enabled) check_kidnap_time(*this, built, problems);
    if (problems.empty() && spin_stop_enabled && !(spin_stop.at_m < lap_m - 1.0 && !built.closed_route)) {
      problems.push_back(found("spin.at_m must be at least 1 m short of the route's end (" +
                                   std::to_string(static_cast<long>(lap_m)) + " m)", spin_stop.at_m));
    }
  }
  if (why != nullptr) {
    why->clear();
    for (const auto& p : problems) *why += (why->empty() ? "" : "; ") + p;
  }
  return problems.empty();
}

TrajectoryOptions Scenario::effective_trajectory() const {
  TrajectoryOptions options = trajectory;
  if (fast_turns) {
    options.max_arc_turn_rad = 0.3;
    options.spin_yaw_rate_rad_s = 2.5;
    options.spin_yaw_acceleration_rad_s2 = 8.0;
  }
  return options;
}

GnssReceiverOptions Scenario::effective_gnss() const {
  GnssReceiverOptions options = gnss;
  const double yaw_rad = gnss_world_yaw_deg * std::numbers::pi / 180.0;
  options.T_enu_world = core::SE3(Quaternion(Eigen::AngleAxisd(yaw_rad, Vector3::UnitZ())), Vector3::Zero());
  if (gnss_dropout_start_s != 0.0 || gnss_dropout_end_s != 0.0) {
    options.dropouts_s.emplace_back(gnss_dropout_start_s, gnss_dropout_end_s);
  }
  return options;
}

std::vector<std::string> scenario_names() {
  return {"office",         "office-people",   "corridor-aliasing", "open-hall",  "loop-building",
          "landmarks",      "building-yard",   "outdoor-stretch",   "kidnapping", "long-absence",
          "second-session", "street-3d",       "street-3d-loops",   "garage-3d",  "tunnel-3d",
          "tunnel-spin-3d"};
}

std::optional<Scenario> make_scenario(std::string_view name) {
  Scenario s;
  s.name = std::string(name);
  if (name == "office") {
    s.world = WorldKind::kOffice;
    s.description = "Office floor: rooms on both sides of a ring corridor around a block of three rooms; "
                    "each lap drives the ring (visiting two rooms) and a second loop through the block";
  } else if (name == "office-people") {
    s.world = WorldKind::kOffice;
    s.office.people = 8;
    s.description = "The office with eight people walking back and forth in the corridors and two rooms: "
                    "moving objects that must not leave ghost trails in a map";
  } else if (name == "corridor-aliasing") {
    s.world = WorldKind::kCorridor;
    s.description = "Two 50 m corridors joined into a ring, identical recessed doors every 4 m on both "
                    "sides: perceptual aliasing (only the ends differ)";
  } else if (name == "open-hall") {
    s.world = WorldKind::kOpenHall;
    s.lidar.max_range_m = 10.0;
    s.description = "A 50 m x 40 m hall with four pillars, LiDAR range 10 m: scan matching is degenerate "
                    "most of the time";
  } else if (name == "loop-building") {
    s.world = WorldKind::kBuildingLoop;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 1.5;
    s.description = "One loop around a 40 m x 25 m building (recessed entrances, columns, trees, parked "
                    "cars), closed only at the end: drift, then one loop closure";
  } else if (name == "landmarks") {
    s.world = WorldKind::kLandmarkField;
    s.simulate_landmarks = true;
    s.description = "A rectangular loop through a field of 60 posts with known identities, seen by a "
                    "range-bearing sensor (and as small circles by the LiDAR)";
  } else if (name == "building-yard") {
    s.world = WorldKind::kBuildingYard;
    s.trajectory.laps = 1;
    s.image_pixels_per_m = 8.0;
    s.description = "The office building with doors A (west) and B (east) to an open yard with six trees, posts "
                    "and benches: a lap inside, out through A, round the yard 35 m from the walls (beyond the "
                    "LiDAR's range: scans with few or no returns), in through B, then corridors mapped on the lap";
  } else if (name == "outdoor-stretch") {
    s.world = WorldKind::kOutdoorStretch;
    s.trajectory.laps = 1;
    s.image_pixels_per_m = 6.0;
    s.description = "Two office buildings (4 and 3 rooms per row) joined by a 130 m outdoor path with four posts "
                    "and trees: map building 1, cross, drive building 2's ring, cross back, revisit building 1";
  } else if (name == "kidnapping") {
    s.world = WorldKind::kOffice;
    s.kidnap_enabled = true;
    s.trajectory.laps = 1;
    s.description = "The office: at kidnap.time_s the robot is carried into another room (the ground truth jumps, "
                    "the odometry shows no motion), then leaves it and drives the ring it mapped; see kidnap.txt";
  } else if (name == "long-absence") {
    s.world = WorldKind::kTwoWings;
    s.trajectory.laps = 1;
    s.image_pixels_per_m = 12.0;
    s.description = "Two office wings joined by a 16 m corridor: map the west wing, spend more than 5 minutes and "
                    "200 m in the east wing, come back and revisit the west wing (the absence is in the manifest)";
  } else if (name == "second-session") {
    s.world = WorldKind::kBuildingYard;
    s.second_session = true;
    s.trajectory.laps = 1;
    s.image_pixels_per_m = 8.0;
    s.description = "building-yard's world (same frame, walls and features), another route: from the middle room "
                    "facing west, the ring clockwise, through the middle room, into bottom room 1; localise it "
                    "in a map made from building-yard";
  } else if (name == "street-3d") {
    s.world = WorldKind::kStreet3D;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 4.0;
    s.trajectory.max_acceleration_mps2 = 1.0;
    s.trajectory.corner_radius_m = 6.0;
    s.image_pixels_per_m = 8.0;
    s.description = "A loop of streets around a city block: facades, lamp poles, trees and parked cars; a "
                    "spinning 16-ring LiDAR with per-point times (motion distortion) and a pinhole camera "
                    "seeing the lamps";
  } else if (name == "street-3d-loops") {
    s.world = WorldKind::kStreet3D;
    s.street.reverse_second_lap = true;
    s.street.moving_cars = 6;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 6.0;
    s.trajectory.max_acceleration_mps2 = 1.5;
    s.trajectory.corner_radius_m = 6.0;
    s.lidar3d_format = "pcd";
    s.image_pixels_per_m = 8.0;
    s.description = "The street loop driven twice: counter-clockwise on the centre line, then after a U-turn "
                    "clockwise one lane (3 m) further in (reverse revisits), with six cars driving around the "
                    "block; true loop closures in loops.txt";
  } else if (name == "garage-3d") {
    s.world = WorldKind::kGarage3D;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 4.0;
    s.trajectory.max_acceleration_mps2 = 1.0;
    s.lidar3d_format = "pcd";
    s.image_pixels_per_m = 5.0;
    s.description = "Straight through a 160 m parking garage whose pillars, beams and parked cars repeat every "
                    "8 m (perceptual aliasing); nothing is revisited, so every loop closure is false";
  } else if (name == "tunnel-3d") {
    s.world = WorldKind::kTunnel3D;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 6.0;
    s.trajectory.max_acceleration_mps2 = 1.5;
    s.lidar3d_format = "pcd";
    s.image_pixels_per_m = 5.0;
    s.description = "Straight through a 150 m tunnel with flat walls at constant speed: scan matching is "
                    "degenerate along the axis; the scans inside are listed in the manifest";
  } else if (name == "tunnel-spin-3d") {
    s.world = WorldKind::kTunnel3D;
    s.trajectory.laps = 1;
    s.trajectory.max_speed_mps = 6.0;
    s.trajectory.max_acceleration_mps2 = 1.5;
    s.lidar3d_format = "pcd";
    s.image_pixels_per_m = 5.0;
    s.spin_stop_enabled = true;
    s.description = "tunnel-3d with a stop in the middle of the tunnel (out of LiDAR range of both portals) for one "
                    "full turn on the spot in 0.99 s at up to 458 deg/s, meant to defeat LiDAR-only registration and "
                    "be carried by the IMU; the spin's times and scans are in the manifest";
  } else {
    return std::nullopt;
  }
  return s;
}

std::string Parameter::text() const {
  return std::visit(
      [](auto* field) -> std::string {
        using T = std::remove_pointer_t<decltype(field)>;
        if constexpr (std::is_same_v<T, bool>) {
          return *field ? "true" : "false";
        } else if constexpr (std::is_same_v<T, std::string>) {
          return *field;
        } else if constexpr (std::is_same_v<T, double>) {
          std::string out;
          io::append_number(out, *field);
          return out;
        } else {
          return std::to_string(*field);
        }
      },
      value);
}

bool Parameter::set(std::string_view input, std::string* why) {
  const bool ok = std::visit(
      [&](auto* field) -> bool {
        using T = std::remove_pointer_t<decltype(field)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!choices.empty() && std::find(choices.begin(), choices.end(), input) == choices.end()) {
            if (why) {
              std::string list;
              for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
              *why = name + " expects one of " + list + ", found '" + std::string(input) + "'";
            }
            return false;
          }
          *field = std::string(input);
          return true;
        } else if constexpr (std::is_same_v<T, bool>) {
          if (input == "true" || input == "1" || input == "on") *field = true;
          else if (input == "false" || input == "0" || input == "off") *field = false;
          else {
            if (why) *why = name + " expects true or false, found '" + std::string(input) + "'";
            return false;
          }
          return true;
        } else {
          T parsed{};
          const auto result = std::from_chars(input.data(), input.data() + input.size(), parsed);
          if (result.ec != std::errc() || result.ptr != input.data() + input.size()) {
            if (why) {
              *why = name + " expects " + (std::is_same_v<T, double> ? "a number" : "an integer") + ", found '" +
                     std::string(input) + "'";
            }
            return false;
          }
          if constexpr (std::is_same_v<T, double>) {
            if (!std::isfinite(parsed)) {
              if (why) *why = name + " must be finite, found '" + std::string(input) + "'";
              return false;
            }
          }
          *field = parsed;
          return true;
        }
      },
      value);
  if (ok && after_set) after_set();
  return ok;
}

std::vector<Parameter> parameters(Scenario& s) {
  std::vector<Parameter> out;
  auto add = [&](const char* name, const char* unit, const char* description, auto* field) {
    out.push_back(Parameter{name, unit, description, field});
  };
  // The office plan: the office itself, or the building(s) of a mission world (without people).
  auto add_office = [&](bool with_people) {
    add("office.rooms_per_row", "", "rooms in the bottom row and in the top row", &s.office.rooms_per_row);
    add("office.width_m", "m", "width of the floor", &s.office.width_m);
    add("office.room_depth_m", "m", "depth of each room row", &s.office.room_depth_m);
    add("office.corridor_width_m", "m", "width of the ring corridor", &s.office.corridor_width_m);
    add("office.block_depth_m", "m", "depth of the central block of three rooms", &s.office.block_depth_m);
    add("office.door_width_m", "m", "door opening", &s.office.door_width_m);
    if (with_people) {
      add("office.people", "", "people walking back and forth (0-8)", &s.office.people);
      add("office.furnished", "", "cabinets along the corridors and a shelf in every room at irregular places, which break "
          "the plan's half-turn symmetry (default plan only)", &s.office.furnished);
    }
  };
  switch (s.world) {
    case WorldKind::kOffice:
      add_office(true);
      if (s.kidnap_enabled) {
        add("kidnap.time_s", "s", "the robot is picked up this long after the start", &s.kidnap.time_s);
        add("kidnap.drop_place", "", "and put down at the centre of this room (bottom-room-<i>, top-room-<i>, middle-room)",
            &s.kidnap.drop_place);
        add("kidnap.drop_heading_rad", "rad", "facing this way (0 = east)", &s.kidnap.drop_heading_rad);
        add("kidnap.rings_after", "", "then drives round the ring corridor this many times (1-5)", &s.kidnap.rings_after);
      }
      break;
    case WorldKind::kBuildingYard:
      add_office(false);
      add("building_yard.door_width_m", "m", "width of doors A (west wall) and B (east wall)",
          &s.building_yard.door_width_m);
      add("building_yard.yard_offset_m", "m", "distance from the walls to the yard legs of the route",
          &s.building_yard.yard_offset_m);
      add("building_yard.features", "", "trees, posts and benches in the yard (0-30)", &s.building_yard.features);
      add("building_yard.world_seed", "", "seed of the features' places", &s.building_yard.world_seed);
      if (s.second_session) {
        add("session.start_place", "", "start at the centre of this room (bottom-room-<i>, top-room-<i>, middle-room)",
            &s.session_start.place);
        add("session.start_heading_rad", "rad", "facing this way (0 = east)", &s.session_start.heading_rad);
      }
      break;
    case WorldKind::kOutdoorStretch:
      add_office(false);
      add("outdoor.path_length_m", "m", "distance between the buildings' facing facades", &s.outdoor.path_length_m);
      add("outdoor.door_width_m", "m", "width of the door at each end of the path", &s.outdoor.door_width_m);
      add("outdoor.features", "", "trees, posts and benches along the path (0-30)", &s.outdoor.features);
      add("outdoor.world_seed", "", "seed of the features' places", &s.outdoor.world_seed);
      add("outdoor.glass_facades", "", "the facades facing the path are glass: the LiDAR sees through them except near "
          "their normal", &s.outdoor.glass_facades);
      add("building_2.rooms_per_row", "", "building 2: rooms per row (other sizes as office.*)",
          &s.outdoor.building_2_rooms_per_row);
      add("building_2.width_m", "m", "building 2: width", &s.outdoor.building_2_width_m);
      break;
    case WorldKind::kTwoWings:
      add_office(false);
      add("long_absence.away_laps", "", "laps of the east wing before going back (1-20)", &s.wings.away_laps);
      add("long_absence.connector_length_m", "m", "length of the corridor between the wings",
          &s.wings.connector_length_m);
      add("long_absence.connector_width_m", "m", "its width", &s.wings.connector_width_m);
      add("long_absence.door_width_m", "m", "width of the doors at its ends", &s.wings.door_width_m);
      add("east_wing.rooms_per_row", "", "east wing: rooms per row (other sizes as office.*)",
          &s.wings.east_wing_rooms_per_row);
      add("east_wing.width_m", "m", "east wing: width", &s.wings.east_wing_width_m);
      break;
    case WorldKind::kCorridor:
      add("corridor.length_m", "m", "length of each long corridor", &s.corridor.length_m);
      add("corridor.width_m", "m", "corridor width", &s.corridor.width_m);
      add("corridor.block_depth_m", "m", "depth of the block between the corridors", &s.corridor.block_depth_m);
      add("corridor.door_pitch_m", "m", "distance between neighbouring doors", &s.corridor.door_pitch_m);
      add("corridor.door_width_m", "m", "door opening", &s.corridor.door_width_m);
      add("corridor.door_recess_m", "m", "depth of the recess behind each door", &s.corridor.door_recess_m);
      break;
    case WorldKind::kOpenHall:
      add("open_hall.width_m", "m", "hall width", &s.open_hall.width_m);
      add("open_hall.depth_m", "m", "hall depth", &s.open_hall.depth_m);
      add("open_hall.pillars", "", "number of pillars (0-8)", &s.open_hall.pillars);
      add("open_hall.pillar_radius_m", "m", "pillar radius", &s.open_hall.pillar_radius_m);
      add("open_hall.route_width_m", "m", "width of the rectangular route", &s.open_hall.route_width_m);
      add("open_hall.route_depth_m", "m", "depth of the rectangular route", &s.open_hall.route_depth_m);
      break;
    case WorldKind::kBuildingLoop:
      add("building.building_width_m", "m", "building footprint width", &s.building.building_width_m);
      add("building.building_depth_m", "m", "building footprint depth", &s.building.building_depth_m);
      add("building.street_offset_m", "m", "distance from facade to route", &s.building.street_offset_m);
      add("building.trees_per_m", "1/m", "trees per metre of route", &s.building.trees_per_m);
      add("building.world_seed", "", "seed of the tree placement", &s.building.world_seed);
      break;
    case WorldKind::kLandmarkField:
      add("landmark_field.route_width_m", "m", "width of the rectangular route", &s.landmark_field.route_width_m);
      add("landmark_field.route_depth_m", "m", "depth of the rectangular route", &s.landmark_field.route_depth_m);
      add("landmark_field.landmarks", "", "number of landmarks", &s.landmark_field.landmarks);
      add("landmark_field.max_distance_from_route_m", "m", "landmarks lie at most this far from the route",
          &s.landmark_field.max_distance_from_route_m);
      add("landmark_field.min_distance_from_route_m", "m", "and at least this far",
          &s.landmark_field.min_distance_from_route_m);
      add("landmark_field.post_radius_m", "m", "radius of the post at each landmark (LiDAR-visible; 0 = none)",
          &s.landmark_field.post_radius_m);
      add("landmark_field.world_seed", "", "seed of the landmark placement", &s.landmark_field.world_seed);
      break;
    case WorldKind::kStreet3D:
      add("street.loop_width_m", "m", "width of the loop of street centre lines", &s.street.loop_width_m);
      add("street.loop_depth_m", "m", "depth of the loop of street centre lines", &s.street.loop_depth_m);
      add("street.street_half_width_m", "m", "centre line to facades", &s.street.street_half_width_m);
      add("street.min_building_height_m", "m", "lowest building", &s.street.min_building_height_m);
      add("street.max_building_height_m", "m", "highest building", &s.street.max_building_height_m);
      add("street.pole_spacing_m", "m", "distance between lamp poles", &s.street.pole_spacing_m);
      add("street.tree_spacing_m", "m", "distance between trees", &s.street.tree_spacing_m);
      add("street.parked_cars", "", "parked cars along the outer kerb", &s.street.parked_cars);
      add("street.world_seed", "", "seed of building sizes and car places", &s.street.world_seed);
      add("street.reverse_second_lap", "", "drive the loop again clockwise in the inner lane (open route)",
          &s.street.reverse_second_lap);
      add("street.reverse_lane_offset_m", "m", "inner lane of the reverse lap, from the centre line",
          &s.street.reverse_lane_offset_m);
      add("street.moving_cars", "", "cars driving clockwise around the block (0-20)", &s.street.moving_cars);
      add("street.moving_car_speed_mps", "m/s", "their speed", &s.street.moving_car_speed_mps);
      break;
    case WorldKind::kGarage3D:
      add("garage.length_m", "m", "length of the garage", &s.garage.length_m);
      add("garage.half_width_m", "m", "aisle centre to side walls (8-20)", &s.garage.half_width_m);
      add("garage.ceiling_height_m", "m", "ceiling height", &s.garage.ceiling_height_m);
      add("garage.bay_pitch_m", "m", "distance between pillars: the period of the structure", &s.garage.bay_pitch_m);
      add("garage.approach_m", "m", "street before and after the garage", &s.garage.approach_m);
      add("garage.world_seed", "", "seed of the buildings, poles and trees outside", &s.garage.world_seed);
      break;
    case WorldKind::kTunnel3D:
      add("tunnel.length_m", "m", "length of the tunnel", &s.tunnel.length_m);
      add("tunnel.half_width_m", "m", "centre line to either wall", &s.tunnel.half_width_m);
      add("tunnel.height_m", "m", "ceiling height", &s.tunnel.height_m);
      add("tunnel.approach_m", "m", "road before and after the tunnel", &s.tunnel.approach_m);
      add("tunnel.world_seed", "", "seed of the buildings, poles and trees outside", &s.tunnel.world_seed);
      if (s.spin_stop_enabled) {
        add("spin.at_m", "m", "where the robot stops to spin, along the route from its start", &s.spin_stop.at_m);
        add("spin.turns", "", "full counter-clockwise turns on the spot", &s.spin_stop.turns);
        add("spin.yaw_rate_rad_s", "rad/s", "peak yaw rate of the spin", &s.spin_stop.yaw_rate_rad_s);
        add("spin.yaw_acceleration_rad_s2", "rad/s^2", "yaw acceleration of the spin's ramps",
            &s.spin_stop.yaw_acceleration_rad_s2);
      }
      break;
  }
  TrajectoryOptions& t = s.trajectory;
  add("trajectory.laps", "", "times the route is driven", &t.laps);
  add("trajectory.max_speed_mps", "m/s", "top forward speed", &t.max_speed_mps);
  add("trajectory.max_acceleration_mps2", "m/s^2", "largest |dv/dt|", &t.max_acceleration_mps2);
  add("trajectory.max_yaw_rate_rad_s", "rad/s", "largest yaw rate on arcs", &t.max_yaw_rate_rad_s);
  add("trajectory.corner_radius_m", "m", "radius of corner arcs", &t.corner_radius_m);
  add("trajectory.max_arc_turn_rad", "rad", "sharper corners become turns on the spot", &t.max_arc_turn_rad);
  add("trajectory.spin_yaw_rate_rad_s", "rad/s", "yaw rate of turns on the spot", &t.spin_yaw_rate_rad_s);
  add("trajectory.spin_yaw_acceleration_rad_s2", "rad/s^2", "yaw acceleration of turns on the spot",
      &t.spin_yaw_acceleration_rad_s2);
  add("trajectory.sample_period_s", "s", "ground-truth sample period", &t.sample_period_s);
  add("trajectory.start_time_s", "s", "time stamp of the first sample", &t.start_time_s);
  add("trajectory.fast_turns", "", "every corner > 0.3 rad becomes a 2.5 rad/s spin", &s.fast_turns);
  OdometryNoise& o = s.odometry;
  add("odometry.period_s", "s", "time between ODOM records", &s.odometry_period_s);
  add("odometry.forward_sigma_m_per_sqrt_m", "m/sqrt(m)", "forward noise per sqrt(metre)", &o.forward_sigma_m_per_sqrt_m);
  add("odometry.lateral_sigma_m_per_sqrt_m", "m/sqrt(m)", "lateral noise per sqrt(metre)", &o.lateral_sigma_m_per_sqrt_m);
  add("odometry.yaw_sigma_rad_per_sqrt_rad", "rad/sqrt(rad)", "yaw noise per sqrt(radian turned)",
      &o.yaw_sigma_rad_per_sqrt_rad);
  add("odometry.yaw_sigma_rad_per_sqrt_m", "rad/sqrt(m)", "yaw noise per sqrt(metre travelled)", &o.yaw_sigma_rad_per_sqrt_m);
  add("odometry.scale_error", "", "relative wheel-radius error", &o.scale_error);
  add("odometry.yaw_scale_error", "", "relative error of turned angles", &o.yaw_scale_error);
  add("odometry.yaw_bias_rad_per_m", "rad/m", "yaw drift per metre", &o.yaw_bias_rad_per_m);
  add("odometry.slip_rate_per_s", "1/s", "slip events per second", &o.slip_rate_per_s);
  add("odometry.slip_duration_s", "s", "duration of a slip", &o.slip_duration_s);
  add("odometry.slip_max_excess", "", "largest over-reported translation fraction during a slip", &o.slip_max_excess);
  if (s.is_3d()) {
    Lidar3DOptions& l3 = s.lidar3d;
    out.push_back(Parameter{"lidar3d.model", "", "sensor preset: vlp16 or hdl64 (sets rings, elevations, columns, "
                            "max range; other lidar3d.* settings override it)", &s.lidar3d_model, {"vlp16", "hdl64"},
                            [&s] { apply_lidar3d_model(s.lidar3d_model, s.lidar3d); }});
    out.push_back(Parameter{"lidar3d.format", "", "scan files: kitti (velodyne/*.bin) or pcd (scans/*.pcd with ring, time)",
                            &s.lidar3d_format, {"kitti", "pcd"}});
    add("lidar3d.rings", "", "number of rings", &l3.rings);
    add("lidar3d.elevation_min_rad", "rad", "elevation of the lowest ring", &l3.elevation_min_rad);
    add("lidar3d.elevation_max_rad", "rad", "elevation of the highest ring", &l3.elevation_max_rad);
    add("lidar3d.columns", "", "firings per revolution", &l3.columns);
    add("lidar3d.period_s", "s", "time of one revolution (= between clouds)", &l3.period_s);
    add("lidar3d.max_range_m", "m", "max range", &l3.max_range_m);
    add("lidar3d.range_sigma_m", "m", "Gaussian range noise", &l3.range_sigma_m);
    add("lidar3d.dropout_probability", "", "probability a ray returns no point", &l3.dropout_probability);
    add("lidar3d.mount_height_m", "m", "sensor height above the body origin", &l3.mount_height_m);
    CameraOptions& c = s.camera;
    add("camera.fx", "px", "focal length x", &c.fx);
    add("camera.fy", "px", "focal length y", &c.fy);
    add("camera.cx", "px", "principal point x", &c.cx);
    add("camera.cy", "px", "principal point y", &c.cy);
    add("camera.width", "px", "image width", &c.width);
    add("camera.height", "px", "image height", &c.height);
    add("camera.pixel_sigma", "px", "Gaussian pixel noise", &c.pixel_sigma);
    add("camera.max_range_m", "m", "farthest landmark seen", &c.max_range_m);
    add("camera.mount_height_m", "m", "camera height above the body origin", &c.mount_height_m);
    add("camera.period_s", "s", "time between images", &c.period_s);
    add("loops.max_distance_m", "m", "loops.txt lists scan pairs at most this far apart", &s.loop_truth.max_distance_m);
    add("loops.min_separation_s", "s", "and at least this far apart in time", &s.loop_truth.min_separation_s);
    add_imu_parameters(s, out);
    add_gnss_parameters(s, out);
  } else {
    LidarOptions& l = s.lidar;
    add("lidar.beams", "", "number of beams", &l.beams);
    add("lidar.angle_min_rad", "rad", "angle of the first beam", &l.angle_min_rad);
    add("lidar.angle_increment_rad", "rad", "angle between beams", &l.angle_increment_rad);
    add("lidar.max_range_m", "m", "max range (no return reads this)", &l.max_range_m);
    add("lidar.range_sigma_m", "m", "Gaussian range noise", &l.range_sigma_m);
    add("lidar.dropout_probability", "", "probability a beam reads max range", &l.dropout_probability);
    add("lidar.range_decimals", "", "decimals readings are rounded to (-1: none)", &l.range_decimals);
    add("lidar.forward_offset_m", "m", "laser position ahead of the body origin", &l.forward_offset_m);
    add("lidar.period_s", "s", "time between scans", &l.period_s);
    add("landmarks.enabled", "", "run the range-bearing landmark sensor", &s.simulate_landmarks);
    RangeBearingOptions& r = s.landmarks;
    add("landmarks.max_range_m", "m", "farthest landmark seen", &r.max_range_m);
    add("landmarks.field_of_view_rad", "rad", "full field of view", &r.field_of_view_rad);
    add("landmarks.range_sigma_m", "m", "range noise", &r.range_sigma_m);
    add("landmarks.bearing_sigma_rad", "rad", "bearing noise", &r.bearing_sigma_rad);
    add("landmarks.detection_probability", "", "probability a visible landmark is reported", &r.detection_probability);
    add("landmarks.occlusion", "", "walls and circles hide landmarks", &r.occlusion);
    add("landmarks.period_s", "s", "time between observations", &r.period_s);
    GraphOptions& g = s.graph;
    add("graph.node_spacing_m", "m", "new node after this much travel", &g.node_spacing_m);
    add("graph.node_spacing_rad", "rad", "or this much turning", &g.node_spacing_rad);
    add("graph.odometry_sigma_xy_m", "m", "odometry edge noise (x, y)", &g.odometry_sigma_xy_m);
    add("graph.odometry_sigma_theta_rad", "rad", "odometry edge noise (theta)", &g.odometry_sigma_theta_rad);
    add("graph.loop_sigma_xy_m", "m", "loop edge noise (x, y)", &g.loop_sigma_xy_m);
    add("graph.loop_sigma_theta_rad", "rad", "loop edge noise (theta)", &g.loop_sigma_theta_rad);
    add("graph.loop_radius_m", "m", "loop closures between nodes at most this far apart", &g.loop_radius_m);
    add("graph.loop_max_heading_difference_rad", "rad", "and this different in heading", &g.loop_max_heading_difference_rad);
    add("graph.loop_min_separation_s", "s", "and this far apart in time", &g.loop_min_separation_s);
    add("graph.loop_every_n_nodes", "", "loop search at every n-th node", &g.loop_every_n_nodes);
    add("graph.false_loops", "", "number of false loop closures added", &g.false_loops);
    add("graph.false_loop_min_distance_m", "m", "false loops join nodes at least this far apart", &g.false_loop_min_distance_m);
    RelationsOptions& rel = s.relations;
    add("relations.short_interval_s", "s", "time between the scans of a short relation", &rel.short_interval_s);
    add("relations.long_count", "", "largest number of long relations", &rel.long_count);
    add("relations.long_min_separation_s", "s", "long relations join scans at least this far apart in time",
        &rel.long_min_separation_s);
    add("relations.long_max_distance_m", "m", "and at most this far apart in space", &rel.long_max_distance_m);
    add("relations.long_max_heading_difference_rad", "rad", "and this different in heading",
        &rel.long_max_heading_difference_rad);
    add("relations.long_candidate_spacing_s", "s", "scans considered for long relations are this far apart",
        &rel.long_candidate_spacing_s);
    if (s.is_mission()) {
      add("revisits.max_distance_m", "m", "revisits.txt: scans at most this far from an earlier one",
          &s.revisits.max_distance_m);
      add("revisits.min_separation_s", "s", "and at least this much later", &s.revisits.min_separation_s);
      add("segments.few_returns", "", "segments.txt counts scans with fewer returns than this", &s.few_returns);
    }
  }
  add("image.pixels_per_m", "px/m", "scale of world.png", &s.image_pixels_per_m);
  return out;
}

WorldWithRoute build_world(const Scenario& scenario) {
  switch (scenario.world) {
    case WorldKind::kOffice: {
      WorldWithRoute office = office_world(scenario.office);
      if (scenario.kidnap_enabled) {
        office.regions = {{"office", OfficeFloor(scenario.office).bounds()}};
      }
      return office;
    }
    case WorldKind::kCorridor: return corridor_world(scenario.corridor);
    case WorldKind::kOpenHall: return open_hall_world(scenario.open_hall);
    case WorldKind::kBuildingLoop: return building_loop_world(scenario.building);
    case WorldKind::kLandmarkField: return landmark_field_world(scenario.landmark_field);
    case WorldKind::kBuildingYard:
      return scenario.second_session
                 ? building_yard_second_session(scenario.office, scenario.building_yard, scenario.session_start)
                 : building_yard_world(scenario.office, scenario.building_yard);
    case WorldKind::kOutdoorStretch: return outdoor_stretch_world(scenario.office, scenario.outdoor);
    case WorldKind::kTwoWings: return two_wing_world(scenario.office, scenario.wings);
    case WorldKind::kStreet3D:
    case WorldKind::kGarage3D:
    case WorldKind::kTunnel3D: {
      const World3DWithRoute built = build_world_3d(scenario);
      WorldWithRoute flat;
      flat.world = footprint(built.world);
      flat.route = built.route;
      flat.closed_route = built.closed_route;
      return flat;
    }
  }
  CAIRN_ASSERT(false, "build_world: unknown world kind");
  return {};
}

World3DWithRoute build_world_3d(const Scenario& scenario) {
  switch (scenario.world) {
    case WorldKind::kStreet3D: return street_world(scenario.street);
    case WorldKind::kGarage3D: return garage_world(scenario.garage);
    case WorldKind::kTunnel3D: return tunnel_world(scenario.tunnel);
    default: break;
  }
  CAIRN_ASSERT(false, "build_world_3d: not a 3D world");
  return {};
}

SimulationResult simulate(const Scenario& scenario, std::uint64_t seed) {
  CAIRN_ASSERT(scenario.is_valid(nullptr), "simulate: invalid scenario (check is_valid first)");
  SimulationResult result;
  result.world = build_world(scenario);
  const World& world = result.world.world;
  const TrajectoryOptions trajectory = scenario.effective_trajectory();
  if (scenario.kidnap_enabled) {
    // The office laps up to the pick-up, then, one sample later, the route from the drop place.
    const std::vector<TrajectorySample> before =
        generate_trajectory(result.world.route, trajectory, result.world.closed_route);
    TrajectoryOptions after_options = trajectory;
    after_options.laps = 1;
    const std::vector<Vector2> route =
        route_after_drop(OfficeFloor(scenario.office), scenario.kidnap.drop_place, scenario.kidnap.rings_after);
    const std::vector<TrajectorySample> after =
        generate_trajectory(route, after_options, false, scenario.kidnap.drop_heading_rad);
    std::size_t first_after = 0;
    result.truth = splice_kidnap(before, after, scenario.kidnap.time_s, &first_after);
    result.carried_samples = {first_after};
  } else if (scenario.spin_stop_enabled) {
    SpinEvent spin;
    result.truth = trajectory_with_spin_stop(result.world.route, trajectory, scenario.spin_stop, &spin);
    result.spin = spin;
  } else {
    result.truth = generate_trajectory(result.world.route, trajectory, result.world.closed_route,
                                       result.world.start_heading_rad);
  }
  result.odometry = simulate_odometry(result.truth, scenario.odometry, Random::derive_seed(seed, kOdometryStream),
                                      result.carried_samples);

  const auto odometry_step = static_cast<std::size_t>(whole_steps(scenario.odometry_period_s, trajectory.sample_period_s));
  const auto scan_step = static_cast<std::size_t>(whole_steps(scenario.lidar.period_s, trajectory.sample_period_s));
  const auto landmark_step = static_cast<std::size_t>(whole_steps(scenario.landmarks.period_s, trajectory.sample_period_s));
  for (std::size_t k = 0; k < result.truth.size(); k += odometry_step) result.odometry_samples.push_back(k);
  for (std::size_t k = 0; k < result.truth.size(); k += scan_step) result.scan_samples.push_back(k);

  if (scenario.is_3d()) {
    result.scan_samples.clear();
    const auto cloud_step = static_cast<std::size_t>(whole_steps(scenario.lidar3d.period_s, trajectory.sample_period_s));
    for (std::size_t k = 0; k < result.truth.size(); k += cloud_step) result.scan_samples.push_back(k);
    simulate_street_sensors(scenario, Random::derive_seed(seed, kLidarStream), Random::derive_seed(seed, kLandmarkStream),
                            result);
    std::vector<core::SE3> T_world_lidar;
    std::vector<double> times_s;
    for (std::size_t k : result.scan_samples) {
      T_world_lidar.push_back(lidar_pose(result.truth[k].T_world_body, scenario.lidar3d));
      times_s.push_back(result.truth[k].stamp.seconds());
    }
    result.true_loops = find_true_loops(T_world_lidar, times_s, scenario.loop_truth);
    const World3DWithRoute built = build_world_3d(scenario);
    if (built.passage) {
      result.passage_scans = find_passage_scans(*built.passage, T_world_lidar, times_s, scenario.lidar3d.max_range_m);
    }
    if (scenario.imu_enabled) {
      ImuSimulationOptions imu = scenario.imu;
      imu.seed = Random::derive_seed(seed, kImuStream);
      result.imu = simulate_imu(PlanarKinematics(result.truth), result.truth.front().stamp.seconds(),
                                result.truth.back().stamp.seconds(), imu);
    }
    if (scenario.gnss_enabled) result.gnss = simulate_scenario_gnss(scenario, Random::derive_seed(seed, kGnssStream), result);
  } else {
    Random lidar_random(Random::derive_seed(seed, kLidarStream));
    const core::SE2 T_body_laser = scenario.lidar.T_body_laser();
    std::size_t max_range_readings = 0;
    std::size_t readings = 0;
    for (std::size_t k : result.scan_samples) {
      const core::SE2 T_world_laser = result.truth[k].T_world_body * T_body_laser;
      const double time_s = result.truth[k].stamp.seconds();
      result.scans.push_back(
          add_scan_noise(ideal_scan(world, T_world_laser, scenario.lidar, time_s), scenario.lidar, lidar_random));
      for (double r : result.scans.back()) max_range_readings += r == scenario.lidar.max_range_m ? 1 : 0;
      readings += result.scans.back().size();
    }
    result.max_range_fraction = readings > 0 ? static_cast<double>(max_range_readings) / static_cast<double>(readings) : 0.0;

    if (scenario.simulate_landmarks) {
      Random landmark_random(Random::derive_seed(seed, kLandmarkStream));
      for (std::size_t k = 0; k < result.truth.size(); k += landmark_step) {
        const auto seen = observe_landmarks(world, result.truth[k].T_world_body, result.truth[k].stamp, scenario.landmarks,
                                            landmark_random);
        result.landmark_observations.insert(result.landmark_observations.end(), seen.begin(), seen.end());
      }
    }

    result.graph = build_graph(result.truth, result.scan_samples, scenario.graph, Random::derive_seed(seed, kGraphStream));
    result.relations =
        make_relations(result.truth, result.scan_samples, scenario.relations, Random::derive_seed(seed, kRelationsStream));
  }

  result.duration_s = static_cast<double>(result.truth.back().stamp.nanoseconds() - result.truth.front().stamp.nanoseconds()) * 1e-9;
  // The driven path: a carry is not driven.
  std::vector<double> path_m(result.truth.size(), 0.0);
  for (std::size_t k = 1; k < result.truth.size(); ++k) {
    const bool carried = std::binary_search(result.carried_samples.begin(), result.carried_samples.end(), k);
    path_m[k] = path_m[k - 1] + (carried ? 0.0
                                         : (result.truth[k].T_world_body.translation() -
                                            result.truth[k - 1].T_world_body.translation())
                                               .norm());
  }
  result.path_length_m = path_m.back();
  if (scenario.is_mission()) result.mission = mission_truth(scenario, result, path_m);
  const core::SE2 final_error = result.truth.back().T_world_body.inverse() * result.odometry.poses.back();
  result.dead_reckoning_final_error_m = final_error.translation().norm();
  result.dead_reckoning_final_error_rad = std::abs(final_error.angle());
  for (std::size_t k = 0; k < result.truth.size(); ++k) {
    result.dead_reckoning_max_error_m =
        std::max(result.dead_reckoning_max_error_m,
                 (result.truth[k].T_world_body.translation() - result.odometry.poses[k].translation()).norm());
  }
  result.min_clearance_m = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < result.truth.size(); k += 10) {
    result.min_clearance_m = std::min(result.min_clearance_m, world.clearance(result.truth[k].T_world_body.translation()));
  }
  return result;
}

std::vector<std::string> write_outputs(const SimulationResult& result, const Scenario& scenario, std::uint64_t seed,
                                       const std::string& directory) {
  namespace fs = std::filesystem;
  std::vector<std::string> files;
  auto path_of = [&](const std::string& name) {
    files.push_back(name);
    return (fs::path(directory) / name).string();
  };
  if (scenario.is_3d()) {
    files = write_street_outputs(result, scenario, directory);
    std::vector<Vector2> truth_points;
    std::vector<Vector2> odometry_points;
    for (std::size_t k = 0; k < result.truth.size(); k += 5) {
      truth_points.push_back(result.truth[k].T_world_body.translation());
      odometry_points.push_back(result.odometry.poses[k].translation());
    }
    RenderOptions render;
    render.pixels_per_m = scenario.image_pixels_per_m;
    render.title = scenario.name + ", seed " + std::to_string(seed) + " (top view: footprints of buildings, cars, poles, trees)";
    render_png(path_of("world.png"), result.world.world, truth_points, odometry_points, render);
    if (scenario.imu_enabled) {
      for (const auto& name : write_imu_outputs(result, scenario, directory)) files.push_back(name);
    }
    if (scenario.gnss_enabled) {
      for (const auto& name : write_gnss_outputs(result, scenario, directory)) files.push_back(name);
    }
    return files;
  }

  CarmenLog log;
  log.comments.push_back("written by cairn simulate: scenario " + scenario.name + ", seed " + std::to_string(seed) +
                         "; FLASER poses are odometry, ground truth is in ground_truth.tum");
  log.lidar = scenario.lidar;
  for (std::size_t i = 0; i < result.odometry_samples.size(); ++i) {
    // tv and rv: the odometry's own motion since the previous record over the time between them
    // (0 at the first record), so they agree with the poses written beside them.
    const std::size_t k = result.odometry_samples[i];
    double speed = 0.0;
    double yaw_rate = 0.0;
    if (i > 0) {
      const std::size_t j = result.odometry_samples[i - 1];
      const double dt = static_cast<double>(result.truth[k].stamp.nanoseconds() - result.truth[j].stamp.nanoseconds()) * 1e-9;
      const core::SE2 motion = result.odometry.poses[j].inverse() * result.odometry.poses[k];
      speed = motion.x() / dt;
      yaw_rate = motion.angle() / dt;
    }
    log.odometry.push_back({result.truth[k].stamp, result.odometry.poses[k], speed, yaw_rate});
  }
  const core::SE2 T_body_laser = scenario.lidar.T_body_laser();
  for (std::size_t i = 0; i < result.scan_samples.size(); ++i) {
    const std::size_t k = result.scan_samples[i];
    log.scans.push_back({result.truth[k].stamp, result.scans[i], result.odometry.poses[k] * T_body_laser,
                         result.odometry.poses[k]});
  }
  write_carmen(path_of("log.clf"), log);
  write_relations(path_of("log.relations"), result.relations);

  std::vector<core::Timestamp> scan_stamps;
  std::vector<core::SE2> scan_truth;
  std::vector<core::SE2> scan_odometry;
  for (std::size_t k : result.scan_samples) {
    scan_stamps.push_back(result.truth[k].stamp);
    scan_truth.push_back(result.truth[k].T_world_body);
    scan_odometry.push_back(result.odometry.poses[k]);
  }
  write_tum_file(path_of("ground_truth.tum"), scan_stamps, scan_truth);
  write_tum_file(path_of("odometry.tum"), scan_stamps, scan_odometry);

  io::write_graph(path_of("graph.g2o"), io::PoseGraph(result.graph.graph), io::GraphFormat::kG2o);
  std::vector<core::Timestamp> node_stamps;
  for (std::size_t scan : result.graph.node_scans) node_stamps.push_back(result.truth[result.scan_samples[scan]].stamp);
  write_tum_file(path_of("graph_nodes.tum"), node_stamps, result.graph.truth);
  io::write_output(path_of("loop_closures.csv"), [&](std::ostream& out) {
    out << "from,to,kind\n";
    for (const auto& loop : result.graph.loops) out << loop.from << ',' << loop.to << ',' << (loop.is_false ? "false" : "true") << '\n';
  });

  write_world_file(path_of("world.txt"), result.world.world);
  if (scenario.simulate_landmarks) {
    write_landmark_map(path_of("landmarks.csv"), result.world.world.landmarks);
    write_landmark_observations(path_of("landmark_observations.csv"), result.landmark_observations);
  }
  if (result.mission) {
    const std::string comment = "written by cairn simulate: scenario " + scenario.name + ", seed " + std::to_string(seed);
    write_segments_file(path_of("segments.txt"), result.mission->segments, result.mission->few_returns, comment);
    write_revisits_file(path_of("revisits.txt"), result.mission->revisits, result.mission->revisit_options, comment);
    if (result.mission->kidnap) write_kidnap_file(path_of("kidnap.txt"), *result.mission->kidnap, comment);
  }

  std::vector<Vector2> truth_points;
  std::vector<Vector2> odometry_points;
  std::size_t next_carry = 0;
  for (std::size_t k = 0; k < result.truth.size(); k += 5) {
    // The path is not drawn across a carry.
    if (next_carry < result.carried_samples.size() && result.carried_samples[next_carry] <= k) {
      truth_points.push_back(Vector2::Constant(std::numeric_limits<double>::quiet_NaN()));
      ++next_carry;
    }
    truth_points.push_back(result.truth[k].T_world_body.translation());
    odometry_points.push_back(result.odometry.poses[k].translation());
  }
  RenderOptions render;
  render.pixels_per_m = scenario.image_pixels_per_m;
  std::ostringstream title;
  title << scenario.name << ", seed " << seed << ": " << static_cast<int>(std::round(result.path_length_m)) << " m in "
        << static_cast<int>(std::round(result.duration_s)) << " s";
  render.title = title.str();
  render_png(path_of("world.png"), result.world.world, truth_points, odometry_points, render);
  return files;
}

}  // namespace cairn::sim
