#include "cairn/bag/message_schema.hpp"

#include <charconv>
#include <stdexcept>
#include <utility>

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

/// Built-in type names of a dialect (wiki.ros.org/msg "Built-in types"; design.ros2.org
/// "Interface definition", field types). ROS 1 `byte` is int8 and `char` uint8 (deprecated
/// aliases); ROS 2 `byte` is an octet and `char` an 8-bit unsigned.
bool builtin_primitive(std::string_view name, SchemaSet::Dialect dialect, Primitive* out) {
  static const std::map<std::string_view, Primitive> common = {
      {"bool", Primitive::kBool},       {"int8", Primitive::kInt8},       {"uint8", Primitive::kUInt8},
      {"int16", Primitive::kInt16},     {"uint16", Primitive::kUInt16},   {"int32", Primitive::kInt32},
      {"uint32", Primitive::kUInt32},   {"int64", Primitive::kInt64},     {"uint64", Primitive::kUInt64},
      {"float32", Primitive::kFloat32}, {"float64", Primitive::kFloat64}, {"string", Primitive::kString},
      {"char", Primitive::kUInt8}};
  if (auto it = common.find(name); it != common.end()) {
    *out = it->second;
    return true;
  }
  if (name == "byte") {
    *out = dialect == SchemaSet::Dialect::kRos1 ? Primitive::kInt8 : Primitive::kUInt8;
    return true;
  }
  if (dialect == SchemaSet::Dialect::kRos1 && name == "time") {
    *out = Primitive::kTime;
    return true;
  }
  if (dialect == SchemaSet::Dialect::kRos1 && name == "duration") {
    *out = Primitive::kDuration;
    return true;
  }
  return false;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::string_view package_of(std::string_view type) {
  const auto slash = type.find('/');
  return slash == std::string_view::npos ? std::string_view{} : type.substr(0, slash);
}

/// Types ROS defines without their text appearing in a definition.
const char* implicit_definition(const std::string& type, SchemaSet::Dialect dialect) {
  if (dialect == SchemaSet::Dialect::kRos1 && type == "std_msgs/Header") {
    return "uint32 seq\ntime stamp\nstring frame_id\n";
  }
  if (dialect == SchemaSet::Dialect::kRos2 && type == "builtin_interfaces/Time") return "int32 sec\nuint32 nanosec\n";
  if (dialect == SchemaSet::Dialect::kRos2 && type == "builtin_interfaces/Duration") {
    return "int32 sec\nuint32 nanosec\n";
  }
  if (dialect == SchemaSet::Dialect::kRos2 && type == "std_msgs/Header") {
    return "builtin_interfaces/Time stamp\nstring frame_id\n";
  }
  return nullptr;
}

class DefinitionParser {
 public:
  DefinitionParser(SchemaSet::Dialect dialect, const std::string& where) : dialect_(dialect), where_(where) {}

  /// Splits the text into the top-level section and the "MSG: type" sections, parsing each.
  void parse_text(std::string_view type, std::string_view text, std::size_t first_line) {
    std::string current = normalize_type(type);
    auto* schema = begin_schema(current, first_line);
    std::size_t line_number = first_line;
    while (!text.empty()) {
      const auto end = text.find('\n');
      std::string_view line = text.substr(0, end);
      text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
      ++line_number;
      const std::string_view content = trim(line.substr(0, comment_start(line)));
      if (content.empty()) continue;
      if (content.find_first_not_of('=') == std::string_view::npos && content.size() >= 3) {
        schema = nullptr;  // a separator: the next non-empty line must be "MSG: type"
        continue;
      }
      if (content.starts_with("MSG:")) {
        current = normalize_type(trim(content.substr(4)));
        schema = begin_schema(current, line_number);
        continue;
      }
      if (schema == nullptr) fail(line_number, "expected \"MSG: package/Type\" after a separator line");
      parse_field(content, package_of(current), line_number, schema);
    }
  }

  /// Adds the implicit definitions of every type used but not defined, then checks the rest.
  void resolve(std::map<std::string, std::shared_ptr<MessageSchema>>* out) {
    for (const Repeat& repeat : repeats_) {
      if (!same_fields(*schemas_.at(repeat.type), *repeat.schema)) {
        fail(repeat.line, "type '" + repeat.type + "' is defined twice, differently");
      }
    }
    for (bool added = true; added;) {
      added = false;
      for (const auto& [name, line] : used_) {
        if (schemas_.count(name) != 0) continue;
        const char* text = implicit_definition(name, dialect_);
        if (text == nullptr) fail(line, "type '" + name + "' is used but its definition is not in the bag");
        parse_text(name, text, 0);
        added = true;
        break;
      }
    }
    *out = std::move(schemas_);
  }

 private:
  static std::size_t comment_start(std::string_view line) {
    // A '#' inside a string constant's value is part of it; constants are skipped anyway.
    return line.find('#');
  }

  /// A type defined a second time (rosbag2 repeats a dependency that several fields use) is parsed
  /// into a scratch schema and must equal the first definition.
  MessageSchema* begin_schema(const std::string& type, std::size_t line) {
    if (schemas_.count(type) != 0) {
      repeats_.push_back({type, line, std::make_shared<MessageSchema>()});
      repeats_.back().schema->type = type;
      return repeats_.back().schema.get();
    }
    auto schema = std::make_shared<MessageSchema>();
    schema->type = type;
    schemas_[type] = schema;
    return schema.get();
  }

  void parse_field(std::string_view content, std::string_view package, std::size_t line, MessageSchema* schema) {
    const auto space = content.find_first_of(" \t");
    if (space == std::string_view::npos) fail(line, "expected 'type name', found '" + std::string(content) + "'");
    std::string_view type_text = content.substr(0, space);
    std::string_view rest = trim(content.substr(space));
    const auto name_end = rest.find_first_of(" \t=");
    const std::string_view name = rest.substr(0, name_end);
    if (name.empty()) fail(line, "expected a field name after '" + std::string(type_text) + "'");
    const std::string_view after = name_end == std::string_view::npos ? std::string_view{} : trim(rest.substr(name_end));
    if (after.starts_with("=")) return;  // a constant: not serialised
    Field field;
    field.name = std::string(name);
    parse_array_suffix(&type_text, &field, line);
    parse_element_type(type_text, package, line, &field);
    schema->fields.push_back(std::move(field));
  }

  void parse_array_suffix(std::string_view* type_text, Field* field, std::size_t line) {
    const auto bracket = type_text->find('[');
    if (bracket == std::string_view::npos) return;
    if (!type_text->ends_with("]")) fail(line, "expected ']' closing the array type '" + std::string(*type_text) + "'");
    std::string_view inside = type_text->substr(bracket + 1, type_text->size() - bracket - 2);
    *type_text = type_text->substr(0, bracket);
    if (inside.empty()) {
      field->array = Field::Array::kSequence;
      return;
    }
    const bool bounded = inside.starts_with("<=");
    if (bounded) inside.remove_prefix(2);
    std::size_t size = 0;
    const auto [end, error] = std::from_chars(inside.data(), inside.data() + inside.size(), size);
    if (error != std::errc{} || end != inside.data() + inside.size() || (!bounded && size == 0)) {
      fail(line, "expected an array size in '[" + std::string(inside) + "]'");
    }
    field->array = bounded ? Field::Array::kSequence : Field::Array::kFixed;
    field->array_size = size;
  }

  void parse_element_type(std::string_view type_text, std::string_view package, std::size_t line, Field* field) {
    if (type_text.starts_with("string<=")) type_text = "string";  // bounded string: same wire format
    if (type_text == "wstring" || type_text.starts_with("wstring<=")) {
      fail(line, "wstring fields are not supported (no sensor message uses them)");
    }
    if (builtin_primitive(type_text, dialect_, &field->primitive)) return;
    field->primitive = Primitive::kMessage;
    if (type_text == "Header") {
      field->message_type = "std_msgs/Header";
    } else if (type_text.find('/') == std::string_view::npos) {
      if (package.empty()) fail(line, "type '" + std::string(type_text) + "' has no package and its message none");
      field->message_type = std::string(package) + "/" + std::string(type_text);
    } else {
      field->message_type = normalize_type(type_text);
    }
    used_.emplace(field->message_type, line);
  }

  [[noreturn]] void fail(std::size_t line, const std::string& detail) const {
    throw io::ParseError(where_, 0, "message definition line " + std::to_string(line) + ": " + detail);
  }

  static bool same_fields(const MessageSchema& a, const MessageSchema& b) {
    if (a.fields.size() != b.fields.size()) return false;
    for (std::size_t i = 0; i < a.fields.size(); ++i) {
      const Field& x = a.fields[i];
      const Field& y = b.fields[i];
      if (x.name != y.name || x.primitive != y.primitive || x.message_type != y.message_type || x.array != y.array ||
          x.array_size != y.array_size) {
        return false;
      }
    }
    return true;
  }

  struct Repeat {
    std::string type;
    std::size_t line = 0;
    std::shared_ptr<MessageSchema> schema;
  };
  std::vector<Repeat> repeats_;

  SchemaSet::Dialect dialect_;
  const std::string& where_;
  std::map<std::string, std::shared_ptr<MessageSchema>> schemas_;
  std::map<std::string, std::size_t> used_;
};

}  // namespace

std::size_t primitive_size(Primitive primitive) {
  switch (primitive) {
    case Primitive::kBool:
    case Primitive::kInt8:
    case Primitive::kUInt8:
      return 1;
    case Primitive::kInt16:
    case Primitive::kUInt16:
      return 2;
    case Primitive::kInt32:
    case Primitive::kUInt32:
    case Primitive::kFloat32:
      return 4;
    case Primitive::kInt64:
    case Primitive::kUInt64:
    case Primitive::kFloat64:
    case Primitive::kTime:
    case Primitive::kDuration:
      return 8;
    case Primitive::kString:
    case Primitive::kMessage:
      return 0;
  }
  return 0;
}

std::string normalize_type(std::string_view type) {
  std::string out(type);
  if (const auto infix = out.find("/msg/"); infix != std::string::npos) out.erase(infix, 4);
  return out;
}

SchemaSet SchemaSet::parse(std::string_view type, std::string_view definition, Dialect dialect,
                           const std::string& where) {
  if (type.empty()) throw io::ParseError(where, 0, "the connection names no message type");
  DefinitionParser parser(dialect, where);
  parser.parse_text(type, definition, 0);
  SchemaSet set;
  set.dialect_ = dialect;
  parser.resolve(&set.schemas_);
  set.root_ = set.schemas_.at(normalize_type(type));
  return set;
}

std::shared_ptr<const MessageSchema> SchemaSet::shared(const std::string& type) const {
  auto it = schemas_.find(type);
  if (it == schemas_.end()) throw std::out_of_range("no schema for " + type);
  return it->second;
}

const MessageSchema& SchemaSet::at(const std::string& type) const {
  auto it = schemas_.find(type);
  if (it == schemas_.end()) throw std::out_of_range("no schema for " + type);
  return *it->second;
}

}  // namespace cairn::bag
