// `cairn localize2d LOG --map FILE --out DIR`: pure localisation of a CARMEN log in a map saved by
// `cairn slam2d --save-map`, scan by scan through the same streaming interface a robot would use.
// The map is never changed.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/eval/statistics.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/slam2d/config.hpp"
#include "cairn/slam2d/localization.hpp"
#include "cairn/slam2d/localization_outputs.hpp"
#include "cairn/slam2d/map_file.hpp"

namespace cairn::cli {
namespace {

struct Localize2dFlags : LogReplayFlags {
  std::string log;
  std::string map;
  std::string out;
  std::string config;
  std::vector<std::string> set;
  std::string ground_truth;
  long first_scan = 0;
  int global_searches_per_scan = 0;
  int confirmations = 0;
};

/// The terminal line of a ground-truth comparison.
void print_ground_truth(const std::string& path, const slam2d::LocalizationTruthErrors& e) {
  if (e.translation_m.empty()) return;
  // The same statistics as report.json's ground_truth (eval's, evo's definitions).
  const eval::Statistics s = eval::compute_statistics(e.translation_m);
  std::printf("against %s: %zu localised scans compared, translation error mean %.3f m, max %.3f m; %zu of %zu "
              "relocalisations off by more than 0.3 m or 3 degrees\n",
              path.c_str(), e.translation_m.size(), s.mean, s.max, e.wrong_relocalisations, e.relocalisations_compared);
}

/// The options in effect: slam2d's --config and --set on the matching, then the dedicated flags.
slam2d::Localizer2dOptions localizer_options(const Localize2dFlags& flags) {
  slam2d::Localizer2dOptions options;
  if (!flags.config.empty()) slam2d::load_config(flags.config, options.matching);
  for (const std::string& assignment : flags.set) slam2d::apply_setting(assignment, options.matching);
  if (flags.global_searches_per_scan > 0) options.global_searches_per_scan = flags.global_searches_per_scan;
  if (flags.confirmations > 0) options.confirmations = flags.confirmations;
  std::string error;
  if (!options.is_valid(&error)) throw std::invalid_argument("invalid configuration: " + error);
  return options;
}

/// Scans [first, end) through the localiser until the last or a signal, printing health changes
/// and progress. Returns one result per scan fed.
std::vector<slam2d::LocalizationResult> feed_scans(slam2d::Localizer2d& localizer, const io::CarmenLog& log,
                                                   std::size_t first, std::size_t end, const Localize2dFlags& flags) {
  std::vector<slam2d::LocalizationResult> results;
  results.reserve(end - first);
  const bool tty_progress = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  slam2d::Health last_health = slam2d::Health::kLost;
  for (std::size_t k = first; k < end && !interrupted(); ++k) {
    const slam2d::LocalizationResult result = localizer.add_scan(log.scans[k]);
    results.push_back(result);
    if ((result.health != last_health || result.relocalised) && !flags.quiet) {
      const auto& events = localizer.summary().health_events;
      std::fprintf(stderr, "%s[scan %zu, t = %s] %s: %s\n", tty_progress ? "\r" : "", k,
                   log.scans[k].time.to_seconds_string().c_str(), std::string(slam2d::to_string(result.health)).c_str(),
                   events.empty() ? "" : events.back().reason.c_str());
      last_health = result.health;
    }
    if ((tty_progress || flags.progress) && ((k - first) % 200 == 0 || k + 1 == end)) {
      const auto& s = localizer.summary();
      std::fprintf(stderr, "%sscan %zu / %zu  localised %zu  relocalisations %zu  %s%s", tty_progress ? "\r" : "",
                   k - first + 1, end - first, s.scans_localised, s.relocalisations.size(),
                   std::string(slam2d::to_string(result.health)).c_str(), tty_progress ? "   " : "\n");
      std::fflush(stderr);
    }
  }
  if (tty_progress) std::fprintf(stderr, "\n");
  return results;
}

void print_summary(const slam2d::Localizer2dSummary& summary, std::size_t used, std::size_t first, double total_s,
                   bool stopped, const Localize2dFlags& flags) {
  std::printf("%zu scans in %.1f s (%.1f s localising, slowest scan %.3f s); map: %zu submaps, %zu tracking points\n", used,
              total_s, summary.total_s, summary.max_scan_s, summary.map_submaps, summary.map_points);
  if (summary.first_localised_scan) {
    std::printf("localised at scan %zu; %zu of %zu scans localised (%zu ok, %zu degraded), %zu lost\n",
                first + *summary.first_localised_scan, summary.scans_localised, used, summary.scans_ok,
                summary.scans_degraded, summary.scans_lost);
  } else {
    std::printf("never localised: %zu scans searched without an accepted pose\n", used);
  }
  std::printf("search: %zu global and %zu confirmation searches, %zu verified matches, %zu relocalisations, %zu "
              "hypotheses dropped, tracking contradicted %zu times\n",
              summary.global_searches, summary.confirmation_searches, summary.verified_matches,
              summary.relocalisations.size(), summary.hypotheses_dropped, summary.tracking_contradicted);
  std::printf("wrote map.png, trajectory.tum, scans.csv, report.json to %s%s\n", flags.out.c_str(),
              stopped ? " (interrupted: the result so far)" : "");
}

int localize2d_command(const Localize2dFlags& flags) {
  if (flags.log.empty()) throw std::invalid_argument("a LOG to localise is required");
  if (flags.map.empty()) throw std::invalid_argument("--map FILE is required (write one with cairn slam2d --save-map)");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  const slam2d::Localizer2dOptions options = localizer_options(flags);

  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  const auto start = core::Clock::now();
  slam2d::SavedMap2D map = slam2d::read_saved_map(flags.map);
  if (map.submaps.empty()) throw io::ParseError(flags.map, 0, "the map holds no submaps: nothing to localise in");
  io::CarmenReadReport read_report;
  const io::CarmenLog log = flags.read_log(flags.log, &read_report);
  const double read_s = core::seconds_since(start);
  const std::size_t first = static_cast<std::size_t>(std::max<long>(flags.first_scan, 0));
  if (first >= log.scans.size()) {
    throw std::invalid_argument("--first-scan " + std::to_string(first) + " is beyond the log's " +
                                std::to_string(log.scans.size()) + " scans");
  }
  std::size_t end = log.scans.size();
  if (flags.max_scans > 0) end = std::min(end, first + static_cast<std::size_t>(flags.max_scans));

  slam2d::Localizer2d localizer(std::move(map), options);
  const std::vector<slam2d::LocalizationResult> results = feed_scans(localizer, log, first, end, flags);
  const bool stopped = interrupted();
  const std::size_t used = results.size();
  if (stopped) {
    std::fprintf(stderr, "cairn localize2d: interrupted by %s after scan %zu of %zu: writing the result so far\n",
                 interrupt_signal_name(), used, end - first);
  }

  // Outputs: trajectory.tum (localised scans only, by time), scans.csv, map.png, report.json.
  const io::Trajectory trajectory = slam2d::localized_trajectory(results);
  if (!trajectory.stamps.empty()) io::write_tum(out.staging_path("trajectory.tum"), trajectory);
  else io::write_output(out.staging_path("trajectory.tum"), [](std::ostream& o) { o << "# no scan was localised\n"; });
  slam2d::write_localization_csv(results, out.staging_path("scans.csv"));
  const slam2d::ProbabilityGrid grid = slam2d::render_saved_map(localizer.map(), localizer.map().grid.resolution_m);
  slam2d::write_localization_png(grid, results, out.staging_path("map.png"));
  const auto& summary = localizer.summary();
  nlohmann::json report = slam2d::localization_report_json(localizer, options);
  const double total_s = core::seconds_since(start);
  report["input"] = {{"log", flags.log},
                     {"map", flags.map},
                     {"first_scan", first},
                     {"scans", used},
                     {"scans_in_log", log.scans.size()},
                     {"read_s", read_s},
                     {"records", read_report.records}};
  report["interrupted"] = stopped;
  if (stopped) {
    report["interruption"] = {
        {"signal", interrupt_signal_name()}, {"scans_processed", used}, {"scans_requested", end - first}};
  }
  report["wall_time_s"] = total_s;
  report["scans_per_second"] = summary.total_s > 0 ? static_cast<double>(used) / summary.total_s : 0.0;
  if (!flags.ground_truth.empty()) {
    const slam2d::LocalizationTruthErrors errors =
        slam2d::compare_with_ground_truth(io::read_tum(flags.ground_truth), results);
    if (!flags.quiet) print_ground_truth(flags.ground_truth, errors);
    report["ground_truth"] = slam2d::ground_truth_json(flags.ground_truth, errors);
  }
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();
  if (!flags.quiet) print_summary(localizer.summary(), used, first, total_s, stopped, flags);
  if (stopped) {
    if (flags.quiet) std::fprintf(stderr, "cairn localize2d: wrote the result so far to %s\n", flags.out.c_str());
    return interrupted_exit_status();
  }
  return 0;
}

}  // namespace

Runner register_localize2d(CLI::App& app) {
  auto flags = std::make_shared<Localize2dFlags>();
  app.add_option("LOG", flags->log, "CARMEN log (.clf/.log, also .gz/.bz2), or a bag with a sensor_msgs/LaserScan topic (ROS 1 .bag, .mcap, rosbag2 .db3 or folder)");
  app.add_option("--map", flags->map, "Map file written by cairn slam2d --save-map");
  app.add_option("--out", flags->out, "Output directory: map.png, trajectory.tum, scans.csv, report.json");
  app.add_option("--ground-truth", flags->ground_truth,
                 "TUM trajectory in the map's frame (e.g. cairn slam2d's trajectory.tum of the whole log): report the error");
  app.add_option("--config", flags->config, "slam2d YAML configuration: its matching and verification keys apply");
  app.add_option("--set", flags->set, "Override one slam2d key: section.key=value (repeatable)");
  app.add_option("--global-searches-per-scan", flags->global_searches_per_scan,
                 "Whole-submap searches per scan while searching (default 3)")
      ->check(checks::count());
  app.add_option("--confirmations", flags->confirmations,
                 "Scans whose verified matches must agree before a pose is accepted (default 2)")
      ->check(checks::count());
  app.add_option("--first-scan", flags->first_scan, "Start at this scan of the log (0-based)")
      ->check(checks::count_or_zero(std::numeric_limits<long>::max()));
  flags->LogReplayFlags::add_to(app);
  return [flags]() { return localize2d_command(*flags); };
}

}  // namespace cairn::cli
