#pragma once
/// \file
/// The subcommands of the one `cairn` binary. Each registers its options on the app and returns
/// the function that runs it (exit status: 0 success, 1 bad input or failure; usage errors are
/// reported by CLI11 with status 2).

#include <CLI/CLI.hpp>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "cairn/io/carmen_log.hpp"
#include "cairn/io/graph_io.hpp"

namespace cairn::cli {

using Runner = std::function<int()>;

Runner register_info(CLI::App& app);
/// `cairn info BAG` (info_bag.cpp): prints what a bag holds; `json` as for --json.
int info_bag(const std::string& path, const std::string& json);
Runner register_convert(CLI::App& app);
Runner register_optimize(CLI::App& app);
Runner register_simulate(CLI::App& app);
Runner register_corrupt(CLI::App& app);
Runner register_slam2d(CLI::App& app);
Runner register_localize2d(CLI::App& app);
Runner register_localize3d(CLI::App& app);
Runner register_landmarks(CLI::App& app);
Runner register_eval(CLI::App& app);
Runner register_ba(CLI::App& app);
Runner register_slam3d(CLI::App& app);
Runner register_vslam(CLI::App& app);
Runner register_vocabulary(CLI::App& app);
Runner register_imu(CLI::App& app);
Runner register_navigate(CLI::App& app);
Runner register_register(CLI::App& app);

/// Flags shared by every command that reads a pose graph.
struct GraphReadFlags {
  bool strict = false;
  std::string info_policy = "project";
  std::string toro_info_order = "auto";

  void add_to(CLI::App& command);
  /// Throws io::ParseError on an invalid combination (there is none yet; kept for symmetry).
  io::GraphReadOptions options() const;
};

/// Flags shared by the commands that replay a CARMEN log scan by scan (slam2d, localize2d).
struct LogReplayFlags {
  long max_scans = 0;
  bool lenient = false;
  bool quiet = false;
  bool progress = false;
  bool overwrite = false;
  std::string scan_topic;
  std::string odometry_topic;

  void add_to(CLI::App& command);
  /// The CARMEN log at `path` with --lenient applied. Throws io::ParseError when it holds no laser
  /// record (FLASER, RLASER, ROBOTLASER1).
  /// A bag (bag::is_bag) is read through bag::read_laser_log with --scan-topic and --odom-topic.
  io::CarmenLog read_log(const std::string& path, io::CarmenReadReport* report) const;

 private:
  io::CarmenLog read_bag(const std::string& path, io::CarmenReadReport* report) const;
};

/// A flag combination that does nothing, or a flag value the input cannot honour, found before
/// any work: printed as "cairn: error: <text>", exit status 2 (as CLI11's usage errors).
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Prints "cairn: warning: <text>" to stderr.
void warn(const std::string& text);

}  // namespace cairn::cli
