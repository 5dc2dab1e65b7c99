// `cairn info BAG`: what a ROS 1 bag, MCAP file, rosbag2 SQLite3 file or rosbag2 folder holds, in
// the layout of `rosbag info` (files, time span, compression, then one line per topic).

#include <cstdio>
#include <iostream>
#include <sstream>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/bag_info.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::cli {
namespace {

std::string seconds_text(std::int64_t ns) {
  char text[64];
  std::snprintf(text, sizeof text, "%.3f", static_cast<double>(ns) * 1e-9);
  return text;
}

std::string chunks_text(const nlohmann::json& chunks) {
  if (chunks.empty()) return "no chunks";
  std::string out;
  for (const auto& [compression, count] : chunks.items()) {
    out += (out.empty() ? "" : ", ") + compression + " x" + std::to_string(count.get<std::uint64_t>());
  }
  return out + " chunks";
}

void print_bag_info(const nlohmann::json& j) {
  std::ostringstream o;
  o << "path         " << j["path"].get<std::string>() << '\n';
  o << "format       " << j["format"].get<std::string>() << '\n';
  for (const auto& file : j["files"]) {
    o << "file         " << file["path"].get<std::string>() << "  (" << file["format"].get<std::string>();
    if (!file["profile"].get<std::string>().empty()) o << ", profile " << file["profile"].get<std::string>();
    o << ", " << file["bytes"].get<std::uint64_t>() << " bytes, " << chunks_text(file["chunks"]) << ", "
      << (file["indexed"].get<bool>() ? "indexed" : "no index: counts from a scan") << ")\n";
    for (const auto& note : file["notes"]) o << "  note       " << note.get<std::string>() << '\n';
  }
  o << "messages     " << j["messages"].get<std::uint64_t>() << '\n';
  o << "start        " << seconds_text(j["start_ns"].get<std::int64_t>()) << " s\n";
  o << "end          " << seconds_text(j["end_ns"].get<std::int64_t>()) << " s\n";
  char duration[64];
  std::snprintf(duration, sizeof duration, "%.3f s", j["duration_s"].get<double>());
  o << "duration     " << duration << '\n';
  o << "topics\n";
  for (const auto& t : j["topics"]) {
    char line[512];
    std::snprintf(line, sizeof line, "  %-36s %8llu msgs %8.2f Hz  %s [%s]", t["name"].get<std::string>().c_str(),
                  static_cast<unsigned long long>(t["messages"].get<std::uint64_t>()), t["rate_hz"].get<double>(),
                  t["type"].get<std::string>().c_str(), t["encoding"].get<std::string>().c_str());
    o << line;
    if (!t["decodable"].get<bool>()) o << "  not decoded: " << t["why_not"].get<std::string>();
    o << '\n';
  }
  std::cout << o.str();
}

}  // namespace

int info_bag(const std::string& path, const std::string& json) {
  const bag::Bag bag = bag::Bag::open(path);
  const nlohmann::json j = bag::bag_info_json(bag);
  if (!json.empty()) io::write_output(json, [&](std::ostream& out) { out << io::json_text(j); });
  if (!io::is_standard_output(json)) print_bag_info(j);
  return 0;
}

}  // namespace cairn::cli
