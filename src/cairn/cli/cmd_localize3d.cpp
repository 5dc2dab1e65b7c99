// `cairn localize3d SCANS --map FILE --out DIR`: pure localisation of 3D LiDAR scans in a map saved
// by `cairn slam3d --save-map`, scan by scan through the same streaming interface a robot would
// use (lidar3d/localization.hpp). The map is never changed. The outputs are the library's
// (lidar3d/localization_outputs.hpp).

#include <unistd.h>

#include <cstdio>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/slam3d_flags.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"
#include "cairn/lidar3d/localization.hpp"
#include "cairn/lidar3d/localization_outputs.hpp"
#include "cairn/lidar3d/map_file.hpp"
#include "cairn/lidar3d/scan_reader.hpp"

namespace cairn::cli {
namespace {

struct Localize3dFlags {
  std::vector<std::string> scans;
  std::string map;
  std::string out;
  std::string times;
  int times_column = 1;
  std::string cloud_topic;
  long max_scans = 0;
  int threads = 0;
  int confirmations = 0;
  int picture_px = 1600;
  bool quiet = false, progress = false, overwrite = false;
  bool odometry_while_tracking = false;
};

lidar3d::Localizer3dOptions localizer_options(const Localize3dFlags& flags) {
  lidar3d::Localizer3dOptions options;
  options.threads = flags.threads;
  if (flags.confirmations > 0) options.confirmations = flags.confirmations;
  options.odometry_while_tracking = flags.odometry_while_tracking;
  return options;
}

void print_change(const lidar3d::Localization3dResult& r, bool tty) {
  std::fprintf(stderr, "%s[scan %zu, t = %.3f s] %s: %s\n", tty ? "\r" : "", r.scan, r.time_s,
               std::string(core::to_string(r.health)).c_str(), r.reason.c_str());
}

/// Reads and localises the scans one at a time until the last or a signal, with health changes
/// and progress on stderr.
std::vector<lidar3d::Localization3dResult> feed_scans(lidar3d::Localizer3d& localizer, lidar3d::ScanSequence& sequence,
                                                      const Localize3dFlags& flags) {
  std::vector<lidar3d::Localization3dResult> results;
  lidar3d::ScanReader reader(sequence);
  const std::size_t n = sequence.files.size();
  const bool tty = !flags.quiet && !flags.progress && isatty(fileno(stderr));
  core::Health last = core::Health::kLost;
  for (std::size_t k = 0; k < n && !interrupted(); ++k) {
    const io::PointCloud cloud = reader.read(k);
    results.push_back(localizer.add_scan(cloud, sequence.times_s[k]));
    const lidar3d::Localization3dResult& r = results.back();
    if ((r.health != last || r.relocalised) && !flags.quiet) print_change(r, tty);
    last = r.health;
    if ((tty || flags.progress) && (k % 20 == 0 || k + 1 == n)) {
      std::fprintf(stderr, "%sscan %zu / %zu  %.0f ms  localised %zu  relocalisations %zu  %s%s", tty ? "\r" : "", k + 1, n,
                   1e3 * r.total_s, localizer.summary().scans_localised, localizer.summary().relocalisations.size(),
                   std::string(core::to_string(r.health)).c_str(), tty ? "   " : "\n");
      std::fflush(stderr);
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  return results;
}

void print_summary(const lidar3d::Localizer3dSummary& s, const lidar3d::TrackingTimes& tracking, double total_s, bool stopped,
                   const Localize3dFlags& flags) {
  std::printf("%zu scans in %.1f s (%.1f s localising, slowest scan %.3f s); map: %zu keyframes, %zu points (built in %.2f s)\n",
              s.scans, total_s, s.total_s, s.max_scan_s, s.map_keyframes, s.map_points, s.setup_s);
  if (tracking.scans > 0) {
    std::printf("tracked scans: %zu, %.1f ms median, %.1f ms 90th percentile, %.1f ms slowest (the global check included)\n",
                tracking.scans, tracking.median_ms, tracking.p90_ms, tracking.max_ms);
  }
  if (s.first_localised_scan) {
    std::printf("localised at scan %zu; %zu of %zu scans localised (%zu ok, %zu degraded), %zu lost\n", *s.first_localised_scan,
                s.scans_localised, s.scans, s.scans_ok, s.scans_degraded, s.scans_lost);
  } else {
    std::printf("never localised: %zu scans searched without an accepted pose\n", s.scans);
  }
  std::printf("search: %zu descriptor queries, %zu places matched, %zu verified, %zu relocalisations, %zu hypotheses "
              "dropped, %zu ambiguous scans, tracking contradicted %zu times\n",
              s.descriptor_queries, s.places_matched, s.places_verified, s.relocalisations.size(), s.hypotheses_dropped,
              s.scans_ambiguous, s.tracking_contradicted);
  std::printf("wrote trajectory.tum, scans.csv, map.png, report.json to %s%s\n", flags.out.c_str(),
              stopped ? " (interrupted: the result so far)" : "");
}

int localize3d_command(const Localize3dFlags& flags) {
  if (flags.map.empty()) throw std::invalid_argument("--map FILE is required (write one with cairn slam3d --save-map)");
  if (flags.out.empty()) throw std::invalid_argument("--out DIR is required");
  const lidar3d::Localizer3dOptions options = localizer_options(flags);
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid options: " + why);
  lidar3d::ScanSequence sequence =
      read_scan_sequence(flags.scans, flags.times, flags.times_column, flags.cloud_topic, flags.max_scans);

  // Refuse a directory of another run before the work, not after it.
  io::OutputDirectory out(flags.out, flags.overwrite);
  const auto start = core::Clock::now();
  lidar3d::SavedMap3D map = lidar3d::read_saved_map(flags.map);
  if (map.points_world.empty()) throw io::ParseError(flags.map, 0, "the map holds no points: nothing to localise in");
  if (map.keyframes.empty()) throw io::ParseError(flags.map, 0, "the map holds no keyframes: no place to search from");
  lidar3d::Localizer3d localizer(std::move(map), options);
  const std::vector<lidar3d::Localization3dResult> results = feed_scans(localizer, sequence, flags);
  const bool stopped = interrupted();
  if (stopped) {
    std::fprintf(stderr, "cairn localize3d: interrupted by %s after scan %zu of %zu: writing the result so far\n",
                 interrupt_signal_name(), results.size(), sequence.files.size());
  }

  const io::Trajectory trajectory = lidar3d::localized_trajectory(results);
  if (!trajectory.poses.empty()) io::write_tum(out.staging_path("trajectory.tum"), trajectory);
  else io::write_output(out.staging_path("trajectory.tum"), [](std::ostream& o) { o << "# no scan was localised\n"; });
  lidar3d::write_localization_csv(results, out.staging_path("scans.csv"));
  lidar3d::write_localization_png(localizer.map(), results, out.staging_path("map.png"), flags.picture_px);
  nlohmann::json report = lidar3d::localization_report_json(localizer);
  const double total_s = core::seconds_since(start);
  report["input"] = {{"scans", flags.scans}, {"map", flags.map}, {"times", flags.times}, {"scans_read", results.size()}};
  report["interrupted"] = stopped;
  report["wall_time_s"] = total_s;
  const lidar3d::TrackingTimes tracking = lidar3d::tracking_times(results);
  report["tracking_time"] = lidar3d::to_json(tracking);
  io::write_output(out.staging_path("report.json"), [&](std::ostream& o) { o << io::json_text(report); });
  out.commit();
  if (!flags.quiet) print_summary(localizer.summary(), tracking, total_s, stopped, flags);
  return stopped ? interrupted_exit_status() : 0;
}

}  // namespace

Runner register_localize3d(CLI::App& app) {
  auto flags = std::make_shared<Localize3dFlags>();
  app.add_option("SCANS", flags->scans,
                 "A folder of scans (.pcd/.ply/.bin, optionally compressed; natural name order), scan files in order, or a "
                 "bag with a sensor_msgs/PointCloud2 topic")
      ->required();
  app.add_option("--map", flags->map, "Map file written by cairn slam3d --save-map")->required();
  app.add_option("--out", flags->out, "Output directory: trajectory.tum, scans.csv, map.png, report.json")->required();
  app.add_option("--times", flags->times, "Table with one row per scan holding its time in seconds (e.g. KITTI times.txt)");
  app.add_option("--times-column", flags->times_column, "Column of --times holding the time (1-based)")
      ->check(checks::count(10000))
      ->capture_default_str();
  app.add_option("--cloud-topic", flags->cloud_topic, "Bag input: the sensor_msgs/PointCloud2 topic (default: the only one)");
  app.add_option("--max-scans", flags->max_scans, "Localise only the first N scans")
      ->check(checks::count(std::numeric_limits<long>::max()));
  app.add_option("--confirmations", flags->confirmations,
                 "Scans that must support a place before it is accepted (default 2)")
      ->check(checks::count());
  app.add_flag("--odometry-while-tracking", flags->odometry_while_tracking,
               "Run the odometry on every tracked scan and predict through it (default: the localiser's own "
               "constant velocity, no odometry step while tracking)");
  app.add_option("--threads", flags->threads, "Threads (0 = all; more than the machine has are clamped)")
      ->transform(checks::threads())
      ->capture_default_str();
  app.add_option("--picture-size", flags->picture_px, "Longer side of map.png, pixels")
      ->capture_default_str()
      ->check(checks::whole_range(200, 20000));
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  app.add_flag("--progress", flags->progress, "Progress as a line every 20 scans on stderr, also when stderr is not a terminal");
  app.add_flag("--overwrite", flags->overwrite,
               "Write into an --out directory that already holds files (those of the same names are replaced)");
  return [flags]() { return localize3d_command(*flags); };
}

}  // namespace cairn::cli
