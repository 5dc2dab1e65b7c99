#pragma once
/// \file
/// A decoded message as a tree of values, laid out by the MessageSchema it was decoded with:
/// numbers keep their exact type (signed, unsigned, floating), uint8/int8 arrays are raw bytes
/// (an image's or a point cloud's data are copied once, not one value per byte), nested
/// messages and arrays hold their elements. Fields are looked up by name; a missing field or a
/// value of the wrong kind throws std::runtime_error naming the field, which the decoders of
/// bag/sensor_messages.hpp turn into an error naming the topic.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace cairn::bag {

struct MessageSchema;

class Value {
 public:
  enum class Kind : std::uint8_t { kBool, kInt, kUInt, kFloat, kString, kBytes, kArray, kMessage };

  static Value boolean(bool b);
  static Value integer(std::int64_t i);
  static Value unsigned_integer(std::uint64_t u);
  static Value floating(double f);
  static Value string(std::string text);
  static Value bytes(std::string raw);
  /// Bytes left where they are (an image's or a cloud's data inside a bag's chunk), kept valid by
  /// `owner`: no copy.
  static Value bytes_view(std::shared_ptr<const void> owner, std::string_view bytes);
  static Value array(std::vector<Value> items);
  /// The value keeps `schema` alive (it outlives the decoder that made it).
  static Value message(std::shared_ptr<const MessageSchema> schema, std::vector<Value> fields);

  Kind kind() const { return kind_; }
  bool is_number() const { return kind_ == Kind::kBool || kind_ == Kind::kInt || kind_ == Kind::kUInt || kind_ == Kind::kFloat; }

  /// Any number (bool, integer, floating) as a double.
  double number() const;
  std::int64_t as_int() const;
  std::uint64_t as_uint() const;
  bool as_bool() const;
  /// kString or kBytes (valid as long as the value).
  std::string_view text() const;
  /// kArray elements or kMessage fields (in the schema's order).
  const std::vector<Value>& items() const;
  /// The field `name` of a message; throws std::runtime_error when there is none.
  const Value& operator[](std::string_view name) const;
  /// The field `name`, or nullptr.
  const Value* find(std::string_view name) const;
  /// kMessage: the layout it was decoded with.
  const MessageSchema* schema() const { return schema_.get(); }
  /// kArray of numbers, or kBytes: every element as a double.
  std::vector<double> numbers() const;

 private:
  Kind kind_ = Kind::kInt;
  union {
    bool b_;
    std::int64_t i_ = 0;
    std::uint64_t u_;
    double f_;
  };
  std::string text_;
  std::shared_ptr<const void> owner_;  ///< kBytes by view: keeps view_ valid
  std::string_view view_;
  std::vector<Value> items_;
  std::shared_ptr<const MessageSchema> schema_;
};

}  // namespace cairn::bag
