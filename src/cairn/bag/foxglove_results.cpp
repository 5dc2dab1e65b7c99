#include "cairn/bag/foxglove_results.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "cairn/bag/mcap_writer.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::bag {
namespace {

using nlohmann::json;

std::string base64(const void* data, std::size_t size) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const std::uint32_t chunk = (static_cast<std::uint32_t>(bytes[i]) << 16) |
                                (i + 1 < size ? static_cast<std::uint32_t>(bytes[i + 1]) << 8 : 0u) |
                                (i + 2 < size ? static_cast<std::uint32_t>(bytes[i + 2]) : 0u);
    out += kAlphabet[(chunk >> 18) & 63];
    out += kAlphabet[(chunk >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(chunk >> 6) & 63] : '=';
    out += i + 2 < size ? kAlphabet[chunk & 63] : '=';
  }
  return out;
}

json time_json(std::int64_t ns) { return {{"sec", ns / 1'000'000'000}, {"nsec", ns % 1'000'000'000}}; }

json pose_json(const core::SE3& T) {
  const Eigen::Quaterniond q = T.so3().unit_quaternion();
  return {{"position", {{"x", T.translation().x()}, {"y", T.translation().y()}, {"z", T.translation().z()}}},
          {"orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}

json identity_pose() { return pose_json(core::SE3()); }

/// A JSON Schema naming the top-level fields (Foxglove identifies the schema by its name).
std::string schema_text(const std::string& name, const std::vector<std::string>& fields) {
  json properties = json::object();
  for (const std::string& field : fields) properties[field] = json::object();
  return json{{"$schema", "https://json-schema.org/draft/2020-12/schema"},
              {"title", name},
              {"type", "object"},
              {"properties", properties}}
      .dump();
}

class JsonChannels {
 public:
  explicit JsonChannels(std::ostream& out) : writer_(out) {}
  std::uint16_t add(const std::string& topic, const std::string& schema, const std::vector<std::string>& fields) {
    const std::uint16_t schema_id = writer_.add_schema(schema, "jsonschema", schema_text(schema, fields));
    return writer_.add_channel(topic, schema_id, "json");
  }
  void write(std::uint16_t channel, std::int64_t time_ns, const json& message) {
    const std::string text = message.dump();
    const auto t = static_cast<std::uint64_t>(std::max<std::int64_t>(time_ns, 0));
    writer_.write(channel, t, t, std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
  }
  void finish() { writer_.finish(); }

 private:
  McapWriter writer_;
};

void check(const FoxgloveResults& r) {
  if (r.stamps_ns.size() != r.T_frame_body.size()) throw std::invalid_argument("write_foxglove_mcap: stamps and poses differ in number");
  if (!r.health.empty() && r.health.size() != r.stamps_ns.size()) {
    throw std::invalid_argument("write_foxglove_mcap: health and poses differ in number");
  }
}

json point_cloud_json(const FoxgloveResults& r, std::int64_t t0) {
  return {{"timestamp", time_json(t0)},
          {"frame_id", r.frame_id},
          {"pose", identity_pose()},
          {"point_stride", 12},
          {"fields", json::array({{{"name", "x"}, {"offset", 0}, {"type", 7}},
                                  {{"name", "y"}, {"offset", 4}, {"type", 7}},
                                  {{"name", "z"}, {"offset", 8}, {"type", 7}}})},
          {"data", base64(r.map_points.data(), r.map_points.size() * sizeof(Eigen::Vector3f))}};
}

json grid_json(const FoxgloveResults& r, std::int64_t t0) {
  const OccupancyGrid& g = *r.grid;
  json pose = identity_pose();
  pose["position"]["x"] = g.origin_m.x();
  pose["position"]["y"] = g.origin_m.y();
  return {{"timestamp", time_json(t0)},
          {"frame_id", r.frame_id},
          {"pose", pose},
          {"column_count", g.width},
          {"cell_size", {{"x", g.resolution_m}, {"y", g.resolution_m}}},
          {"row_stride", g.width},
          {"cell_stride", 1},
          {"fields", json::array({{{"name", "occupancy"}, {"offset", 0}, {"type", 2}}})},  // INT8
          {"data", base64(g.cells.data(), g.cells.size())}};
}

json loops_json(const FoxgloveResults& r, std::int64_t t0) {
  json points = json::array();
  for (const auto& [a, b] : r.loop_closures) {
    for (const Eigen::Vector3d& p : {a, b}) points.push_back({{"x", p.x()}, {"y", p.y()}, {"z", p.z()}});
  }
  json line = {{"type", 2},  // LINE_LIST
               {"pose", identity_pose()},
               {"thickness", 3},
               {"scale_invariant", true},
               {"points", points},
               {"color", {{"r", 1.0}, {"g", 0.2}, {"b", 0.2}, {"a", 1.0}}},
               {"colors", json::array()},
               {"indices", json::array()}};
  json entity = {{"timestamp", time_json(t0)}, {"frame_id", r.frame_id}, {"id", "loop_closures"},
                 {"lifetime", {{"sec", 0}, {"nsec", 0}}}, {"frame_locked", false}, {"metadata", json::array()},
                 {"arrows", json::array()}, {"cubes", json::array()}, {"spheres", json::array()},
                 {"cylinders", json::array()}, {"lines", json::array({line})}, {"triangles", json::array()},
                 {"texts", json::array()}, {"models", json::array()}};
  return {{"deletions", json::array()}, {"entities", json::array({entity})}};
}

}  // namespace

void write_foxglove_mcap(std::ostream& out, const FoxgloveResults& r) {
  check(r);
  JsonChannels channels(out);
  const std::int64_t t0 = r.stamps_ns.empty() ? 0 : r.stamps_ns.front();
  const std::uint16_t trajectory = channels.add("/trajectory", "foxglove.PosesInFrame", {"timestamp", "frame_id", "poses"});
  json poses = json::array();
  for (const core::SE3& T : r.T_frame_body) poses.push_back(pose_json(T));
  channels.write(trajectory, t0, {{"timestamp", time_json(t0)}, {"frame_id", r.frame_id}, {"poses", poses}});
  if (!r.map_points.empty()) {
    const std::uint16_t map = channels.add("/map", "foxglove.PointCloud", {"timestamp", "frame_id", "pose", "point_stride", "fields", "data"});
    channels.write(map, t0, point_cloud_json(r, t0));
  }
  if (r.grid) {
    const std::uint16_t grid = channels.add(
        "/grid", "foxglove.Grid", {"timestamp", "frame_id", "pose", "column_count", "cell_size", "row_stride", "cell_stride", "fields", "data"});
    channels.write(grid, t0, grid_json(r, t0));
  }
  if (!r.loop_closures.empty()) {
    const std::uint16_t loops = channels.add("/loop_closures", "foxglove.SceneUpdate", {"deletions", "entities"});
    channels.write(loops, t0, loops_json(r, t0));
  }
  const std::uint16_t tf = channels.add("/tf", "foxglove.FrameTransform",
                                        {"timestamp", "parent_frame_id", "child_frame_id", "translation", "rotation"});
  const std::uint16_t pose = channels.add("/pose", "foxglove.PoseInFrame", {"timestamp", "frame_id", "pose"});
  const std::uint16_t health = r.health.empty() ? 0 : channels.add("/health", "foxglove.Log", {"timestamp", "level", "message", "name", "file", "line"});
  std::string last_health;
  for (std::size_t k = 0; k < r.stamps_ns.size(); ++k) {
    const json p = pose_json(r.T_frame_body[k]);
    channels.write(tf, r.stamps_ns[k], {{"timestamp", time_json(r.stamps_ns[k])}, {"parent_frame_id", r.frame_id},
                                        {"child_frame_id", r.body_frame_id}, {"translation", p["position"]},
                                        {"rotation", p["orientation"]}});
    channels.write(pose, r.stamps_ns[k], {{"timestamp", time_json(r.stamps_ns[k])}, {"frame_id", r.frame_id}, {"pose", p}});
    if (health != 0 && r.health[k] != last_health) {
      const int level = r.health[k] == "ok" ? 2 : r.health[k] == "degraded" ? 3 : 4;  // INFO, WARNING, ERROR
      channels.write(health, r.stamps_ns[k], {{"timestamp", time_json(r.stamps_ns[k])}, {"level", level},
                                              {"message", "health: " + r.health[k]}, {"name", "cairn"},
                                              {"file", ""}, {"line", 0}});
      last_health = r.health[k];
    }
  }
  channels.finish();
}

void write_foxglove_mcap(const std::string& path, const FoxgloveResults& results) {
  io::write_output(path, [&](std::ostream& out) { write_foxglove_mcap(out, results); });
}

}  // namespace cairn::bag
