#include "cairn/bag/point_cloud2.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

namespace cairn::bag {
namespace {

/// sensor_msgs/PointField datatypes.
enum Datatype : std::uint8_t { kInt8 = 1, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

std::size_t datatype_size(std::uint64_t datatype) {
  switch (datatype) {
    case kInt8:
    case kUInt8: return 1;
    case kInt16:
    case kUInt16: return 2;
    case kInt32:
    case kUInt32:
    case kFloat32: return 4;
    case kFloat64: return 8;
    default: return 0;
  }
}

struct FieldLayout {
  std::string name;
  std::size_t offset = 0;
  std::uint64_t datatype = 0;
  bool present = false;
};

/// Reads one field of one point as a double.
double read_field(const unsigned char* point, const FieldLayout& field, bool big_endian) {
  unsigned char raw[8];
  const std::size_t size = datatype_size(field.datatype);
  std::memcpy(raw, point + field.offset, size);
  if (big_endian) std::reverse(raw, raw + size);
  switch (field.datatype) {
    case kInt8: return static_cast<double>(static_cast<std::int8_t>(raw[0]));
    case kUInt8: return static_cast<double>(raw[0]);
    case kInt16: { std::int16_t v; std::memcpy(&v, raw, 2); return v; }
    case kUInt16: { std::uint16_t v; std::memcpy(&v, raw, 2); return v; }
    case kInt32: { std::int32_t v; std::memcpy(&v, raw, 4); return v; }
    case kUInt32: { std::uint32_t v; std::memcpy(&v, raw, 4); return v; }
    case kFloat32: { float v; std::memcpy(&v, raw, 4); return static_cast<double>(v); }
    default: { double v; std::memcpy(&v, raw, 8); return v; }
  }
}

std::uint16_t ring_of(double value, const std::string& field) {
  if (!(value >= 0.0 && value <= 65535.0)) {
    throw std::runtime_error("PointField '" + field + "' holds " + std::to_string(value) + ", not a ring number 0..65535");
  }
  return static_cast<std::uint16_t>(value);
}

FieldLayout find_field(const std::vector<FieldLayout>& fields, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    for (const FieldLayout& field : fields) {
      if (field.name == name) return field;
    }
  }
  return {};
}

/// A uint32 field of the message (a bag's own definition may declare it wider): refused above 2^32 - 1.
std::uint64_t uint32_field(const Value& message, const char* name) {
  const std::uint64_t value = message[name].as_uint();
  if (value > UINT32_MAX) throw std::runtime_error(std::string(name) + " is " + std::to_string(value) + ", beyond uint32");
  return value;
}

std::vector<FieldLayout> read_fields(const Value& message, std::size_t point_step) {
  std::vector<FieldLayout> fields;
  for (const Value& field : message["fields"].items()) {
    FieldLayout layout{std::string(field["name"].text()), static_cast<std::size_t>(uint32_field(field, "offset")),
                       field["datatype"].as_uint(), true};
    const std::size_t size = datatype_size(layout.datatype);
    if (size == 0) {
      throw std::runtime_error("PointField '" + layout.name + "' has datatype " + std::to_string(layout.datatype) +
                               ", expected 1..8");
    }
    if (layout.offset + size > point_step) {
      throw std::runtime_error("PointField '" + layout.name + "' ends at byte " + std::to_string(layout.offset + size) +
                               " of a " + std::to_string(point_step) + "-byte point");
    }
    fields.push_back(std::move(layout));
  }
  return fields;
}

/// Scale and shift that take a time field's raw value to seconds relative to the stamp.
struct TimeConversion {
  double scale = 1.0;
  double shift = 0.0;
};

TimeConversion time_conversion(const FieldLayout& field, double first_value, double stamp_s) {
  if (field.name == "t" || field.name == "offset_time") return {1e-9, 0.0};
  if (std::fabs(first_value) > 1e15) return {1e-9, -stamp_s};  // absolute nanoseconds
  if (std::fabs(first_value) > 1e8) return {1.0, -stamp_s};    // absolute seconds
  return {1.0, 0.0};
}

}  // namespace

io::PointCloud to_point_cloud(const Value& message, PointCloud2Report* report) {
  PointCloud2Report local;
  PointCloud2Report& r = report != nullptr ? *report : local;
  r = {};
  r.header = to_header(message["header"]);
  const std::uint64_t height = uint32_field(message, "height");
  const std::uint64_t width = uint32_field(message, "width");
  const std::size_t point_step = static_cast<std::size_t>(uint32_field(message, "point_step"));
  const std::uint64_t row_step = uint32_field(message, "row_step");
  const bool big_endian = message["is_bigendian"].as_bool();
  const std::string_view data = message["data"].text();
  if (point_step == 0 && height * width > 0) throw std::runtime_error("point_step is 0");
  if (width > 0 && (row_step < width * point_step || height > data.size() / std::max<std::uint64_t>(row_step, 1) + 1 ||
                    (height > 0 && (height - 1) * row_step + width * point_step > data.size()))) {
    throw std::runtime_error("data holds " + std::to_string(data.size()) + " bytes, " + std::to_string(height) + " x " +
                             std::to_string(width) + " points of " + std::to_string(point_step) + " bytes (row_step " +
                             std::to_string(row_step) + ") do not fit");
  }
  const std::vector<FieldLayout> fields = read_fields(message, point_step);
  const FieldLayout x = find_field(fields, {"x"}), y = find_field(fields, {"y"}), z = find_field(fields, {"z"});
  if (!x.present || !y.present || !z.present) throw std::runtime_error("PointCloud2 without x, y and z fields");
  const FieldLayout intensity = find_field(fields, {"intensity", "i", "reflectivity"});
  const FieldLayout ring = find_field(fields, {"ring", "line"});
  const FieldLayout time = find_field(fields, {"time", "t", "offset_time", "timestamp"});
  r.intensity_field = intensity.name;
  r.ring_field = ring.name;
  r.time_field = time.name;

  io::PointCloud cloud;
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const double stamp_s = static_cast<double>(r.header.stamp_ns) * 1e-9;
  TimeConversion conversion;
  bool have_conversion = false;
  cloud.points.reserve(static_cast<std::size_t>(height * width));
  for (std::uint64_t row = 0; row < height; ++row) {
    for (std::uint64_t column = 0; column < width; ++column) {
      const unsigned char* point = bytes + row * row_step + column * point_step;
      const Eigen::Vector3d p(read_field(point, x, big_endian), read_field(point, y, big_endian),
                              read_field(point, z, big_endian));
      if (!p.allFinite()) {
        ++r.dropped_non_finite;
        continue;
      }
      cloud.points.push_back(p.cast<float>());
      if (intensity.present) cloud.intensity.push_back(static_cast<float>(read_field(point, intensity, big_endian)));
      if (ring.present) cloud.ring.push_back(ring_of(read_field(point, ring, big_endian), ring.name));
      if (time.present) {
        const double raw = read_field(point, time, big_endian);
        if (!have_conversion) conversion = time_conversion(time, raw, stamp_s);
        have_conversion = true;
        cloud.time_s.push_back(static_cast<float>(raw * conversion.scale + conversion.shift));
      }
    }
  }
  return cloud;
}

}  // namespace cairn::bag
