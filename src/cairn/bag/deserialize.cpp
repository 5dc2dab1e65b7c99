#include "cairn/bag/deserialize.hpp"

#include <bit>
#include <cstring>
#include <memory>
#include <utility>
#include <vector>

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

/// Walks the bytes of one message. `origin` is where alignment counts from (CDR: after the
/// encapsulation header); `swap` is set for big-endian CDR.
class Decoder {
 public:
  Decoder(const SchemaSet& schemas, std::span<const std::uint8_t> bytes, Serialization serialization,
          const std::string& where, std::shared_ptr<const void> owner)
      : schemas_(schemas), bytes_(bytes), cdr_(serialization == Serialization::kCdr), where_(where), owner_(std::move(owner)) {}

  Value run() {
    if (cdr_) read_encapsulation();
    Value root = read_message(schemas_.shared_root(), 0);
    if (!cdr_ && position_ != bytes_.size()) {
      fail(std::to_string(bytes_.size() - position_) + " bytes left after the end of the " + schemas_.root().type +
           " message: the definition does not match the data");
    }
    return root;
  }

 private:
  static constexpr int kMaxDepth = 64;
  /// Byte arrays this long or longer refer to the owner's bytes; shorter ones are copied.
  static constexpr std::size_t kViewAtLeast = 4096;

  void read_encapsulation() {
    require(4, "the CDR encapsulation header");
    const std::uint8_t kind = bytes_[1];
    if (bytes_[0] != 0 || kind > 1) {
      fail("unsupported CDR encapsulation " + std::to_string(bytes_[0]) + " " + std::to_string(kind) +
           " (expected 00 00 CDR_BE or 00 01 CDR_LE)");
    }
    swap_ = kind == 0;
    position_ = 4;
    origin_ = 4;
  }

  Value read_message(std::shared_ptr<const MessageSchema> shared_schema, int depth) {
    count_value();
    const MessageSchema& schema = *shared_schema;
    if (depth > kMaxDepth) fail("messages nested more than 64 deep in " + schema.type);
    std::vector<Value> fields;
    fields.reserve(schema.fields.size());
    if (schema.fields.empty() && cdr_) (void)read_unsigned(1);  // structure_needs_at_least_one_member
    for (const Field& field : schema.fields) fields.push_back(read_field(field, depth));
    return Value::message(std::move(shared_schema), std::move(fields));
  }

  Value read_field(const Field& field, int depth) {
    if (field.array == Field::Array::kNone) return read_element(field, depth);
    std::size_t count = field.array_size;
    if (field.array == Field::Array::kSequence) {
      count = read_count(field);
    }
    if (field.primitive == Primitive::kUInt8) return read_bytes(count, field);
    // Every element takes at least one byte (an empty CDR struct too), so a count the bytes left
    // cannot hold is refused before anything is allocated.
    if (count > bytes_.size() - position_) fail_count(field, count);
    std::vector<Value> items;
    items.reserve(count);
    for (std::size_t i = 0; i < count; ++i) items.push_back(read_element(field, depth));
    return Value::array(std::move(items));
  }

  std::size_t read_count(const Field& field) {
    const auto count = static_cast<std::size_t>(read_unsigned(4));
    if (field.array_size != 0 && count > field.array_size) {
      fail(field.name + " holds " + std::to_string(count) + " elements, its bound is " + std::to_string(field.array_size));
    }
    return count;
  }

  Value read_bytes(std::size_t count, const Field& field) {
    if (count > bytes_.size() - position_) fail_count(field, count);
    const std::string_view view(reinterpret_cast<const char*>(bytes_.data() + position_), count);
    position_ += count;
    if (owner_ && count >= kViewAtLeast) return Value::bytes_view(owner_, view);
    return Value::bytes(std::string(view));
  }

  Value read_element(const Field& field, int depth) {
    count_value();
    switch (field.primitive) {
      case Primitive::kBool: return Value::boolean(read_unsigned(1) != 0);
      case Primitive::kUInt8:
      case Primitive::kUInt16:
      case Primitive::kUInt32:
      case Primitive::kUInt64: return Value::unsigned_integer(read_unsigned(primitive_size(field.primitive)));
      case Primitive::kInt8:
      case Primitive::kInt16:
      case Primitive::kInt32:
      case Primitive::kInt64: return Value::integer(read_signed(primitive_size(field.primitive)));
      case Primitive::kFloat32: return Value::floating(static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(read_unsigned(4)))));
      case Primitive::kFloat64: return Value::floating(std::bit_cast<double>(read_unsigned(8)));
      case Primitive::kString: return Value::string(read_string());
      case Primitive::kTime: return read_ros1_time(false);
      case Primitive::kDuration: return read_ros1_time(true);
      case Primitive::kMessage: return read_message(schemas_.shared(field.message_type), depth + 1);
    }
    fail("unknown field kind");
  }

  /// ROS 1 time/duration as a message-like value with fields sec and nsec.
  Value read_ros1_time(bool is_signed) {
    static const auto time_schema = std::make_shared<const MessageSchema>(
        MessageSchema{"time", {Field{"sec", Primitive::kUInt32, "", Field::Array::kNone, 0},
                               Field{"nsec", Primitive::kUInt32, "", Field::Array::kNone, 0}}});
    static const auto duration_schema = std::make_shared<const MessageSchema>(
        MessageSchema{"duration", {Field{"sec", Primitive::kInt32, "", Field::Array::kNone, 0},
                                   Field{"nsec", Primitive::kInt32, "", Field::Array::kNone, 0}}});
    std::vector<Value> fields;
    if (is_signed) {
      fields.push_back(Value::integer(read_signed(4)));
      fields.push_back(Value::integer(read_signed(4)));
      return Value::message(duration_schema, std::move(fields));
    }
    fields.push_back(Value::unsigned_integer(read_unsigned(4)));
    fields.push_back(Value::unsigned_integer(read_unsigned(4)));
    return Value::message(time_schema, std::move(fields));
  }

  std::string read_string() {
    const auto length = static_cast<std::size_t>(read_unsigned(4));
    if (length > bytes_.size() - position_) {
      fail("a string of " + std::to_string(length) + " bytes, only " + std::to_string(bytes_.size() - position_) + " left");
    }
    std::size_t text_length = length;
    if (cdr_ && length > 0) {
      if (bytes_[position_ + length - 1] != 0) fail("a CDR string without its terminating NUL");
      text_length = length - 1;
    }
    std::string text(reinterpret_cast<const char*>(bytes_.data() + position_), text_length);
    position_ += length;
    return text;
  }

  std::uint64_t read_unsigned(std::size_t size) {
    align(size);
    require(size, "a value");
    std::uint64_t value = 0;
    if (swap_) {
      for (std::size_t i = 0; i < size; ++i) value = (value << 8) | bytes_[position_ + i];
    } else {
      for (std::size_t i = size; i-- > 0;) value = (value << 8) | bytes_[position_ + i];
    }
    position_ += size;
    return value;
  }

  std::int64_t read_signed(std::size_t size) {
    const std::uint64_t raw = read_unsigned(size);
    const unsigned shift = static_cast<unsigned>(64 - 8 * size);
    return static_cast<std::int64_t>(raw << shift) >> shift;  // sign-extend
  }

  /// A definition can make bytes decode to exponentially many values (ROS 1 empty messages in
  /// nested fixed arrays take no byte): refuse more values than the message could plausibly hold.
  void count_value() {
    if (++values_ > value_budget_) {
      fail("the definition makes this " + std::to_string(bytes_.size()) + "-byte message decode to more than " +
           std::to_string(value_budget_) + " values (nested arrays of empty messages?)");
    }
  }

  void align(std::size_t size) {
    if (!cdr_ || size <= 1) return;
    const std::size_t offset = (position_ - origin_) % size;
    if (offset != 0) {
      require(size - offset, "alignment padding");
      position_ += size - offset;
    }
  }

  void require(std::size_t size, const char* what) {
    if (size > bytes_.size() - position_) {
      fail(std::string("expected ") + what + " of " + std::to_string(size) + " bytes, the message ends (" +
           std::to_string(bytes_.size()) + " bytes)");
    }
  }

  [[noreturn]] void fail_count(const Field& field, std::size_t count) {
    fail(field.name + " claims " + std::to_string(count) + " elements, only " + std::to_string(bytes_.size() - position_) +
         " bytes left");
  }

  [[noreturn]] void fail(const std::string& detail) const {
    throw io::ParseError(where_, 0, "message byte " + std::to_string(position_) + ": " + detail);
  }

  const SchemaSet& schemas_;
  std::span<const std::uint8_t> bytes_;
  bool cdr_;
  const std::string& where_;
  bool swap_ = false;
  std::size_t position_ = 0;
  std::size_t origin_ = 0;
  std::shared_ptr<const void> owner_;
  std::size_t values_ = 0;
  std::size_t value_budget_ = 16 * bytes_.size() + 4096;
};

}  // namespace

Value deserialize(const SchemaSet& schemas, std::span<const std::uint8_t> bytes, Serialization serialization,
                  const std::string& where, std::shared_ptr<const void> owner) {
  return Decoder(schemas, bytes, serialization, where, std::move(owner)).run();
}

}  // namespace cairn::bag
