#include "cairn/lidar3d/scan_sequence.hpp"

#include "cairn/bag/bag.hpp"
#include "cairn/bag/point_cloud_stream.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "cairn/io/file_names.hpp"
#include "cairn/io/input_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::lidar3d {
namespace {

namespace fs = std::filesystem;

bool is_scan_file(const std::string& name) {
  std::string base = name;
  for (const char* suffix : {".gz", ".bz2", ".xz"}) {
    const std::string s(suffix);
    if (base.size() > s.size() && base.compare(base.size() - s.size(), s.size(), s) == 0) {
      base.resize(base.size() - s.size());
      break;
    }
  }
  for (const char* ext : {".pcd", ".ply", ".bin"}) {
    const std::string e(ext);
    if (base.size() > e.size() && base.compare(base.size() - e.size(), e.size(), e) == 0) return true;
  }
  return false;
}

}  // namespace


std::vector<std::string> list_scans(const std::vector<std::string>& paths) {
  if (paths.empty()) throw io::ParseError("(scans)", 0, "no scan files or folder given");
  std::vector<std::string> files;
  for (const std::string& path : paths) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (ec || !fs::exists(status)) throw io::ParseError(path, 0, "cannot open: no such file or directory");
    if (fs::is_directory(status)) {
      if (paths.size() != 1) throw io::ParseError(path, 0, "give one folder of scans, or scan files, not both");
      for (const fs::directory_entry& entry : fs::directory_iterator(path, ec)) {
        const std::string name = entry.path().filename().string();
        if (is_scan_file(name) && !entry.is_directory()) files.push_back(entry.path().string());
      }
      if (ec) throw io::ParseError(path, 0, "cannot list the folder: " + ec.message());
      std::sort(files.begin(), files.end(), [](const std::string& a, const std::string& b) {
        return io::natural_less(fs::path(a).filename().string(), fs::path(b).filename().string());
      });
      if (files.empty()) {
        throw io::ParseError(path, 0, "no scan files in the folder (expected .pcd, .ply or .bin, optionally .gz/.bz2/.xz)");
      }
      return files;
    }
    files.push_back(path);
  }
  return files;
}

std::vector<double> read_scan_times(const std::string& times_path, int column, std::size_t count) {
  if (column < 1) throw io::ParseError(times_path, 0, "the time column must be >= 1, got " + std::to_string(column));
  io::check_input_file(times_path);
  std::ifstream in(times_path, std::ios::binary);
  if (!in) throw io::ParseError(times_path, 0, "cannot open");
  std::vector<double> times;
  times.reserve(count);
  std::string line;
  std::size_t line_number = 0;
  while (times.size() < count && std::getline(in, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();  // CRLF line ends
    if (line.find('\0') != std::string::npos) throw io::ParseError(times_path, line_number, "binary data in a text table");
    std::istringstream fields(line);
    std::string field, first;
    if (!(fields >> first) || first[0] == '#') continue;
    field = first;
    for (int c = 1; c < column; ++c) {
      if (!(fields >> field)) {
        throw io::ParseError(times_path, line_number,
                             "expected at least " + std::to_string(column) + " columns, found " + std::to_string(c));
      }
    }
    double value = 0.0;
    const auto [end, error] = std::from_chars(field.data(), field.data() + field.size(), value);
    if (error != std::errc() || end != field.data() + field.size() || !std::isfinite(value)) {
      throw io::ParseError(times_path, line_number,
                           "expected a time in seconds in column " + std::to_string(column) + ", found '" + field + "'");
    }
    if (!times.empty() && !(value > times.back())) {
      throw io::ParseError(times_path, line_number, "times must strictly increase (" + field + " after " +
                                                        std::to_string(times.back()) + ")");
    }
    times.push_back(value);
  }
  if (in.bad()) throw io::ParseError(times_path, line_number, "read error");
  if (times.size() < count) {
    throw io::ParseError(times_path, line_number, "expected a time for each of the " + std::to_string(count) +
                                                      " scans, found " + std::to_string(times.size()));
  }
  return times;
}

ScanSequence make_bag_scan_sequence(const std::string& path, const std::string& topic, std::size_t max_scans) {
  const bag::PointCloudStream stream(path, topic);
  ScanSequence sequence;
  sequence.bag = path;
  sequence.bag_topic = stream.topic();
  std::size_t n = stream.size();
  if (max_scans > 0) n = std::min(n, max_scans);
  for (std::size_t k = 0; k < n; ++k) sequence.files.push_back(path + " " + sequence.bag_topic + " #" + std::to_string(k));
  sequence.times_from_file = true;  // the header stamps
  return sequence;
}

ScanSequence make_scan_sequence(const std::vector<std::string>& paths, const std::string& times_path, int column,
                                double default_period_s) {
  ScanSequence sequence;
  sequence.files = list_scans(paths);
  if (!times_path.empty()) {
    sequence.times_s = read_scan_times(times_path, column, sequence.files.size());
    sequence.times_from_file = true;
  } else {
    for (std::size_t k = 0; k < sequence.files.size(); ++k) sequence.times_s.push_back(static_cast<double>(k) * default_period_s);
  }
  return sequence;
}

ScanSequence open_scan_sequence(const std::vector<std::string>& paths, const std::string& times_path, int column,
                                const std::string& cloud_topic, std::size_t max_scans) {
  if (paths.size() == 1 && bag::is_bag(paths.front())) {
    if (!times_path.empty()) throw std::invalid_argument("--times goes with scan files: a bag's scans carry their stamps");
    return make_bag_scan_sequence(paths.front(), cloud_topic, max_scans);
  }
  if (!cloud_topic.empty()) throw std::invalid_argument("--cloud-topic goes with a bag, and the scans are files");
  ScanSequence sequence;
  sequence.files = list_scans(paths);
  if (max_scans > 0 && sequence.files.size() > max_scans) sequence.files.resize(max_scans);
  if (!times_path.empty()) {
    sequence.times_s = read_scan_times(times_path, column, sequence.files.size());
    sequence.times_from_file = true;
  } else {
    for (std::size_t k = 0; k < sequence.files.size(); ++k) sequence.times_s.push_back(0.1 * static_cast<double>(k));
  }
  return sequence;
}

}  // namespace cairn::lidar3d
