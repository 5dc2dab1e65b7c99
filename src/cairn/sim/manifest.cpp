#include "cairn/sim/manifest.hpp"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <variant>

#include "cairn/io/parse_error.hpp"
#include "cairn/sim/gnss_outputs.hpp"
#include "cairn/sim/imu_outputs.hpp"

namespace cairn::sim {
namespace {

/// FNV-1a, 64 bit (Fowler, Noll, Vo): a cheap fingerprint so two runs can be compared from
/// their manifests alone. Not a cryptographic hash.
std::uint64_t fnv1a64(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw io::ParseError(path, 0, "cannot read back the file just written");
  std::uint64_t hash = 0xcbf29ce484222325ULL;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof buffer) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      hash ^= static_cast<unsigned char>(buffer[i]);
      hash *= 0x100000001b3ULL;
    }
  }
  return hash;
}

std::string hex(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016" PRIx64, value);
  return text;
}

nlohmann::json parameter_json(Scenario& scenario) {
  nlohmann::json j = nlohmann::json::object();
  for (auto& p : parameters(scenario)) {
    nlohmann::json value;
    std::visit([&](auto* field) { value = *field; }, p.value);
    j[p.name] = {{"value", value}, {"unit", p.unit}};
  }
  return j;
}

nlohmann::json pose_json(const core::SE2& T) { return {{"x_m", T.x()}, {"y_m", T.y()}, {"theta_rad", T.angle()}}; }

nlohmann::json revisit_json(const Revisit& r) {
  return {{"scan", r.later},
          {"earlier_scan", r.earlier},
          {"distance_m", r.distance_m},
          {"heading_difference_rad", r.heading_difference_rad},
          {"time_difference_s", r.time_difference_s},
          {"path_between_m", r.path_between_m}};
}

/// The mission scenarios' ground truth (sim/mission_truth.hpp): regions with their scan counts,
/// doors, the segments, revisits, the longest absence, the kidnapping and the second session.
nlohmann::json mission_json(const MissionTruth& m) {
  nlohmann::json truth;
  nlohmann::json regions = nlohmann::json::array();
  std::vector<std::string> names;
  for (const auto& r : m.regions) names.push_back(r.name);
  if (!m.outside_region.empty()) names.push_back(m.outside_region);
  for (const auto& name : names) {
    nlohmann::json region = {{"name", name}};
    for (const auto& r : m.regions) {
      if (r.name == name) {
        region["min_world"] = {r.bounds.min.x(), r.bounds.min.y()};
        region["max_world"] = {r.bounds.max.x(), r.bounds.max.y()};
      }
    }
    if (name == m.outside_region) region["note"] = "everywhere outside the other regions";
    std::size_t scans = 0;
    std::size_t few = 0;
    for (const auto& s : m.segments) {
      if (s.region != name) continue;
      scans += s.last_scan - s.first_scan + 1;
      few += s.few_return_scans;
    }
    region["scans"] = scans;
    region["few_return_scans"] = few;
    regions.push_back(region);
  }
  truth["regions"] = regions;
  truth["few_returns"] = {{"threshold", m.few_returns},
                          {"definition", "a scan with fewer readings below max range than the threshold"}};
  nlohmann::json doors = nlohmann::json::array();
  for (const auto& d : m.doors) {
    doors.push_back({{"name", d.name},
                     {"center_world", {d.center.x(), d.center.y()}},
                     {"outward_world", {d.outward.x(), d.outward.y()}},
                     {"width_m", d.width_m}});
  }
  truth["doors"] = doors;
  nlohmann::json segments = nlohmann::json::array();
  for (const auto& s : m.segments) {
    segments.push_back({{"region", s.region},
                        {"scans", {s.first_scan, s.last_scan}},
                        {"time_s", {s.start_time_s, s.end_time_s}},
                        {"path_length_m", s.path_length_m},
                        {"few_return_scans", s.few_return_scans}});
  }
  truth["segments"] = {{"file", "segments.txt"}, {"list", segments}};
  truth["revisits"] = {{"file", "revisits.txt"},
                       {"criterion", "for every scan, the nearest earlier scan at most max_distance_m away and at "
                                     "least min_separation_s earlier (ground-truth body positions)"},
                       {"max_distance_m", m.revisit_options.max_distance_m},
                       {"min_separation_s", m.revisit_options.min_separation_s},
                       {"scans_with_a_revisit", m.revisits.size()}};
  if (m.absence) {
    const auto& a = *m.absence;
    nlohmann::json absence = {{"region", a.region},
                              {"definition", "the longest stretch outside the region the run starts in, between two "
                                             "stays in it"},
                              {"left_scan", a.left_scan},
                              {"returned_scan", a.returned_scan},
                              {"left_time_s", a.left_time_s},
                              {"returned_time_s", a.returned_time_s},
                              {"duration_s", a.duration_s},
                              {"path_length_m", a.path_length_m}};
    if (a.first_revisit) absence["first_revisit"] = revisit_json(*a.first_revisit);
    truth["absence"] = absence;
  }
  if (m.kidnap) {
    const auto& k = *m.kidnap;
    truth["kidnap"] = {{"file", "kidnap.txt"},
                       {"time_before_s", static_cast<double>(k.stamp_before.nanoseconds()) / 1e9},
                       {"time_after_s", static_cast<double>(k.stamp_after.nanoseconds()) / 1e9},
                       {"last_scan_before", k.last_scan_before},
                       {"first_scan_after", k.first_scan_after},
                       {"T_world_body_before", pose_json(k.T_world_body_before)},
                       {"T_world_body_after", pose_json(k.T_world_body_after)},
                       {"T_odom_body_before", pose_json(k.T_odom_body_before)},
                       {"T_odom_body_after", pose_json(k.T_odom_body_after)},
                       {"note", "the ground truth jumps between the two times; the odometry does not move"}};
  }
  if (m.session) {
    const auto& s = *m.session;
    truth["session"] = {{"pairs_with", s.pairs_with},
                        {"start_place", s.place},
                        {"T_world_start", pose_json(s.T_world_start)},
                        {"T_world_paired_start", pose_json(s.T_world_paired_start)},
                        {"note", "same world frame as " + s.pairs_with + ": localise this run in its map"}};
  }
  return truth;
}


}  // namespace

std::vector<std::string> apply_assignments(Scenario& scenario, const std::vector<std::string>& assignments) {
  std::vector<std::string> problems;
  std::vector<std::string> sorted = assignments;
  std::stable_partition(sorted.begin(), sorted.end(),
                        [](const std::string& a) { return a.starts_with("lidar3d.model=") || a.starts_with("imu.preset="); });
  for (const auto& assignment : sorted) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos) {
      problems.push_back("--set expects NAME=VALUE, found '" + assignment + "'");
      continue;
    }
    const std::string name = assignment.substr(0, equals);
    auto params = parameters(scenario);
    auto it = std::find_if(params.begin(), params.end(), [&](const Parameter& p) { return p.name == name; });
    if (it == params.end()) {
      problems.push_back("scenario " + scenario.name + " has no parameter '" + name +
                         "' (cairn simulate --list " + scenario.name + " shows them)");
      continue;
    }
    std::string why;
    if (!it->set(assignment.substr(equals + 1), &why)) problems.push_back(why);
  }
  return problems;
}

RunCounts count_run(const SimulationResult& result) {
  RunCounts counts;
  for (const auto& cloud : result.clouds) counts.cloud_points += cloud.size();
  for (const auto& loop : result.graph.loops) (loop.is_false ? counts.false_loops : counts.true_loops) += 1;
  return counts;
}

nlohmann::json manifest_json(const SimulationResult& result, Scenario& scenario, std::uint64_t seed,
                             const std::vector<std::string>& overrides, const std::string& directory,
                             const std::vector<std::string>& files) {
  namespace fs = std::filesystem;
  const RunCounts counts = count_run(result);
  const std::size_t cloud_points = counts.cloud_points, true_loops = counts.true_loops, false_loops = counts.false_loops;
  std::string command = "cairn simulate " + scenario.name + " --seed " + std::to_string(seed) + " --out DIR";
  for (const auto& s : overrides) command += " --set " + s;

  nlohmann::json manifest;
  manifest["generator"] = "cairn 0.1.0";
  manifest["scenario"] = scenario.name;
  manifest["description"] = scenario.description;
  manifest["seed"] = seed;
  manifest["command"] = command;
  manifest["overrides"] = overrides;
  manifest["parameters"] = parameter_json(scenario);
  manifest["summary"] = {{"duration_s", result.duration_s},
                         {"path_length_m", result.path_length_m},
                         {"ground_truth_samples", result.truth.size()},
                         {"odometry_records", result.odometry_samples.size()},
                         {"scans", result.scan_samples.size()},
                         {"lidar3d_points", cloud_points},
                         {"camera_observations", result.camera_observations.size()},
                         {"max_range_fraction", result.max_range_fraction},
                         {"landmark_observations", result.landmark_observations.size()},
                         {"graph_nodes", result.graph.graph.vertices.size()},
                         {"graph_edges", result.graph.graph.edges.size()},
                         {"true_loop_closures", true_loops},
                         {"false_loop_closures", false_loops},
                         {"relations", result.relations.size()},
                         {"slip_events", result.odometry.slip_events},
                         {"dead_reckoning_final_error_m", result.dead_reckoning_final_error_m},
                         {"dead_reckoning_final_error_rad", result.dead_reckoning_final_error_rad},
                         {"dead_reckoning_max_error_m", result.dead_reckoning_max_error_m},
                         {"min_clearance_m", result.min_clearance_m}};
  // Timings are not part of the manifest: they would make two identical runs differ.
  nlohmann::json file_list = nlohmann::json::array();
  for (const auto& name : files) {
    const std::string path = directory + "/" + name;
    file_list.push_back({{"name", name}, {"bytes", fs::file_size(path)}, {"fnv1a64", hex(fnv1a64(path))}});
  }
  if (scenario.is_3d()) {
    const bool pcd = scenario.lidar3d_format == "pcd";
    manifest["lidar3d"] = {
        {"model", scenario.lidar3d_model},
        {"format", scenario.lidar3d_format},
        {"scans", pcd ? "scans/NNNNNN.pcd: binary PCD v0.7, FIELDS x y z intensity ring time (float32 x y z intensity, "
                        "uint16 ring, float32 time); sensor frame at each point's firing time; intensity 0"
                      : "velodyne/NNNNNN.bin: float32 x y z intensity (0); velodyne_times/NNNNNN.bin: float32 time"},
        {"ring", "0 = lowest elevation, rings - 1 = highest, evenly spaced"},
        {"time", "seconds after the sweep start (times.txt)"},
        {"times_txt", "time of each sweep's start (its first column's firing), seconds"},
        {"poses_txt", pcd ? "T_world_lidar at the sweep start (times.txt), KITTI 3x4 row-major, world frame"
                          : "T_lidar0_lidar at the sweep start (times.txt), KITTI 3x4 row-major: first pose identity"},
        {"ground_truth_tum", "T_world_lidar at the sweep start"}};
    std::size_t reverse = 0;
    for (const auto& loop : result.true_loops) reverse += loop.heading_difference_rad > std::numbers::pi / 2 ? 1 : 0;
    nlohmann::json truth;
    truth["loops"] = {{"file", "loops.txt"},
                      {"criterion", "scan pairs i < j with LiDAR positions at most max_distance_m apart and times at "
                                    "least min_separation_s apart"},
                      {"max_distance_m", scenario.loop_truth.max_distance_m},
                      {"min_separation_s", scenario.loop_truth.min_separation_s},
                      {"pairs", result.true_loops.size()},
                      {"reverse_pairs", reverse},
                      {"note", result.true_loops.empty()
                                   ? "no true loop closure: every loop closure a SLAM system accepts here is false"
                                   : "reverse_pairs: heading difference above 90 degrees"}};
    truth["moving_objects"] = result.world_3d.moving_boxes.size();
    if (result.passage_scans) {
      const auto& p = *result.passage_scans;
      nlohmann::json passage = {{"kind", p.passage.kind},
                                {"entry_world", {p.passage.entry.x(), p.passage.entry.y(), 0.0}},
                                {"axis_world", {p.passage.axis.x(), p.passage.axis.y(), 0.0}},
                                {"length_m", p.passage.length_m}};
      if (p.any_inside) {
        passage["inside_scans"] = {p.first_inside, p.last_inside};
        passage["inside_time_s"] = {p.first_inside_time_s, p.last_inside_time_s};
      }
      passage["inside_definition"] = "scans whose LiDAR position at the sweep start projects between entry and exit";
      if (p.any_blind) passage["out_of_range_of_both_ends_scans"] = {p.first_blind, p.last_blind};
      truth["passage"] = passage;
    }
    if (result.spin) {
      const SpinEvent& spin = *result.spin;
      std::size_t first_scan = result.scan_samples.size();
      std::size_t last_scan = 0;
      for (std::size_t i = 0; i < result.scan_samples.size(); ++i) {
        // A sweep covers [scan_samples[i], scan_samples[i + 1]): those that overlap the spin.
        const std::size_t begin = result.scan_samples[i];
        const std::size_t end = i + 1 < result.scan_samples.size() ? result.scan_samples[i + 1] : result.truth.size();
        if (begin < spin.last_sample && end > spin.first_sample) {
          first_scan = std::min(first_scan, i);
          last_scan = i;
        }
      }
      truth["spin"] = {{"time_s", {spin.start_time_s, spin.end_time_s}},
                       {"samples", {spin.first_sample, spin.last_sample}},
                       {"position_world", {spin.position_world.x(), spin.position_world.y(), 0.0}},
                       {"angle_rad", spin.angle_rad},
                       {"peak_yaw_rate_rad_s", spin.peak_yaw_rate_rad_s},
                       {"note", "a turn on the spot counter-clockwise; at rest at both ends"}};
      if (first_scan <= last_scan) truth["spin"]["scans"] = {first_scan, last_scan};
    }
    manifest["ground_truth"] = truth;
    if (scenario.imu_enabled) manifest["imu"] = imu_manifest(result, scenario);
    if (scenario.gnss_enabled) manifest["gnss"] = gnss_manifest(result, scenario);
  }
  if (result.mission) manifest["ground_truth"] = mission_json(*result.mission);
  manifest["files"] = file_list;
  return manifest;
}

}  // namespace cairn::sim
