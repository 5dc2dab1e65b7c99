#pragma once
/// \file
/// Message layouts parsed from the definitions a bag carries: ROS 1 `.msg` text (a ROS 1
/// connection's message_definition, an MCAP schema of encoding "ros1msg") and its ROS 2 form
/// ("ros2msg": rosbag2's message_definitions table, MCAP schemas). Both list the top-level type's
/// fields, then each type it depends on after a line of '=' and "MSG: pkg/Type"
/// (wiki.ros.org/msg, design.ros2.org "Interface definition").
///
/// Understood: the primitive types (bool, byte, char, int8..uint64, float32, float64, string,
/// ROS 1 time and duration, ROS 2 wstring is refused), fixed arrays `T[N]`, sequences `T[]`,
/// bounded forms `T[<=N]` and `string<=N`, constants (`int32 X=1`, skipped: they are not
/// serialised), ROS 2 default values (`int32 x 5`, ignored), `Header` (std_msgs/Header), nested
/// types by full or short name (a short name means the enclosing message's package), with or
/// without ROS 2's "/msg/" infix. Errors name the definition's line.

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace cairn::bag {

enum class Primitive : std::uint8_t {
  kBool,
  kInt8,
  kUInt8,
  kInt16,
  kUInt16,
  kInt32,
  kUInt32,
  kInt64,
  kUInt64,
  kFloat32,
  kFloat64,
  kString,
  kTime,      ///< ROS 1 time: uint32 sec, uint32 nsec
  kDuration,  ///< ROS 1 duration: int32 sec, int32 nsec
  kMessage,   ///< a nested message: Field::message_type names it
};

/// Size in bytes of a fixed-size primitive (0 for string and message).
std::size_t primitive_size(Primitive primitive);

struct Field {
  std::string name;
  Primitive primitive = Primitive::kInt32;
  /// For kMessage: the normalised type name ("std_msgs/Header").
  std::string message_type;
  enum class Array : std::uint8_t { kNone, kFixed, kSequence } array = Array::kNone;
  /// kFixed: the element count; kSequence: the bound (0 = unbounded), only checked.
  std::size_t array_size = 0;
};

struct MessageSchema {
  std::string type;  ///< normalised: "sensor_msgs/LaserScan"
  std::vector<Field> fields;
};

/// Normalises a type name: "sensor_msgs/msg/LaserScan" -> "sensor_msgs/LaserScan".
std::string normalize_type(std::string_view type);

/// The layouts of one top-level type and everything it uses.
class SchemaSet {
 public:
  enum class Dialect : std::uint8_t { kRos1, kRos2 };

  /// Parses `definition` (the text a connection or schema carries) for type `type`. `where` names
  /// the source in errors ("bag.bag: connection 3 (/scan)"). Throws io::ParseError naming the line
  /// of the definition and what was wrong; also when a type is used but never defined (and is not
  /// one ROS defines implicitly: std_msgs/Header in ROS 1, builtin_interfaces/Time and Duration).
  static SchemaSet parse(std::string_view type, std::string_view definition, Dialect dialect, const std::string& where);

  const MessageSchema& root() const { return *root_; }
  /// The root and any schema as shared pointers (decoded values keep their layout alive).
  std::shared_ptr<const MessageSchema> shared_root() const { return root_; }
  std::shared_ptr<const MessageSchema> shared(const std::string& type) const;
  /// The schema of a normalised type name; throws std::out_of_range if the set does not hold it.
  const MessageSchema& at(const std::string& type) const;
  Dialect dialect() const { return dialect_; }

 private:
  std::map<std::string, std::shared_ptr<MessageSchema>> schemas_;
  std::shared_ptr<const MessageSchema> root_;
  Dialect dialect_ = Dialect::kRos1;
};

}  // namespace cairn::bag
