#pragma once
/// \file
/// Named scenarios: a world, a trajectory through it, the sensors and the derived files, with
/// every setting exposed as a named parameter (so `cairn simulate --list` shows them, `--set`
/// changes them and manifest.json records them). A scenario plus a seed fixes every output
/// byte: all randomness flows from the seed through Random::derive_seed, one stream per sensor.
///
/// | scenario          | world (world_builders.hpp)  | laps | notes                                     |
/// |-------------------|-----------------------------|------|-------------------------------------------|
/// | office            | office_world                | 2    | two loops per lap, room visits            |
/// | office-people     | office_world, 8 people      | 2    | moving objects (ghost trails)             |
/// | corridor-aliasing | corridor_world              | 2    | identical doors every 4 m                 |
/// | open-hall         | open_hall_world             | 2    | LiDAR max range 10 m: mostly nothing seen |
/// | loop-building     | building_loop_world         | 1    | one long loop closed at the end           |
/// | landmarks         | landmark_field_world        | 2    | range-bearing landmarks with identities   |
/// | building-yard     | building_yard_world         | 1    | out door A, round a blind yard, in door B |
/// | outdoor-stretch   | outdoor_stretch_world       | 1    | two buildings, a 130 m blind path between |
/// | kidnapping        | office_world + kidnap       | 1    | carried to another room at kidnap.time_s  |
/// | long-absence      | two_wing_world              | 1    | back in the west wing after > 5 min away  |
/// | second-session    | building_yard_second_session| 1    | building-yard's world, another start      |
/// | street-3d         | street_world (3D)           | 1    | spinning 3D LiDAR, pinhole camera         |
/// | street-3d-loops   | street_world (3D)           | 1    | 2nd lap reversed in another lane, traffic |
/// | garage-3d         | garage_world (3D)           | 1    | periodic garage: aliasing, no true loops  |
/// | tunnel-3d         | tunnel_world (3D)           | 1    | featureless straight tunnel: degeneracy   |
/// | tunnel-spin-3d    | tunnel_world (3D)           | 1    | tunnel-3d with a 458 deg/s spin inside    |
///
/// The 3D worlds also carry a simulated IMU (sim/imu.hpp, on unless imu.enabled=false) and a
/// simulated GNSS receiver at the LiDAR (sim/gnss_receiver.hpp, on unless gnss.enabled=false;
/// no fix inside a tunnel).

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include "cairn/sim/camera.hpp"
#include "cairn/sim/gnss_receiver.hpp"
#include "cairn/sim/ground_truth_3d.hpp"
#include "cairn/sim/imu.hpp"
#include "cairn/sim/landmark_sensor.hpp"
#include "cairn/sim/lidar_3d.hpp"
#include "cairn/sim/lidar.hpp"
#include "cairn/sim/mission_truth.hpp"
#include "cairn/sim/mission_worlds.hpp"
#include "cairn/sim/odometry.hpp"
#include "cairn/sim/passage_worlds.hpp"
#include "cairn/sim/relations.hpp"
#include "cairn/sim/simulated_graph.hpp"
#include "cairn/sim/spin_stop.hpp"
#include "cairn/sim/street_world.hpp"
#include "cairn/sim/trajectory.hpp"
#include "cairn/sim/world_builders.hpp"

namespace cairn::sim {

/// The 3D worlds (kStreet3D, kGarage3D, kTunnel3D) run the 3D LiDAR and the camera instead of
/// the 2D LiDAR, the landmark sensor, the pose graph and the relations.
enum class WorldKind {
  kOffice,
  kCorridor,
  kOpenHall,
  kBuildingLoop,
  kLandmarkField,
  kBuildingYard,
  kOutdoorStretch,
  kTwoWings,
  kStreet3D,
  kGarage3D,
  kTunnel3D
};

struct Scenario {
  std::string name;
  std::string description;
  WorldKind world = WorldKind::kOffice;
  /// Only the options of `world` are used (and listed).
  OfficeOptions office;
  CorridorOptions corridor;
  OpenHallOptions open_hall;
  BuildingLoopOptions building;
  LandmarkFieldOptions landmark_field;
  /// The mission worlds (mission_worlds.hpp) build their buildings (building-yard's, building 1 of
  /// outdoor-stretch, long-absence's west wing) from `office`, without its people.
  BuildingYardOptions building_yard;
  OutdoorStretchOptions outdoor;
  TwoWingOptions wings;
  /// second-session: building_yard's world driven from `session_start` instead of the
  /// building-yard route; it is to be localised against a map of building-yard.
  bool second_session = false;
  SessionStartOptions session_start;
  /// kidnapping: the office world; the robot is carried to kidnap.drop_place at kidnap.time_s.
  bool kidnap_enabled = false;
  KidnapOptions kidnap;
  /// Mission scenarios (is_mission): revisits.txt, and segments.txt counting the scans with
  /// fewer than `few_returns` readings below max range.
  RevisitOptions revisits;
  int few_returns = 10;
  StreetOptions street;
  GarageOptions garage;
  TunnelOptions tunnel;
  /// 3D sensors (3D worlds only). lidar3d_model names the last preset applied to lidar3d through
  /// the parameter lidar3d.model ("vlp16" or "hdl64", see apply_lidar3d_model); lidar3d.* settings
  /// may override parts of it, so the fields of lidar3d, not this name, describe the sensor.
  Lidar3DOptions lidar3d;
  std::string lidar3d_model = "vlp16";
  /// How the scans are written: "kitti" (velodyne/NNNNNN.bin float32 x y z intensity, plus
  /// velodyne_times/NNNNNN.bin) or "pcd" (scans/NNNNNN.pcd: binary PCD v0.7 with x y z
  /// intensity as float32, ring as uint16, time as float32 seconds after the sweep start).
  std::string lidar3d_format = "kitti";
  CameraOptions camera;
  /// Which scan pairs are listed as true loop closures (3D worlds; loops.txt).
  LoopTruthOptions loop_truth;
  /// 3D worlds: the simulated IMU (sim/imu.hpp) and its files (imu0/, state_groundtruth_estimate0/,
  /// lidar0/sensor.yaml). imu_preset names the last preset applied through the parameter
  /// imu.preset ("adis16448" or "consumer-mems", applied before every other imu.* setting); the
  /// fields of `imu`, not this name, describe the sensor. imu.seed is replaced by the run's IMU
  /// stream of the seed.
  bool imu_enabled = true;
  std::string imu_preset = "adis16448";
  ImuSimulationOptions imu;
  /// 3D worlds: the simulated GNSS receiver (sim/gnss_receiver.hpp) and its files (gnss/). The
  /// antenna is the LiDAR's origin: the receiver is given T_world_lidar, so gnss.lever_arm_body_m
  /// is in the LiDAR frame (default 0). gnss.T_enu_world and gnss.dropouts_s come from the two
  /// settings below (effective_gnss()); gnss.seed is replaced by the run's GNSS stream of the
  /// seed and gnss.sky_visible by the world's tunnel (no fix inside it).
  bool gnss_enabled = true;
  GnssReceiverOptions gnss;
  /// The world's x axis is this many degrees counter-clockwise from east: T_enu_world =
  /// R_z(gnss_world_yaw_deg), in [-360, 360].
  double gnss_world_yaw_deg = 30.0;
  /// One dropout window, seconds from the first stamp: [start, end) with 0 <= start < end, or
  /// 0 and 0 (default) for none.
  double gnss_dropout_start_s = 0.0;
  double gnss_dropout_end_s = 0.0;
  /// tunnel-spin-3d: a stop for a fast spin on the spot on the (open) route (sim/spin_stop.hpp).
  bool spin_stop_enabled = false;
  SpinStopOptions spin_stop;

  TrajectoryOptions trajectory;
  /// When true, every corner sharper than 0.3 rad becomes a spin at 2.5 rad/s (8 rad/s^2):
  /// overrides trajectory.max_arc_turn_rad, spin_yaw_rate_rad_s and spin_yaw_acceleration_rad_s2.
  bool fast_turns = false;
  OdometryNoise odometry;
  /// Time between ODOM records, seconds: a multiple of trajectory.sample_period_s.
  double odometry_period_s = 0.05;
  LidarOptions lidar;
  /// Whether the range-bearing landmark sensor runs (and its files are written).
  bool simulate_landmarks = false;
  RangeBearingOptions landmarks;
  GraphOptions graph;
  RelationsOptions relations;
  /// Picture scale, pixels per metre.
  double image_pixels_per_m = 20.0;

  /// Every option group's checks plus: sensor periods are whole multiples of the sample period.
  bool is_valid(std::string* why) const;
  /// The trajectory options after `fast_turns` is applied.
  TrajectoryOptions effective_trajectory() const;
  /// `gnss` with T_enu_world = R_z(gnss_world_yaw_deg) and the dropout window (if any) applied.
  GnssReceiverOptions effective_gnss() const;
  /// Whether the run writes the mission ground truth (segments.txt, revisits.txt, kidnap.txt and
  /// the manifest's ground_truth): building-yard, outdoor-stretch, kidnapping, long-absence,
  /// second-session.
  bool is_mission() const {
    return kidnap_enabled || world == WorldKind::kBuildingYard || world == WorldKind::kOutdoorStretch ||
           world == WorldKind::kTwoWings;
  }
  /// Whether the world is 3D (street, garage, tunnel).
  bool is_3d() const { return world == WorldKind::kStreet3D || world == WorldKind::kGarage3D || world == WorldKind::kTunnel3D; }
};

/// The scenario names, in the order `--list` shows them.
std::vector<std::string> scenario_names();
/// The named scenario with its defaults; nullopt for an unknown name.
std::optional<Scenario> make_scenario(std::string_view name);

/// One setting of a scenario, bound to its field.
struct Parameter {
  /// "group.field", e.g. "lidar.range_sigma_m".
  std::string name;
  std::string unit;
  std::string description;
  std::variant<double*, int*, bool*, std::uint64_t*, std::string*> value;
  /// For a text parameter: the values it accepts (empty: any).
  std::vector<std::string> choices = {};
  /// Called after every successful set() (a sensor model preset fills the fields it implies).
  std::function<void()> after_set = {};

  /// The value as text: shortest round-trip decimal for doubles, "true"/"false" for flags.
  std::string text() const;
  /// Parses `text` into the field; false (with a reason in `why`) when it does not parse.
  bool set(std::string_view text, std::string* why);
};

/// The parameters of `scenario` (its world's options and every sensor's), bound to its fields.
std::vector<Parameter> parameters(Scenario& scenario);

/// Everything one run produced, in memory.
struct SimulationResult {
  WorldWithRoute world;
  /// Ground truth at every trajectory sample.
  std::vector<TrajectorySample> truth;
  /// Dead reckoning at every sample.
  OdometryTrack odometry;
  /// Sample indices of ODOM records and of scans.
  std::vector<std::size_t> odometry_samples;
  std::vector<std::size_t> scan_samples;
  /// Noisy ranges per scan (scan k taken at truth[scan_samples[k]]).
  std::vector<std::vector<double>> scans;
  std::vector<LandmarkObservation> landmark_observations;
  SimulatedGraph graph;
  std::vector<Relation> relations;
  /// 3D worlds: the 3D world, one point cloud per revolution (starting at scan_samples[k]),
  /// camera observations.
  World3D world_3d;
  std::vector<std::vector<LidarPoint>> clouds;
  std::vector<CameraObservation> camera_observations;
  /// 3D worlds: the true loop closures between scans (Scenario::loop_truth), and the scans
  /// inside the world's passage (garage, tunnel).
  std::vector<TrueLoop> true_loops;
  std::optional<PassageScans> passage_scans;
  /// 3D worlds with the IMU on: its samples and the true state and biases at each.
  SimulatedImu imu;
  /// 3D worlds with the GNSS on: the fixes and their truth (ENU at gnss.origin); true time.
  SimulatedGnss gnss;
  /// tunnel-spin-3d: the spin on the spot.
  std::optional<SpinEvent> spin;
  /// Ground-truth samples whose step from the previous one was a carry (kidnapping): the truth
  /// jumps there, the odometry does not.
  std::vector<std::size_t> carried_samples;
  /// Mission scenarios: segments, revisits, absence, kidnap, second-session start.
  std::optional<MissionTruth> mission;

  /// Summary numbers (also written to the manifest).
  double duration_s = 0.0;
  /// Driven path, metres (a carry is not driven and not counted).
  double path_length_m = 0.0;
  /// |t| and |angle| of T_truth_end^-1 * T_odometry_end: how far dead reckoning ends off.
  double dead_reckoning_final_error_m = 0.0;
  double dead_reckoning_final_error_rad = 0.0;
  /// Largest position error of dead reckoning along the run, metres (the final error can be
  /// small by chance when a loop ends where it started).
  double dead_reckoning_max_error_m = 0.0;
  /// Fraction of all readings equal to max range (misses and dropouts).
  double max_range_fraction = 0.0;
  /// Smallest distance from any ground-truth position to a wall or circle, metres.
  double min_clearance_m = 0.0;
};

/// Runs `scenario` with `seed`. Precondition: scenario.is_valid().
SimulationResult simulate(const Scenario& scenario, std::uint64_t seed);

/// Writes every output file into `directory` (which must exist), atomically, and returns the
/// file names in the order written: log.clf, log.relations, ground_truth.tum, odometry.tum,
/// graph.g2o, graph_nodes.tum, loop_closures.csv, world.txt, [landmarks.csv,
/// landmark_observations.csv], [segments.txt, revisits.txt, [kidnap.txt]], world.png. street-3d writes instead: velodyne/NNNNNN.bin,
/// velodyne_times/NNNNNN.bin (or scans/NNNNNN.pcd), poses.txt, times.txt, ground_truth.tum,
/// odometry.tum, camera_observations.csv, world_3d.txt, loops.txt, world.png (see
/// docs/simulation.md); with the IMU on, then imu0/data.csv, imu0/sensor.yaml,
/// state_groundtruth_estimate0/data.csv and lidar0/sensor.yaml; with the GNSS on, then
/// gnss/fixes.csv and gnss/truth.csv. Throws io::ParseError when a file cannot be written.
std::vector<std::string> write_outputs(const SimulationResult& result, const Scenario& scenario, std::uint64_t seed,
                                       const std::string& directory);

/// Builds the scenario's world (no randomness beyond the world's own seed); for a 3D world, its
/// footprint (boxes reaching below 2.2 m as rectangles, cylinders as circles).
WorldWithRoute build_world(const Scenario& scenario);
/// Builds a 3D scenario's world. Precondition: scenario.is_3d().
World3DWithRoute build_world_3d(const Scenario& scenario);

}  // namespace cairn::sim
