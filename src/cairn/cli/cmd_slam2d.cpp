// `cairn slam2d LOG --out DIR`: 2D LiDAR SLAM on a CARMEN log (raw Freiburg benchmark logs, the
// simulator's logs), fed scan by scan through the same streaming interface a robot would use.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <unistd.h>


#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/slam2d/config.hpp"
#include "cairn/slam2d/foxglove_output.hpp"
#include "cairn/slam2d/map_file.hpp"
#include "cairn/slam2d/outputs.hpp"
#include "cairn/slam2d/slam.hpp"

namespace cairn::cli {
namespace {


struct Slam2dFlags : LogReplayFlags {
  std::string log;
  std::string out;
  std::string config;
  std::string preset = "default";
  std::string relations;
  std::string save_map;
  std::string mcap;
  std::vector<std::string> set;
  bool print_config = false;
};

void print_relations(const eval::RelationsResult& r, std::size_t relations) {
  std::printf("relations metric (Kuemmerle et al. 2009) over %zu relations, mean +- std:\n", relations);
  std::printf("  absolute translational  %.4f +- %.4f m\n", r.translation_absolute_m.mean, r.translation_absolute_m.std);
  std::printf("  squared translational   %.4f +- %.4f m^2\n", r.translation_squared_m2.mean, r.translation_squared_m2.std);
  std::printf("  absolute rotational     %.3f +- %.3f deg\n", r.rotation_absolute_deg.mean, r.rotation_absolute_deg.std);
  std::printf("  squared rotational      %.3f +- %.3f deg^2\n", r.rotation_squared_deg2.mean, r.rotation_squared_deg2.std);
}

/// The options in effect: the preset, then --config, then each --set.
slam2d::Slam2dOptions slam2d_options(const Slam2dFlags& flags) {
  slam2d::Slam2dOptions options = slam2d::preset_options(flags.preset);
  if (!flags.config.empty()) slam2d::load_config(flags.config, options);
  for (const std::string& assignment : flags.set) slam2d::apply_setting(assignment, options);
  return options;
}

/// --save-map must name a file outside --out: refused before the work, not after it.
void check_save_map(const Slam2dFlags& flags) {
  if (flags.save_map.empty()) return;
  if (io::is_standard_output(flags.save_map))
    throw std::invalid_argument("--save-map needs a file: the map is binary and standard output carries the messages");
  io::resolve_output(flags.save_map);  // a directory, a link loop: refused before the work
  std::vector<std::string> names;
  for (const std::string& path : slam2d::output_files("").all()) names.push_back(std::filesystem::path(path).filename().string());
  io::check_file_outside_directory("--save-map", flags.save_map, "--out", flags.out, names);
}

/// --mcap must name a file outside --out, not standard output: refused before the work.
void check_mcap(const Slam2dFlags& flags) {
  if (flags.mcap.empty()) return;
  if (io::is_standard_output(flags.mcap)) throw std::invalid_argument("--mcap needs a file: MCAP is binary");
  io::resolve_output(flags.mcap);
  std::vector<std::string> names;
  for (const std::string& path : slam2d::output_files("").all()) names.push_back(std::filesystem::path(path).filename().string());
  io::check_file_outside_directory("--mcap", flags.mcap, "--out", flags.out, names);
}

/// Feeds the first `n` scans to `slam` until the last or a signal, printing health changes and
/// progress (on a terminal one line rewritten in place; with --progress a line every 200 scans,
/// for logs and for programs that watch the run). Returns the scans used.
std::size_t feed_scans(slam2d::Slam2d& slam, const io::CarmenLog& log, std::size_t n, const Slam2dFlags& flags) {
  const bool tty_progress = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  slam2d::Health last_health = slam2d::Health::kOk;
  std::size_t used = 0;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const slam2d::ScanResult result = slam.add_scan(log.scans[k]);
    used = k + 1;
    if (result.health != last_health && !flags.quiet) {
      std::fprintf(stderr, "%s[scan %zu, t = %s] %s\n", tty_progress ? "\r" : "", k,
                   log.scans[k].time.to_seconds_string().c_str(), std::string(slam2d::to_string(result.health)).c_str());
      last_health = result.health;
    }
    if ((tty_progress || flags.progress) && (k % 200 == 0 || k + 1 == n)) {
      const auto& s = slam.summary();
      std::fprintf(stderr, "%sscan %zu / %zu  keyframes %zu  loops %zu  %s%s", tty_progress ? "\r" : "", k + 1, n,
                   s.keyframes, s.loops_accepted, std::string(slam2d::to_string(result.health)).c_str(),
                   tty_progress ? "   " : "\n");
      std::fflush(stderr);
    }
  }
  slam.finish();  // after an interrupt: no final optimisation (Slam2dOptions::should_stop)
  if (tty_progress) std::fprintf(stderr, "\n");
  return used;
}

/// report.json's "relations": the Freiburg metric of the trajectory (printed unless --quiet).
nlohmann::json relations_report(const slam2d::Slam2d& slam, const std::vector<eval::Relation>& relations,
                                const Slam2dFlags& flags) {
  const eval::RelationsResult r = eval::evaluate_relations(relations, slam2d::to_matrix_trajectory(slam));
  if (!r.outcome.ok()) throw std::runtime_error("relations metric: " + r.outcome.message);
  if (!flags.quiet) print_relations(r, relations.size());
  return {{"file", flags.relations},
          {"count", relations.size()},
          {"translation_absolute_m", {{"mean", r.translation_absolute_m.mean}, {"std", r.translation_absolute_m.std}}},
          {"translation_squared_m2", {{"mean", r.translation_squared_m2.mean}, {"std", r.translation_squared_m2.std}}},
          {"rotation_absolute_deg", {{"mean", r.rotation_absolute_deg.mean}, {"std", r.rotation_absolute_deg.std}}},
          {"rotation_squared_deg2", {{"mean", r.rotation_squared_deg2.mean}, {"std", r.rotation_squared_deg2.std}}}};
}

/// --save-map: the map encoded and written to a staged file (committed with the directory, so the
/// map and the directory form a set); its facts go into the report.
std::unique_ptr<io::OutputFile> stage_saved_map(const slam2d::Slam2d& slam, const Slam2dFlags& flags, nlohmann::json& report) {
  if (flags.save_map.empty()) return nullptr;
  slam2d::SavedMap2D saved = slam.export_map();
  saved.source = flags.log;
  const std::string bytes = slam2d::encode_saved_map(saved);
  report["saved_map"] = {{"file", flags.save_map}, {"bytes", bytes.size()}, {"submaps", saved.submaps.size()},
                         {"keyframes", saved.keyframes.size()}, {"format_version", slam2d::kMapFileVersion}};
  auto map_file = std::make_unique<io::OutputFile>(flags.save_map);
  map_file->write([&](std::ostream& o) { o.write(bytes.data(), static_cast<std::streamsize>(bytes.size())); });
  return map_file;
}

void print_summary(const slam2d::Slam2dSummary& summary, std::size_t used, double data_s, double total_s,
                   double scans_per_second, bool stopped, bool saved_map, const Slam2dFlags& flags) {
  std::printf("%zu scans (%.0f s of data) in %.1f s: %.0f scans/s; %zu keyframes, %zu submaps\n", used, data_s, total_s,
              scans_per_second, summary.keyframes, summary.submaps);
  std::printf("loop closures: %zu searches, %zu candidates, %zu accepted, %zu rejected by the back end (GNC)\n",
              summary.loop_searches, summary.candidates.size(), summary.loops_accepted, summary.loops_rejected_by_gnc);
  std::printf("health: %zu ok, %zu degraded (%zu of them new structure only), %zu lost scans; %zu relocalisations\n",
              summary.scans_ok, summary.scans_degraded, summary.scans_new_space, summary.scans_lost, summary.relocalisations);
  std::printf("time: match %.1f s, local map %.1f s, submaps %.1f s, loop search %.1f s, optimisation %.1f s\n",
              summary.times.local_match_s, summary.times.local_map_s, summary.times.submap_s,
              summary.times.loop_search_s, summary.times.optimize_s);
  if (summary.segments.size() > 1) {
    std::printf("map segments: %zu, %zu merges\n", summary.segments.size(), summary.merges.size());
    int listed = 0;
    for (const slam2d::SegmentInfo& g : summary.segments) {
      if (g.why_not_merged.empty()) continue;
      if (++listed > 10) {
        std::printf("  ... (every segment in report.json)\n");
        break;
      }
      std::printf("  segment %d (%zu scans, %.0f m) not joined with segment 0: %s\n", g.id, g.scans, g.path_length_m, g.why_not_merged.c_str());
    }
  }
  std::printf("wrote map.png, map.pgm, map.yaml, trajectory.tum, scans.csv, graph.g2o, corrected.clf, report.json to %s%s\n",
              flags.out.c_str(), stopped ? " (interrupted: the result so far)" : "");
  if (saved_map) std::printf("wrote the map for reuse (cairn localize2d --map) to %s\n", flags.save_map.c_str());
  if (!flags.mcap.empty()) std::printf("wrote the results for Foxglove (MCAP) to %s\n", flags.mcap.c_str());
}

int slam2d_command(const Slam2dFlags& flags) {
  slam2d::Slam2dOptions options = slam2d_options(flags);
  if (flags.print_config) {
    std::cout << slam2d::config_to_yaml(options);
    if (flags.log.empty()) return 0;
  }
  if (flags.log.empty()) throw std::invalid_argument("a LOG to process is required");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  std::string error;
  if (!options.is_valid(&error)) throw std::invalid_argument("invalid configuration: " + error);
  check_save_map(flags);
  check_mcap(flags);
  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  options.should_stop = stop_on_signal();

  const auto start = core::Clock::now();
  io::CarmenReadReport read_report;
  const io::CarmenLog log = flags.read_log(flags.log, &read_report);
  const double read_s = core::seconds_since(start);
  std::vector<eval::Relation> relations;
  if (!flags.relations.empty()) relations = eval::read_relations(flags.relations);

  slam2d::Slam2d slam(options);
  std::size_t n = log.scans.size();
  if (flags.max_scans > 0) n = std::min<std::size_t>(n, static_cast<std::size_t>(flags.max_scans));
  const std::size_t used = feed_scans(slam, log, n, flags);
  const bool stopped = interrupted();
  if (stopped) {
    std::fprintf(stderr, "cairn slam2d: interrupted by %s after scan %zu of %zu: writing the result so far\n",
                 interrupt_signal_name(), used, n);
  }
  const double total_s = core::seconds_since(start);

  const slam2d::OutputFiles files = slam2d::write_outputs(slam, log, used, out.staging(), options);
  nlohmann::json report = slam2d::report_json(slam, options);
  report["input"] = {{"log", flags.log}, {"scans", used}, {"scans_in_log", log.scans.size()}, {"read_s", read_s},
                     {"records", read_report.records}};
  report["interrupted"] = stopped;
  if (stopped) {
    report["interruption"] = {{"signal", interrupt_signal_name()},
                              {"scans_processed", used},
                              {"scans_requested", n},
                              {"final_optimization", "skipped"}};
  }
  report["wall_time_s"] = total_s;
  const double data_s = used > 1 ? log.scans[used - 1].time.seconds() - log.scans[0].time.seconds() : 0.0;
  report["data_duration_s"] = data_s;
  const double scans_per_second = total_s > 0 ? static_cast<double>(used) / total_s : 0.0;
  report["scans_per_second"] = scans_per_second;
  if (!relations.empty() && !stopped) report["relations"] = relations_report(slam, relations, flags);
  const std::unique_ptr<io::OutputFile> map_file = stage_saved_map(slam, flags, report);
  io::write_output(files.report, [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();
  if (map_file) map_file->commit();
  if (!flags.mcap.empty()) slam2d::write_foxglove_mcap(flags.mcap, slam, options);
  if (!flags.quiet) print_summary(slam.summary(), used, data_s, total_s, scans_per_second, stopped, map_file != nullptr, flags);
  if (stopped) {
    if (flags.quiet) std::fprintf(stderr, "cairn slam2d: wrote the result so far to %s\n", flags.out.c_str());
    return interrupted_exit_status();
  }
  return 0;
}

}  // namespace

Runner register_slam2d(CLI::App& app) {
  auto flags = std::make_shared<Slam2dFlags>();
  app.add_option("LOG", flags->log, "CARMEN log (.clf/.log, also .gz/.bz2), or a bag with a sensor_msgs/LaserScan topic (ROS 1 .bag, .mcap, rosbag2 .db3 or folder)");
  app.add_option("--out", flags->out, "Output directory: map.pgm/.yaml/.png, trajectory.tum, graph.g2o, corrected.clf, report.json");
  app.add_option("--config", flags->config, "YAML configuration (every key optional; see docs/configuration.md)");
  app.add_option("--preset", flags->preset, "Starting configuration: default (SICK LMS-class, 180-361 beams over 180 degrees), short-range (360-degree scanners up to 12 m, 2-3 cm noise)")
      ->capture_default_str();
  app.add_option("--set", flags->set, "Override one key: section.key=value (repeatable)");
  app.add_option("--relations", flags->relations, "Freiburg relations file: print the relations metric at the end");
  app.add_option("--mcap", flags->mcap,
                 "Also write the trajectory, health, occupancy grid and loop closures as MCAP for Foxglove");
  app.add_option("--save-map", flags->save_map,
                 "Also write the finished map (submaps, grids, poses) for cairn localize2d --map (docs/formats.md)");
  app.add_flag("--print-config", flags->print_config, "Print the configuration in effect (YAML) and exit unless LOG is given");
  flags->LogReplayFlags::add_to(app);
  return [flags]() { return slam2d_command(*flags); };
}

}  // namespace cairn::cli
