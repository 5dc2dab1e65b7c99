#pragma once
/// \file
/// Which scans a run reads, in which order, and when each was taken.
///
/// Scans come as one folder (every file whose name ends in .pcd, .ply or .bin, each optionally
/// followed by .gz, .bz2 or .xz, in natural order: "scan_9" before "scan_10") or as a list of
/// files in the order given. Times come from a whitespace-separated table with one row per scan
/// in that order (KITTI's times.txt has one column; a key-frame list may hold the time in its
/// fourth), lines starting with '#' and blank lines skipped; without a table the scans are taken
/// as `default_period_s` apart, as KISS-ICP assumes for every scan.

#include <cstddef>
#include <string>
#include <vector>

namespace cairn::lidar3d {

struct ScanSequence {
  /// The scan files; for a bag, one label per scan ("<bag> /points #k").
  std::vector<std::string> files;
  /// One per file, seconds, strictly increasing.
  std::vector<double> times_s;
  /// False when the times were made up (no table).
  bool times_from_file = false;
  /// Set when the scans are a bag's sensor_msgs/PointCloud2 topic (make_bag_scan_sequence): the
  /// bag and the topic; `times_s` then fills as the scans are read (their header stamps).
  std::string bag;
  std::string bag_topic;
};

/// The scan files of `paths` (one folder, or files). Throws ParseError for a missing path, an
/// empty folder, or a folder mixed with files.
std::vector<std::string> list_scans(const std::vector<std::string>& paths);

/// Reads column `column` (1-based) of the first `count` data rows of `times_path`. Throws
/// ParseError naming the file and line for a short table, a missing column, a value that is not a
/// finite number, or times that do not strictly increase.
std::vector<double> read_scan_times(const std::string& times_path, int column, std::size_t count);

/// list_scans, then read_scan_times if `times_path` is not empty (or times k * default_period_s).
ScanSequence make_scan_sequence(const std::vector<std::string>& paths, const std::string& times_path, int column,
                                double default_period_s = 0.1);

/// The first `max_scans` (0: all) PointCloud2 messages of `topic` ("" = the only such topic) in
/// the bag at `path` (any format bag::Bag opens). Throws io::ParseError.
ScanSequence make_bag_scan_sequence(const std::string& path, const std::string& topic, std::size_t max_scans);

/// The scans a command line names, as `cairn slam3d` and `cairn localize3d` read them: one bag
/// (bag::is_bag) gives its PointCloud2 topic `cloud_topic` ("" = the only one) with the header
/// stamps; otherwise list_scans, cut to the first `max_scans` (0: all), with the times of
/// `times_path` (column `column`, 1-based) or 0.1 s apart. Throws std::invalid_argument for a
/// times table with a bag or a topic with files, io::ParseError for unreadable input.
ScanSequence open_scan_sequence(const std::vector<std::string>& paths, const std::string& times_path, int column,
                                const std::string& cloud_topic, std::size_t max_scans);

}  // namespace cairn::lidar3d
