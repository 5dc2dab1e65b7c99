#include "cairn/bag/value.hpp"

#include <stdexcept>
#include <utility>

#include "cairn/bag/message_schema.hpp"

namespace cairn::bag {
namespace {
const char* kind_name(Value::Kind kind) {
  switch (kind) {
    case Value::Kind::kBool: return "bool";
    case Value::Kind::kInt: return "signed integer";
    case Value::Kind::kUInt: return "unsigned integer";
    case Value::Kind::kFloat: return "floating-point number";
    case Value::Kind::kString: return "string";
    case Value::Kind::kBytes: return "byte array";
    case Value::Kind::kArray: return "array";
    case Value::Kind::kMessage: return "message";
  }
  return "value";
}
[[noreturn]] void wrong_kind(Value::Kind found, const char* expected) {
  throw std::runtime_error(std::string("expected a ") + expected + ", found a " + kind_name(found));
}
}  // namespace

Value Value::boolean(bool b) {
  Value v;
  v.kind_ = Kind::kBool;
  v.b_ = b;
  return v;
}
Value Value::integer(std::int64_t i) {
  Value v;
  v.kind_ = Kind::kInt;
  v.i_ = i;
  return v;
}
Value Value::unsigned_integer(std::uint64_t u) {
  Value v;
  v.kind_ = Kind::kUInt;
  v.u_ = u;
  return v;
}
Value Value::floating(double f) {
  Value v;
  v.kind_ = Kind::kFloat;
  v.f_ = f;
  return v;
}
Value Value::string(std::string text) {
  Value v;
  v.kind_ = Kind::kString;
  v.text_ = std::move(text);
  return v;
}
Value Value::bytes(std::string raw) {
  Value v;
  v.kind_ = Kind::kBytes;
  v.text_ = std::move(raw);
  return v;
}
Value Value::bytes_view(std::shared_ptr<const void> owner, std::string_view bytes) {
  Value v;
  v.kind_ = Kind::kBytes;
  v.owner_ = std::move(owner);
  v.view_ = bytes;
  return v;
}

Value Value::array(std::vector<Value> items) {
  Value v;
  v.kind_ = Kind::kArray;
  v.items_ = std::move(items);
  return v;
}
Value Value::message(std::shared_ptr<const MessageSchema> schema, std::vector<Value> fields) {
  Value v;
  v.kind_ = Kind::kMessage;
  v.schema_ = std::move(schema);
  v.items_ = std::move(fields);
  return v;
}

double Value::number() const {
  switch (kind_) {
    case Kind::kBool: return b_ ? 1.0 : 0.0;
    case Kind::kInt: return static_cast<double>(i_);
    case Kind::kUInt: return static_cast<double>(u_);
    case Kind::kFloat: return f_;
    default: wrong_kind(kind_, "number");
  }
}

std::int64_t Value::as_int() const {
  if (kind_ == Kind::kInt) return i_;
  if (kind_ == Kind::kUInt && u_ <= static_cast<std::uint64_t>(INT64_MAX)) return static_cast<std::int64_t>(u_);
  if (kind_ == Kind::kBool) return b_ ? 1 : 0;
  wrong_kind(kind_, "signed integer");
}

std::uint64_t Value::as_uint() const {
  if (kind_ == Kind::kUInt) return u_;
  if (kind_ == Kind::kInt && i_ >= 0) return static_cast<std::uint64_t>(i_);
  if (kind_ == Kind::kBool) return b_ ? 1 : 0;
  wrong_kind(kind_, "unsigned integer");
}

bool Value::as_bool() const {
  if (kind_ == Kind::kBool) return b_;
  if (kind_ == Kind::kUInt) return u_ != 0;
  if (kind_ == Kind::kInt) return i_ != 0;
  wrong_kind(kind_, "bool");
}

std::string_view Value::text() const {
  if (kind_ != Kind::kString && kind_ != Kind::kBytes) wrong_kind(kind_, "string");
  return owner_ ? view_ : std::string_view(text_);
}

const std::vector<Value>& Value::items() const {
  if (kind_ != Kind::kArray && kind_ != Kind::kMessage) wrong_kind(kind_, "array");
  return items_;
}

const Value* Value::find(std::string_view name) const {
  if (kind_ != Kind::kMessage || schema_ == nullptr) return nullptr;
  for (std::size_t i = 0; i < schema_->fields.size() && i < items_.size(); ++i) {
    if (schema_->fields[i].name == name) return &items_[i];
  }
  return nullptr;
}

const Value& Value::operator[](std::string_view name) const {
  if (kind_ != Kind::kMessage) wrong_kind(kind_, "message");
  const Value* field = find(name);
  if (field == nullptr) {
    throw std::runtime_error("message " + (schema_ != nullptr ? schema_->type : std::string("?")) + " has no field '" +
                             std::string(name) + "'");
  }
  return *field;
}

std::vector<double> Value::numbers() const {
  std::vector<double> out;
  if (kind_ == Kind::kBytes) {
    const std::string_view bytes = text();
    out.reserve(bytes.size());
    for (const char c : bytes) out.push_back(static_cast<double>(static_cast<unsigned char>(c)));
    return out;
  }
  if (kind_ != Kind::kArray) wrong_kind(kind_, "array of numbers");
  out.reserve(items_.size());
  for (const Value& item : items_) out.push_back(item.number());
  return out;
}

}  // namespace cairn::bag
