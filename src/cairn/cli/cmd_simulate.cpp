// `cairn simulate SCENARIO --seed N --out DIR`: a simulated world, trajectory and sensor logs in
// the formats cairn reads, with a manifest that makes the run reproducible byte for byte.

#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>

#include "cairn/cli/commands.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/sim/scenario.hpp"

namespace cairn::cli {
namespace {

namespace fs = std::filesystem;

struct SimulateFlags {
  std::string scenario;
  std::uint64_t seed = 1;
  std::string out;
  std::vector<std::string> set;
  bool list = false;
  bool quiet = false;
  bool overwrite = false;
};

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

/// A bad flag or scenario name: said on stderr, exit status 2 (as CLI11's own usage errors).
int usage_error(const std::string& message) {
  std::cerr << "cairn: error: cairn simulate: " << message << '\n';
  return 2;
}

std::optional<sim::Scenario> find_scenario(const std::string& name, std::string* why) {
  auto scenario = sim::make_scenario(name);
  if (!scenario) {
    std::string known;
    for (const auto& n : sim::scenario_names()) known += (known.empty() ? "" : ", ") + n;
    *why = "unknown scenario '" + name + "': expected one of " + known;
  }
  return scenario;
}

int list_scenarios(const SimulateFlags& flags) {
  std::vector<std::string> names = sim::scenario_names();
  if (!flags.scenario.empty()) {
    std::string why;
    if (!find_scenario(flags.scenario, &why)) return usage_error(why);
    names = {flags.scenario};
  }
  for (const auto& name : names) {
    sim::Scenario scenario = *sim::make_scenario(name);
    std::printf("%s\n  %s\n", name.c_str(), scenario.description.c_str());
    for (auto& p : sim::parameters(scenario)) {
      std::printf("    %-42s %-12s %-14s %s\n", p.name.c_str(), p.text().c_str(), p.unit.c_str(), p.description.c_str());
    }
    std::printf("\n");
  }
  std::printf("Change a parameter with --set NAME=VALUE (repeatable); every run records them in manifest.json.\n");
  return 0;
}

nlohmann::json parameter_json(sim::Scenario& scenario) {
  nlohmann::json j = nlohmann::json::object();
  for (auto& p : sim::parameters(scenario)) {
    nlohmann::json value;
    std::visit([&](auto* field) { value = *field; }, p.value);
    j[p.name] = {{"value", value}, {"unit", p.unit}};
  }
  return j;
}

nlohmann::json pose_json(const core::SE2& T) { return {{"x_m", T.x()}, {"y_m", T.y()}, {"theta_rad", T.angle()}}; }

nlohmann::json revisit_json(const sim::Revisit& r) {
  return {{"scan", r.later},
          {"earlier_scan", r.earlier},
          {"distance_m", r.distance_m},
          {"heading_difference_rad", r.heading_difference_rad},
          {"time_difference_s", r.time_difference_s},
          {"path_between_m", r.path_between_m}};
}

/// The mission scenarios' ground truth (sim/mission_truth.hpp): regions with their scan counts,
/// doors, the segments, revisits, the longest absence, the kidnapping and the second session.
nlohmann::json mission_json(const sim::MissionTruth& m) {
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

int simulate_command(const SimulateFlags& flags) {
  if (flags.list) return list_scenarios(flags);
  if (flags.scenario.empty()) return usage_error("name a scenario (cairn simulate --list shows them)");
  if (flags.out.empty()) return usage_error("--out DIR is required");
  std::string unknown;
  auto found = find_scenario(flags.scenario, &unknown);
  if (!found) return usage_error(unknown);
  sim::Scenario scenario = *found;

  // --set NAME=VALUE, all problems reported at once. A sensor preset (lidar3d.model) goes first,
  // so the other lidar3d.* settings override it whatever their order on the command line.
  std::vector<std::string> problems;
  std::vector<std::string> assignments = flags.set;
  std::stable_partition(assignments.begin(), assignments.end(),
                        [](const std::string& a) { return a.starts_with("lidar3d.model="); });
  for (const auto& assignment : assignments) {
    const auto equals = assignment.find('=');
    if (equals == std::string::npos) {
      problems.push_back("--set expects NAME=VALUE, found '" + assignment + "'");
      continue;
    }
    const std::string name = assignment.substr(0, equals);
    auto params = sim::parameters(scenario);
    auto it = std::find_if(params.begin(), params.end(), [&](const sim::Parameter& p) { return p.name == name; });
    if (it == params.end()) {
      problems.push_back("scenario " + scenario.name + " has no parameter '" + name +
                         "' (cairn simulate --list " + scenario.name + " shows them)");
      continue;
    }
    std::string why;
    if (!it->set(assignment.substr(equals + 1), &why)) problems.push_back(why);
  }
  // Values that did not parse kept their defaults, so the rules can still be checked.
  std::string why;
  if (!scenario.is_valid(&why)) problems.push_back(why);
  if (!problems.empty()) {
    std::string message;
    for (const auto& p : problems) message += (message.empty() ? "" : "; ") + p;
    return usage_error(message);
  }

  // Files go to a staging directory on --out's file system and appear together at the end (io/output_file.hpp).
  io::OutputDirectory out(flags.out, flags.overwrite);

  const auto start = std::chrono::steady_clock::now();
  const sim::SimulationResult result = sim::simulate(scenario, flags.seed);
  const auto simulated = std::chrono::steady_clock::now();
  const std::vector<std::string> files = sim::write_outputs(result, scenario, flags.seed, out.staging());
  const auto written = std::chrono::steady_clock::now();
  const double simulate_s = std::chrono::duration<double>(simulated - start).count();
  const double write_s = std::chrono::duration<double>(written - simulated).count();

  std::size_t cloud_points = 0;
  for (const auto& cloud : result.clouds) cloud_points += cloud.size();
  std::size_t true_loops = 0;
  std::size_t false_loops = 0;
  for (const auto& loop : result.graph.loops) (loop.is_false ? false_loops : true_loops) += 1;

  std::string command = "cairn simulate " + scenario.name + " --seed " + std::to_string(flags.seed) + " --out DIR";
  for (const auto& s : flags.set) command += " --set " + s;

  nlohmann::json manifest;
  manifest["generator"] = "cairn 0.1.0";
  manifest["scenario"] = scenario.name;
  manifest["description"] = scenario.description;
  manifest["seed"] = flags.seed;
  manifest["command"] = command;
  manifest["overrides"] = flags.set;
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
    const std::string path = out.staging_path(name);
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
    manifest["ground_truth"] = truth;
  }
  if (result.mission) manifest["ground_truth"] = mission_json(*result.mission);
  manifest["files"] = file_list;
  io::write_output(out.staging_path("manifest.json"), [&](std::ostream& o) { o << io::json_text(manifest); });
  out.commit();

  if (result.min_clearance_m < 0.2) {
    warn("the ground-truth path passes " + std::to_string(result.min_clearance_m) +
         " m from a wall or pillar: the parameters make the route collide with the world");
  }
  if (!flags.quiet) {
    std::printf("%s, seed %" PRIu64 ": %.1f m in %.1f s; %zu scans, %zu ODOM records", scenario.name.c_str(), flags.seed,
                result.path_length_m, result.duration_s, result.scan_samples.size(), result.odometry_samples.size());
    if (scenario.simulate_landmarks) std::printf(", %zu landmark observations", result.landmark_observations.size());
    if (scenario.is_3d()) {
      std::printf("\n%zu points in %zu clouds; %zu camera observations of %zu lamps; %zu true loop-closure pairs\n",
                  cloud_points, result.clouds.size(), result.camera_observations.size(), result.world_3d.landmarks.size(),
                  result.true_loops.size());
      if (result.passage_scans && result.passage_scans->any_inside) {
        std::printf("%s: scans %zu-%zu inside\n", result.passage_scans->passage.kind.c_str(),
                    result.passage_scans->first_inside, result.passage_scans->last_inside);
      }
    } else {
      std::printf("\ngraph: %zu nodes, %zu edges (%zu true loop closures, %zu false); %zu relations\n",
                  result.graph.graph.vertices.size(), result.graph.graph.edges.size(), true_loops, false_loops,
                  result.relations.size());
      if (result.mission) {
        for (const auto& s : result.mission->segments) {
          std::printf("  %s: scans %zu-%zu (%.1f-%.1f s, %.1f m), %zu with fewer than %d returns\n", s.region.c_str(),
                      s.first_scan, s.last_scan, s.start_time_s, s.end_time_s, s.path_length_m, s.few_return_scans,
                      result.mission->few_returns);
        }
        if (result.mission->kidnap) {
          const auto& k = *result.mission->kidnap;
          std::printf("kidnapped between %.2f s and %.2f s (scans %zu, %zu): (%.2f, %.2f) -> (%.2f, %.2f)\n",
                      k.stamp_before.seconds(), k.stamp_after.seconds(), k.last_scan_before, k.first_scan_after,
                      k.T_world_body_before.x(), k.T_world_body_before.y(), k.T_world_body_after.x(),
                      k.T_world_body_after.y());
        }
        if (result.mission->absence) {
          const auto& a = *result.mission->absence;
          std::printf("away from %s for %.1f s and %.1f m (scans %zu-%zu)\n", a.region.c_str(), a.duration_s,
                      a.path_length_m, a.left_scan, a.returned_scan);
        }
      }
    }
    std::printf("dead reckoning ends %.2f m / %.2f deg off the ground truth (at most %.2f m off on the way); "
                "%.1f %% of readings at max range\n",
                result.dead_reckoning_final_error_m, result.dead_reckoning_final_error_rad * 180.0 / std::numbers::pi,
                result.dead_reckoning_max_error_m, 100.0 * result.max_range_fraction);
    std::printf("wrote %zu files and manifest.json to %s (simulation %.2f s, writing %.2f s)\n", files.size(),
                flags.out.c_str(), simulate_s, write_s);
  }
  return 0;
}

}  // namespace

Runner register_simulate(CLI::App& app) {
  auto flags = std::make_shared<SimulateFlags>();
  app.add_option("SCENARIO", flags->scenario, "office, office-people, corridor-aliasing, open-hall, loop-building, landmarks, "
                 "building-yard, outdoor-stretch, kidnapping, long-absence, second-session, street-3d, street-3d-loops, "
                 "garage-3d or tunnel-3d");
  app.add_option("--seed", flags->seed, "Seed of every random draw; the same seed gives the same bytes")
      ->capture_default_str();
  app.add_option("--out", flags->out, "Output directory (created if missing; must be empty unless --overwrite)");
  app.add_flag("--overwrite", flags->overwrite,
               "Write into an --out directory that already holds files (those of the same names are replaced)");
  app.add_option("--set", flags->set, "Change a parameter: NAME=VALUE (repeatable; see --list)");
  app.add_flag("--list", flags->list, "List the scenarios (or the named one) with their parameters and exit");
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  return [flags]() { return simulate_command(*flags); };
}

}  // namespace cairn::cli
