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
#include "cairn/core/timer.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/sim/manifest.hpp"
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

// The 3D worlds' lines of the summary: clouds, IMU, GNSS, the spin, the tunnel.
void print_3d_summary(const sim::Scenario& scenario, const sim::SimulationResult& result, std::size_t cloud_points) {
  std::printf("\n%zu points in %zu clouds; %zu camera observations of %zu lamps; %zu true loop-closure pairs\n",
              cloud_points, result.clouds.size(), result.camera_observations.size(), result.world_3d.landmarks.size(),
              result.true_loops.size());
  if (scenario.imu_enabled) {
    std::printf("IMU (%s): %zu samples at %.0f Hz\n", scenario.imu_preset.c_str(), result.imu.samples.size(),
                scenario.imu.rate_hz);
  }
  if (scenario.gnss_enabled) {
    std::size_t jumps = 0;
    for (const bool o : result.gnss.outlier) jumps += o ? 1 : 0;
    std::printf("GNSS: %zu fixes at %.0f Hz (%zu jumps, %zu epochs without sky)\n", result.gnss.fixes.size(),
                scenario.gnss.rate_hz, jumps, result.gnss.blocked_without_sky);
  }
  if (result.spin) {
    std::printf("spin on the spot: %.2f-%.2f s, %.0f deg at up to %.0f deg/s\n", result.spin->start_time_s,
                result.spin->end_time_s, result.spin->angle_rad * 180.0 / std::numbers::pi,
                result.spin->peak_yaw_rate_rad_s * 180.0 / std::numbers::pi);
  }
  if (result.passage_scans && result.passage_scans->any_inside) {
    std::printf("%s: scans %zu-%zu inside\n", result.passage_scans->passage.kind.c_str(),
                result.passage_scans->first_inside, result.passage_scans->last_inside);
  }
}

// The 2D worlds' lines of the summary: the graph and the mission's segments, kidnap and absence.
void print_2d_summary(const sim::SimulationResult& result, std::size_t true_loops, std::size_t false_loops) {
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

int simulate_command(const SimulateFlags& flags) {
  if (flags.list) return list_scenarios(flags);
  if (flags.scenario.empty()) return usage_error("name a scenario (cairn simulate --list shows them)");
  if (flags.out.empty()) return usage_error("--out DIR is required");
  std::string unknown;
  auto found = find_scenario(flags.scenario, &unknown);
  if (!found) return usage_error(unknown);
  sim::Scenario scenario = *found;

  // --set NAME=VALUE, all problems reported at once.
  std::vector<std::string> problems = sim::apply_assignments(scenario, flags.set);
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

  const auto start = core::Clock::now();
  const sim::SimulationResult result = sim::simulate(scenario, flags.seed);
  const auto simulated = core::Clock::now();
  const std::vector<std::string> files = sim::write_outputs(result, scenario, flags.seed, out.staging());
  const auto written = core::Clock::now();
  const double simulate_s = std::chrono::duration<double>(simulated - start).count();
  const double write_s = std::chrono::duration<double>(written - simulated).count();

  const sim::RunCounts counts = sim::count_run(result);
  const std::size_t cloud_points = counts.cloud_points, true_loops = counts.true_loops, false_loops = counts.false_loops;
  const nlohmann::json manifest = sim::manifest_json(result, scenario, flags.seed, flags.set, out.staging(), files);
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
      print_3d_summary(scenario, result, cloud_points);
    } else {
      print_2d_summary(result, true_loops, false_loops);
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
                 "garage-3d, tunnel-3d or tunnel-spin-3d");
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
