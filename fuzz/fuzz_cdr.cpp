// libFuzzer entry point for the message deserialisers (bag/deserialize.hpp: ROS 1 serialisation and
// CDR as ROS 2 writes it) and the typed decoders behind them (bag/sensor_messages.hpp,
// bag/point_cloud2.hpp), without a container around the bytes. The first input byte picks one of a
// few fixed layouts (sensor_msgs/PointCloud2, LaserScan, Imu, tf2_msgs/TFMessage and a message of
// nested sequences and strings, each with its ROS 1 and its ROS 2 definition text), the second
// byte ROS 1 (even) or CDR (odd), the rest is the payload: SchemaSet::parse, deserialize, then the
// typed decoder. Any input must end in a value, an io::ParseError (bytes that do not fit the
// layout) or, from a typed decoder, a std::runtime_error: another exception, a crash, a hang or a
// sanitizer report is a bug. The corpus in fuzz/corpus/cdr runs in `make test`.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>

#include "cairn/bag/deserialize.hpp"
#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/value.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

constexpr const char* kSeparator = "================================================================================\n";

/// std_msgs/Header and what it uses, as the dependency sections of a definition.
std::string header_sections(SchemaSet::Dialect dialect) {
  if (dialect == SchemaSet::Dialect::kRos1) {
    return std::string(kSeparator) +
           "MSG: std_msgs/Header\n"
           "# sequence ID: consecutively increasing ID\n"
           "uint32 seq\n"
           "time stamp\n"
           "string frame_id\n";
  }
  return std::string(kSeparator) +
         "MSG: std_msgs/Header\n"
         "# Standard metadata for higher-level stamped data types.\n"
         "builtin_interfaces/Time stamp\n"
         "string frame_id\n" +
         kSeparator +
         "MSG: builtin_interfaces/Time\n"
         "int32 sec\n"
         "uint32 nanosec\n";
}

std::string header_field(SchemaSet::Dialect dialect) {
  return dialect == SchemaSet::Dialect::kRos1 ? "Header header\n" : "std_msgs/Header header\n";
}

// sensor_msgs/PointCloud2 (sensor_msgs/msg/PointCloud2.msg, comments shortened).
std::string point_cloud2_definition(SchemaSet::Dialect dialect) {
  return "# This message holds a collection of N-dimensional points.\n" + header_field(dialect) +
         "\n"
         "# 2D structure of the point cloud.\n"
         "uint32 height\n"
         "uint32 width\n"
         "PointField[] fields\n"
         "bool    is_bigendian # Is this data bigendian?\n"
         "uint32  point_step   # Length of a point in bytes\n"
         "uint32  row_step     # Length of a row in bytes\n"
         "uint8[] data         # Actual point data, size is (row_step*height)\n"
         "bool is_dense        # True if there are no invalid points\n" +
         header_sections(dialect) + kSeparator +
         "MSG: sensor_msgs/PointField\n"
         "uint8 INT8    = 1\n"
         "uint8 UINT8   = 2\n"
         "uint8 INT16   = 3\n"
         "uint8 UINT16  = 4\n"
         "uint8 INT32   = 5\n"
         "uint8 UINT32  = 6\n"
         "uint8 FLOAT32 = 7\n"
         "uint8 FLOAT64 = 8\n"
         "string name      # Name of field\n"
         "uint32 offset    # Offset from start of pixel start\n"
         "uint8  datatype  # Datatype enumeration, see above\n"
         "uint32 count     # How many elements in the field\n";
}

// sensor_msgs/LaserScan.
std::string laser_scan_definition(SchemaSet::Dialect dialect) {
  return header_field(dialect) +
         "float32 angle_min        # start angle of the scan [rad]\n"
         "float32 angle_max\n"
         "float32 angle_increment\n"
         "float32 time_increment\n"
         "float32 scan_time\n"
         "float32 range_min\n"
         "float32 range_max\n"
         "float32[] ranges\n"
         "float32[] intensities\n" +
         header_sections(dialect);
}

std::string vector3_and_quaternion_sections(SchemaSet::Dialect dialect) {
  const bool ros2 = dialect == SchemaSet::Dialect::kRos2;
  return std::string(kSeparator) + "MSG: geometry_msgs/Quaternion\n" +
         (ros2 ? "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n" : "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n") +
         kSeparator + "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n";
}

// sensor_msgs/Imu.
std::string imu_definition(SchemaSet::Dialect dialect) {
  return header_field(dialect) +
         "geometry_msgs/Quaternion orientation\n"
         "float64[9] orientation_covariance # Row major about x, y, z axes\n"
         "geometry_msgs/Vector3 angular_velocity\n"
         "float64[9] angular_velocity_covariance\n"
         "geometry_msgs/Vector3 linear_acceleration\n"
         "float64[9] linear_acceleration_covariance\n" +
         header_sections(dialect) + vector3_and_quaternion_sections(dialect);
}

// tf2_msgs/TFMessage: a sequence of messages holding strings.
std::string tf_message_definition(SchemaSet::Dialect dialect) {
  return "geometry_msgs/TransformStamped[] transforms\n" + std::string(kSeparator) +
         "MSG: geometry_msgs/TransformStamped\n" + header_field(dialect) +
         "string child_frame_id # the frame id of the child frame\n"
         "Transform transform\n" +
         header_sections(dialect) + kSeparator +
         "MSG: geometry_msgs/Transform\n"
         "Vector3 translation\n"
         "Quaternion rotation\n" +
         vector3_and_quaternion_sections(dialect);
}

// Sequences of messages holding sequences and strings, fixed and bounded arrays, bounded strings,
// times (ROS 1 time and duration; ROS 2 builtin_interfaces).
std::string nested_definition(SchemaSet::Dialect dialect) {
  const bool ros2 = dialect == SchemaSet::Dialect::kRos2;
  return std::string(
             "string name\n"
             "Item[] items\n"
             "string[] tags\n"
             "Item[2] pair\n"
             "uint8[] blob\n"
             "int16[<=3] bounded\n"
             "string<=8 short_text\n"
             "float64[3] fixed\n"
             "int8 LIMIT=-3\n") +
         kSeparator +
         "MSG: cairn_fuzz/Item\n"
         "string label\n"
         "int32[] values\n"
         "Leaf[] leaves\n"
         "bool flag\n" +
         kSeparator +
         "MSG: cairn_fuzz/Leaf\n"
         "uint64 id\n"
         "string[] names\n"
         "float32 weight\n" +
         (ros2 ? "builtin_interfaces/Time stamp\nbuiltin_interfaces/Duration span\n" : "time stamp\nduration span\n");
}

/// Reads every leaf of a decoded value through the Value accessors.
void walk(const Value& value) {
  switch (value.kind()) {
    case Value::Kind::kString:
    case Value::Kind::kBytes: (void)value.text().size(); break;
    case Value::Kind::kArray:
    case Value::Kind::kMessage:
      for (const Value& item : value.items()) walk(item);
      break;
    default: (void)value.number(); break;
  }
}

void decode_nested(const Value& message) {
  walk(message);
  for (const Value& item : message["items"].items()) {
    (void)item["label"].text();
    (void)item["values"].numbers();
    for (const Value& leaf : item["leaves"].items()) (void)time_ns(leaf["stamp"]);
  }
}

struct Layout {
  const char* type;
  std::string (*definition)(SchemaSet::Dialect);
  void (*decode)(const Value&);
};

const std::array<Layout, 5> kLayouts = {{
    {"sensor_msgs/msg/PointCloud2", point_cloud2_definition, [](const Value& v) { (void)to_point_cloud(v); }},
    {"sensor_msgs/msg/LaserScan", laser_scan_definition, [](const Value& v) { (void)to_laser_scan(v); }},
    {"sensor_msgs/msg/Imu", imu_definition, [](const Value& v) { (void)to_imu(v); }},
    {"tf2_msgs/msg/TFMessage", tf_message_definition, [](const Value& v) { (void)to_tf_message(v); }},
    {"cairn_fuzz/msg/Nested", nested_definition, decode_nested},
}};

void decode(const Layout& layout, bool cdr, std::span<const std::uint8_t> payload) {
  const SchemaSet::Dialect dialect = cdr ? SchemaSet::Dialect::kRos2 : SchemaSet::Dialect::kRos1;
  const SchemaSet schemas = SchemaSet::parse(layout.type, layout.definition(dialect), dialect, "fuzz_cdr");
  try {
    const Value message = deserialize(schemas, payload, cdr ? Serialization::kCdr : Serialization::kRos1, "fuzz_cdr");
    try {
      layout.decode(message);
    } catch (const std::runtime_error&) {
      // A typed decoder refusing the values (a point cloud whose data cannot hold its points).
    }
  } catch (const io::ParseError&) {
    // Bytes that do not fit the layout.
  }
}

}  // namespace
}  // namespace cairn::bag

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const auto& layout = cairn::bag::kLayouts[data[0] % cairn::bag::kLayouts.size()];
  cairn::bag::decode(layout, (data[1] & 1u) != 0, std::span<const std::uint8_t>(data + 2, size - 2));
  return 0;
}
