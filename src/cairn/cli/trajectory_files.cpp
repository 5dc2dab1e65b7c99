#include "cairn/cli/trajectory_files.hpp"

#include "cairn/cli/commands.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {

io::Trajectory read_trajectory(const std::string& path, io::FileFormat format, const std::string& times_path,
                               io::TrajectoryReadReport* report) {
  if (!times_path.empty() && format != io::FileFormat::kKitti) {
    throw UsageError("--times goes with a KITTI trajectory, and " + path + " is " + std::string(io::to_string(format)));
  }
  switch (format) {
    case io::FileFormat::kTum: return io::read_tum(path, report);
    case io::FileFormat::kKitti: return io::read_kitti(path, times_path, report);
    case io::FileFormat::kEuroc: return io::read_euroc(path, report);
    default: break;
  }
  throw io::ParseError(path, 0, "not a trajectory format: " + std::string(io::to_string(format)));
}

void write_trajectory(const std::string& path, const io::Trajectory& trajectory, io::FileFormat format,
                      const std::string& times_path) {
  if (!times_path.empty() && format != io::FileFormat::kKitti) {
    throw UsageError("--out-times goes with KITTI output (poses without times), and " + path + " is written as " +
                     std::string(io::to_string(format)) + ", whose lines hold their times");
  }
  switch (format) {
    case io::FileFormat::kTum: return io::write_tum(path, trajectory);
    case io::FileFormat::kKitti: return io::write_kitti(path, trajectory, times_path);
    case io::FileFormat::kEuroc: return io::write_euroc(path, trajectory);
    default: break;
  }
  throw io::ParseError(path, 0, "not a trajectory format: " + std::string(io::to_string(format)));
}

io::FileFormat resolve_format(const std::string& path, const std::string& flag, const char* flag_name) {
  if (!flag.empty()) {
    if (auto format = io::file_format_from_name(flag)) return *format;
    throw io::ParseError(path, 0, std::string("unknown format '") + flag + "' given with " + flag_name +
                                      ": expected g2o, toro, tum, kitti or euroc");
  }
  if (auto format = io::detect_file_format(path)) return *format;
  throw io::ParseError(path, 0,
                       std::string("cannot tell the format from the name or the first record: "
                                   "expected .g2o, .graph, .tum, .kitti or .csv, or name it with ") +
                           flag_name);
}

}  // namespace cairn::cli
