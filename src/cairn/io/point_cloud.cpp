#include "cairn/io/point_cloud.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <ostream>
#include <string_view>

#include "cairn/core/assert.hpp"
#include "cairn/io/compressed_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

// Binary PCD, PLY binary_little_endian and KITTI .bin are little endian; values are copied
// byte for byte into native variables.
static_assert(std::endian::native == std::endian::little,
              "the point-cloud readers assume a little-endian host (PCD binary, PLY "
              "binary_little_endian and KITTI .bin store little-endian values)");

// ---------------------------------------------------------------------------------------------
// Shared pieces: scalar types, the attribute a field feeds, and the cloud under construction.

/// A scalar as stored in a file: 'F' float, 'U' unsigned or 'I' signed integer, of `size` bytes.
struct ScalarType {
  char kind = 'F';
  std::size_t size = 4;
};

double read_scalar(const char* p, ScalarType type) {
  switch (type.kind) {
    case 'F':
      if (type.size == 4) {
        float v = 0.0F;
        std::memcpy(&v, p, 4);
        return static_cast<double>(v);
      } else {
        double v = 0.0;
        std::memcpy(&v, p, 8);
        return v;
      }
    case 'U':
      if (type.size == 1) return static_cast<double>(static_cast<unsigned char>(*p));
      if (type.size == 2) {
        std::uint16_t v = 0;
        std::memcpy(&v, p, 2);
        return static_cast<double>(v);
      } else {
        std::uint32_t v = 0;
        std::memcpy(&v, p, 4);
        return static_cast<double>(v);
      }
    default:
      if (type.size == 1) return static_cast<double>(static_cast<signed char>(*p));
      if (type.size == 2) {
        std::int16_t v = 0;
        std::memcpy(&v, p, 2);
        return static_cast<double>(v);
      } else {
        std::int32_t v = 0;
        std::memcpy(&v, p, 4);
        return static_cast<double>(v);
      }
  }
}

/// The attribute of PointCloud a field of the file fills.
enum class Role { kX, kY, kZ, kIntensity, kRing, kTime, kSkip };
constexpr std::size_t kRoles = 6;  // every role but kSkip

const char* role_name(Role role) {
  switch (role) {
    case Role::kX:
      return "x";
    case Role::kY:
      return "y";
    case Role::kZ:
      return "z";
    case Role::kIntensity:
      return "intensity";
    case Role::kRing:
      return "ring";
    case Role::kTime:
      return "time";
    case Role::kSkip:
      break;
  }
  return "skipped";
}

/// Field names and the attribute they feed: PCL and the Velodyne/Ouster drivers write
/// `intensity`, `ring`, `time` (seconds) or `t` (Ouster: uint32 nanoseconds); CloudCompare
/// prefixes scalar fields with `scalar_`.
Role role_of(std::string_view name) {
  if (name == "x") return Role::kX;
  if (name == "y") return Role::kY;
  if (name == "z") return Role::kZ;
  if (name == "intensity" || name == "i" || name == "scalar_intensity") return Role::kIntensity;
  if (name == "ring") return Role::kRing;
  if (name == "time" || name == "t") return Role::kTime;
  return Role::kSkip;
}

std::string printable(std::string_view bytes, std::size_t max = 24) {
  std::string out = "'";
  for (std::size_t i = 0; i < bytes.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(bytes[i]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buffer[8];
      std::snprintf(buffer, sizeof buffer, "\\x%02x", c);
      out += buffer;
    }
  }
  if (bytes.size() > max) out += "...";
  return out + "'";
}

std::string number_text(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.9g", value);
  return buffer;
}

/// Collects the points, dropping those with a non-finite coordinate.
class CloudBuilder {
 public:
  /// `present[r]` tells whether the file has the attribute of role r; `time_scale` converts the
  /// file's time unit to seconds.
  CloudBuilder(const std::array<bool, kRoles>& present, double time_scale, std::size_t expected_points)
      : present_(present), time_scale_(time_scale) {
    cloud_.points.reserve(expected_points);
    if (present_[static_cast<std::size_t>(Role::kIntensity)]) cloud_.intensity.reserve(expected_points);
    if (present_[static_cast<std::size_t>(Role::kTime)]) cloud_.time_s.reserve(expected_points);
    if (present_[static_cast<std::size_t>(Role::kRing)]) cloud_.ring.reserve(expected_points);
  }

  /// Adds one point from its values (indexed by Role). Returns an empty string, or what is wrong
  /// with an attribute of a point whose coordinates are finite.
  std::string add(const std::array<double, kRoles>& v) {
    const double x = v[static_cast<std::size_t>(Role::kX)];
    const double y = v[static_cast<std::size_t>(Role::kY)];
    const double z = v[static_cast<std::size_t>(Role::kZ)];
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) {
      ++dropped_;
      return {};
    }
    // A coordinate that overflows float (an F8 field beyond 3.4e38 m) is not a LiDAR point.
    constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());
    if (std::abs(x) > kFloatMax || std::abs(y) > kFloatMax || std::abs(z) > kFloatMax) {
      return "a coordinate beyond the float range: expected metres";
    }
    float intensity = 0.0F;
    float time_s = 0.0F;
    std::uint16_t ring = 0;
    if (present_[static_cast<std::size_t>(Role::kIntensity)]) {
      const double value = v[static_cast<std::size_t>(Role::kIntensity)];
      if (!std::isfinite(value) || std::abs(value) > kFloatMax) {
        return "intensity " + number_text(value) + " of a valid point: expected a finite number";
      }
      intensity = static_cast<float>(value);
    }
    if (present_[static_cast<std::size_t>(Role::kTime)]) {
      const double value = v[static_cast<std::size_t>(Role::kTime)] * time_scale_;
      if (!std::isfinite(value) || std::abs(value) > kFloatMax) {
        return "time " + number_text(value) + " s of a valid point: expected a finite number";
      }
      time_s = static_cast<float>(value);
    }
    if (present_[static_cast<std::size_t>(Role::kRing)]) {
      const double value = v[static_cast<std::size_t>(Role::kRing)];
      if (!(value >= 0.0 && value <= 65535.0 && value == std::floor(value))) {
        return "ring " + number_text(value) + ": expected an integer in 0..65535";
      }
      ring = static_cast<std::uint16_t>(value);
    }
    cloud_.points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    if (present_[static_cast<std::size_t>(Role::kIntensity)]) cloud_.intensity.push_back(intensity);
    if (present_[static_cast<std::size_t>(Role::kTime)]) cloud_.time_s.push_back(time_s);
    if (present_[static_cast<std::size_t>(Role::kRing)]) cloud_.ring.push_back(ring);
    return {};
  }

  PointCloud finish(PointCloudReadReport& report) {
    report.dropped_non_finite = dropped_;
    return std::move(cloud_);
  }

 private:
  std::array<bool, kRoles> present_;
  double time_scale_;
  PointCloud cloud_;
  std::size_t dropped_ = 0;
};

/// A number of an ASCII record; NaN and inf are accepted (as PCL writes them) and dealt with by
/// CloudBuilder.
std::optional<double> parse_number(std::string_view token) {
  const char* begin = token.data();
  const char* end = begin + token.size();
  if (begin != end && *begin == '+') ++begin;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (begin == end || ptr != end) return std::nullopt;
  // from_chars reports overflow (1e999) as out of range: it is an infinity here.
  if (ec == std::errc::result_out_of_range) return token[0] == '-' ? -HUGE_VAL : HUGE_VAL;
  if (ec != std::errc()) return std::nullopt;
  return value;
}

std::optional<std::uint64_t> parse_unsigned(std::string_view token) {
  std::uint64_t value = 0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || ptr != token.data() + token.size()) return std::nullopt;
  return value;
}

/// Lines of a header held in memory, with binary bytes refused.
class HeaderLines {
 public:
  HeaderLines(const std::string& path, const std::string& contents, const char* format)
      : path_(path), contents_(contents), format_(format) {}

  /// The next line without its '\n' or '\r'; nullopt at the end of the contents.
  std::optional<std::string_view> next() {
    if (position_ >= contents_.size()) return std::nullopt;
    const std::size_t end = contents_.find('\n', position_);
    const std::size_t stop = end == std::string::npos ? contents_.size() : end;
    std::string_view line(contents_.data() + position_, stop - position_);
    ++line_;
    for (const char ch : line) {
      const auto c = static_cast<unsigned char>(ch);
      if ((c < 0x20 && c != '\t' && c != '\r') || c >= 0x7f) {
        char hex[8];
        std::snprintf(hex, sizeof hex, "%02x", c);
        fail(std::string("binary data (byte 0x") + hex + ") in the " + section_ + ": expected " + format_ + " " +
             section_ + " text (truncated or corrupt file?)");
      }
    }
    position_ = end == std::string::npos ? contents_.size() : end + 1;
    while (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    return line;
  }

  /// Names the part being read in errors about binary bytes ("header", "ASCII data").
  void set_section(const char* section) { section_ = section; }
  std::size_t line_number() const { return line_; }
  /// Offset of the byte after the last line returned.
  std::size_t offset() const { return position_; }
  [[noreturn]] void fail(const std::string& detail) const { throw ParseError(path_, line_, detail); }
  [[noreturn]] void fail_at(std::size_t line, const std::string& detail) const {
    throw ParseError(path_, line, detail);
  }

 private:
  const std::string& path_;
  const std::string& contents_;
  const char* format_;
  const char* section_ = "header";
  std::size_t position_ = 0;
  std::size_t line_ = 0;
};

/// A field of a record: where its values are and which attribute it fills.
struct Field {
  std::string name;
  ScalarType type;
  std::size_t count = 1;
  Role role = Role::kSkip;
};

/// Roles present among `fields`; error text when a role appears twice or x/y/z is missing.
std::string check_roles(const std::vector<Field>& fields, std::array<bool, kRoles>& present) {
  present.fill(false);
  std::array<std::string, kRoles> first;
  for (const Field& field : fields) {
    if (field.role == Role::kSkip) continue;
    const auto r = static_cast<std::size_t>(field.role);
    if (present[r]) {
      return "fields '" + first[r] + "' and '" + field.name + "' both give the " + role_name(field.role) +
             ": expected one";
    }
    present[r] = true;
    first[r] = field.name;
  }
  for (const Role r : {Role::kX, Role::kY, Role::kZ}) {
    if (!present[static_cast<std::size_t>(r)]) {
      std::string names;
      for (const Field& field : fields) names += (names.empty() ? "" : " ") + field.name;
      return std::string("no field '") + role_name(r) + "': expected fields x, y and z, found '" + names + "'";
    }
  }
  return {};
}

/// Seconds per unit of the time field: Ouster's `t` is an unsigned integer in nanoseconds;
/// `time` (Velodyne) and a floating-point `t` are seconds.
double time_scale_of(const std::vector<Field>& fields) {
  for (const Field& field : fields) {
    if (field.role == Role::kTime && field.name == "t" && field.type.kind != 'F') return 1e-9;
  }
  return 1.0;
}

// ---------------------------------------------------------------------------------------------
// LZF, as PCL's binary_compressed stores it (liblzf 3.6, lzf_d.c, by Marc Lehmann). A stream is
// a sequence of
//   000LLLLL <L+1 literal bytes>                       literal run of 1..32 bytes
//   LLLooooo oooooooo                                  back reference, length L+2 (L = 1..6)
//   111ooooo LLLLLLLL oooooooo                         back reference, length L+9
// copying from `o + 1` bytes before the output position (the copy may overlap its source).

/// Decompresses `in` into exactly `out.size()` bytes. Returns an empty string or what is wrong,
/// with the offset in the compressed data.
std::string lzf_decompress(const unsigned char* in, std::size_t in_size, std::vector<unsigned char>& out) {
  std::size_t ip = 0;
  std::size_t op = 0;
  const std::size_t out_size = out.size();
  while (ip < in_size) {
    const std::size_t control_at = ip;
    const unsigned control = in[ip++];
    if (control < 32) {
      const std::size_t length = control + 1;
      if (length > in_size - ip) {
        return "LZF literal run of " + std::to_string(length) + " bytes at compressed byte " +
               std::to_string(control_at) + " runs past the end of the compressed data";
      }
      if (length > out_size - op) {
        return "LZF data at compressed byte " + std::to_string(control_at) + " writes past the " +
               std::to_string(out_size) + " bytes the header announces";
      }
      std::memcpy(out.data() + op, in + ip, length);
      ip += length;
      op += length;
    } else {
      std::size_t length = control >> 5;
      if (length == 7) {
        if (ip >= in_size) return "LZF back reference at compressed byte " + std::to_string(control_at) + " is cut off";
        length += in[ip++];
      }
      if (ip >= in_size) return "LZF back reference at compressed byte " + std::to_string(control_at) + " is cut off";
      const std::size_t distance = ((static_cast<std::size_t>(control & 0x1f) << 8) | in[ip++]) + 1;
      length += 2;
      if (distance > op) {
        return "LZF back reference at compressed byte " + std::to_string(control_at) + " points " +
               std::to_string(distance) + " bytes back, before the start of the data (at output byte " +
               std::to_string(op) + ")";
      }
      if (length > out_size - op) {
        return "LZF data at compressed byte " + std::to_string(control_at) + " writes past the " +
               std::to_string(out_size) + " bytes the header announces";
      }
      for (std::size_t k = 0; k < length; ++k, ++op) out[op] = out[op - distance];  // may overlap
    }
  }
  if (op != out_size) {
    return "LZF data decompresses to " + std::to_string(op) + " bytes, expected " + std::to_string(out_size);
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// PCD v0.7 (pointclouds.org/documentation/tutorials/pcd_file_format.html).

constexpr std::size_t kMaxFieldCount = std::size_t{1} << 24;

struct PcdHeader {
  std::vector<Field> fields;
  std::uint64_t points = 0;
  std::string data;
  std::size_t data_line = 0;
  std::size_t fields_line = 0;
  std::size_t data_offset = 0;
};

PcdHeader read_pcd_header(HeaderLines& lines) {
  struct Seen {
    std::size_t line = 0;
    std::vector<std::string_view> values;
  };
  static constexpr std::array<std::string_view, 10> kKeys = {"VERSION", "FIELDS", "SIZE",      "TYPE",   "COUNT",
                                                             "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
  std::array<Seen, kKeys.size()> seen;
  const auto index_of = [&](std::string_view key) -> std::size_t {
    return static_cast<std::size_t>(std::find(kKeys.begin(), kKeys.end(), key) - kKeys.begin());
  };
  PcdHeader header;
  while (true) {
    const std::optional<std::string_view> line = lines.next();
    if (!line) {
      lines.fail("file ends inside the PCD header: expected a 'DATA ascii|binary|binary_compressed' line");
    }
    const std::vector<std::string_view> tokens = split_whitespace(*line);
    if (tokens.empty() || tokens[0][0] == '#') continue;
    const std::size_t k = index_of(tokens[0]);
    if (k == kKeys.size()) {
      lines.fail("unknown PCD header keyword " + quote_token(tokens[0]) +
                 ": expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS or DATA");
    }
    if (seen[k].line != 0) {
      lines.fail("second " + std::string(kKeys[k]) + " line (the first is line " + std::to_string(seen[k].line) +
                 "): expected one");
    }
    if (tokens.size() < 2) lines.fail(std::string(kKeys[k]) + " without a value");
    seen[k].line = lines.line_number();
    seen[k].values.assign(tokens.begin() + 1, tokens.end());
    if (kKeys[k] == "DATA") break;
  }
  header.data_offset = lines.offset();
  header.data_line = lines.line_number();
  const Seen& data = seen[index_of("DATA")];

  const auto require = [&](std::string_view key) -> const Seen& {
    const Seen& s = seen[index_of(key)];
    if (s.line == 0) lines.fail("no " + std::string(key) + " line before DATA: expected a PCD v0.7 header");
    return s;
  };
  const auto single = [&](const Seen& s, std::string_view key) -> std::string_view {
    if (s.values.size() != 1) {
      lines.fail_at(s.line, std::string(key) + " expects one value, found " + std::to_string(s.values.size()));
    }
    return s.values[0];
  };
  const auto unsigned_value = [&](std::string_view key) -> std::uint64_t {
    const Seen& s = require(key);
    const std::string_view token = single(s, key);
    const auto value = parse_unsigned(token);
    if (!value)
      lines.fail_at(s.line,
                    "expected a non-negative integer for " + std::string(key) + ", found " + quote_token(token));
    return *value;
  };

  const Seen& version = require("VERSION");
  const std::string_view v = single(version, "VERSION");
  if (v != "0.7" && v != ".7") {
    lines.fail_at(version.line, "PCD version " + quote_token(v) + " is not supported: expected 0.7");
  }

  const Seen& fields = require("FIELDS");
  const Seen& sizes = require("SIZE");
  const Seen& types = require("TYPE");
  const Seen& counts = seen[index_of("COUNT")];
  header.fields_line = fields.line;
  const std::size_t n = fields.values.size();
  const auto check_length = [&](const Seen& s, std::string_view key) {
    if (s.values.size() != n) {
      lines.fail_at(s.line, std::string(key) + " has " + std::to_string(s.values.size()) + " values, FIELDS (line " +
                                std::to_string(fields.line) + ") names " + std::to_string(n) +
                                ": expected one per field");
    }
  };
  check_length(sizes, "SIZE");
  check_length(types, "TYPE");
  if (counts.line != 0) check_length(counts, "COUNT");
  for (std::size_t i = 0; i < n; ++i) {
    Field field;
    field.name = std::string(fields.values[i]);
    for (std::size_t j = 0; j < i; ++j) {
      if (header.fields[j].name == field.name)
        lines.fail_at(fields.line, "field " + quote_token(field.name) + " appears twice");
    }
    const auto size = parse_unsigned(sizes.values[i]);
    const std::string_view type = types.values[i];
    if (!size || type.size() != 1 ||
        !((type[0] == 'F' && (*size == 4 || *size == 8)) ||
          ((type[0] == 'U' || type[0] == 'I') && (*size == 1 || *size == 2 || *size == 4)))) {
      lines.fail_at(types.line, "field " + quote_token(field.name) + " has TYPE " + quote_token(type) + " and SIZE " +
                                    quote_token(sizes.values[i]) + ": expected F4, F8, U1, U2, U4, I1, I2 or I4");
    }
    field.type = ScalarType{type[0], static_cast<std::size_t>(*size)};
    if (counts.line != 0) {
      const auto count = parse_unsigned(counts.values[i]);
      if (!count || *count == 0 || *count > kMaxFieldCount) {
        lines.fail_at(counts.line, "field " + quote_token(field.name) + " has COUNT " + quote_token(counts.values[i]) +
                                       ": expected an integer in 1.." + std::to_string(kMaxFieldCount));
      }
      field.count = static_cast<std::size_t>(*count);
    }
    field.role = role_of(field.name);
    if (field.role != Role::kSkip && field.count != 1) {
      lines.fail_at(counts.line, "field " + quote_token(field.name) + " has COUNT " + std::to_string(field.count) +
                                     ": expected 1 (one value per point)");
    }
    if (field.role == Role::kRing && field.type.kind == 'F') {
      lines.fail_at(types.line, "field 'ring' has TYPE F: expected an integer type (U or I)");
    }
    header.fields.push_back(std::move(field));
  }

  const std::uint64_t width = unsigned_value("WIDTH");
  const std::uint64_t height = unsigned_value("HEIGHT");
  header.points = unsigned_value("POINTS");
  const bool product_matches =
      width == 0 ? header.points == 0 : header.points % width == 0 && header.points / width == height;
  if (!product_matches) {
    lines.fail_at(seen[index_of("POINTS")].line, "POINTS " + std::to_string(header.points) +
                                                     " differs from WIDTH * HEIGHT = " + std::to_string(width) + " * " +
                                                     std::to_string(height));
  }
  if (const Seen& viewpoint = seen[index_of("VIEWPOINT")]; viewpoint.line != 0) {
    if (viewpoint.values.size() != 7) {
      lines.fail_at(viewpoint.line, "VIEWPOINT expects 7 numbers (tx ty tz qw qx qy qz), found " +
                                        std::to_string(viewpoint.values.size()));
    }
    for (const std::string_view token : viewpoint.values) {
      const auto value = parse_number(token);
      if (!value || !std::isfinite(*value)) {
        lines.fail_at(viewpoint.line, "expected a finite number in VIEWPOINT, found " + quote_token(token));
      }
    }
  }
  header.data = std::string(single(data, "DATA"));
  if (header.data != "ascii" && header.data != "binary" && header.data != "binary_compressed") {
    lines.fail_at(data.line, "DATA " + quote_token(header.data) + ": expected ascii, binary or binary_compressed");
  }
  return header;
}

/// Reads the records of binary data: value j of point i of field f is at
/// `data + start[f] + i * stride[f]` (records one after another, or columns one after another).
void read_records(const std::string& path, const unsigned char* data, std::size_t points,
                  const std::vector<Field>& fields, const std::vector<std::size_t>& start,
                  const std::vector<std::size_t>& stride, const std::string& where, std::size_t base_offset,
                  CloudBuilder& builder) {
  std::array<double, kRoles> values{};
  for (std::size_t i = 0; i < points; ++i) {
    for (std::size_t f = 0; f < fields.size(); ++f) {
      if (fields[f].role == Role::kSkip) continue;
      values[static_cast<std::size_t>(fields[f].role)] =
          read_scalar(reinterpret_cast<const char*>(data + start[f] + i * stride[f]), fields[f].type);
    }
    const std::string problem = builder.add(values);
    if (!problem.empty()) {
      throw ParseError(path, 0,
                       "point " + std::to_string(i) + " (" + where + " " +
                           std::to_string(base_offset + start[0] + i * stride[0]) + "): " + problem);
    }
  }
}

PointCloud parse_pcd(const std::string& path, const std::string& contents, PointCloudReadReport& report) {
  HeaderLines lines(path, contents, "PCD");
  const PcdHeader header = read_pcd_header(lines);
  std::array<bool, kRoles> present{};
  if (const std::string problem = check_roles(header.fields, present); !problem.empty()) {
    lines.fail_at(header.fields_line, problem);
  }
  report.format = "pcd " + header.data;
  const std::vector<Field>& fields = header.fields;
  const std::size_t available = contents.size() - header.data_offset;
  std::size_t values_per_point = 0;
  std::size_t point_size = 0;
  std::vector<std::size_t> offset;  // of each field within a record
  for (const Field& field : fields) {
    offset.push_back(point_size);
    values_per_point += field.count;
    point_size += field.type.size * field.count;
  }
  const std::string announced =
      "the header announces " + std::to_string(header.points) + " points of " + std::to_string(point_size) + " bytes";

  if (header.data == "ascii") {
    // Each value takes at least one character and one separator.
    if (header.points > (available + 1) / (2 * values_per_point)) {
      lines.fail_at(header.data_line, announced + " (" + std::to_string(values_per_point) +
                                          " values each), more than the " + std::to_string(available) +
                                          " bytes after the DATA line can hold (truncated file?)");
    }
    CloudBuilder builder(present, time_scale_of(fields), static_cast<std::size_t>(header.points));
    std::array<double, kRoles> values{};
    std::uint64_t read = 0;
    lines.set_section("ASCII data");
    while (const std::optional<std::string_view> line = lines.next()) {
      const std::vector<std::string_view> tokens = split_whitespace(*line);
      if (tokens.empty()) continue;
      if (read == header.points) {
        lines.fail("unexpected data after the " + std::to_string(header.points) +
                   " points the header announces: " + quote_token(*line));
      }
      if (tokens.size() != values_per_point) {
        lines.fail("point " + std::to_string(read) + " has " + std::to_string(tokens.size()) + " values: expected " +
                   std::to_string(values_per_point) + " (one per FIELDS entry and COUNT)");
      }
      std::size_t t = 0;
      for (const Field& field : fields) {
        for (std::size_t c = 0; c < field.count; ++c, ++t) {
          const auto value = parse_number(tokens[t]);
          if (!value) {
            lines.fail("expected a number for field " + quote_token(field.name) + " of point " + std::to_string(read) +
                       ", found " + quote_token(tokens[t]));
          }
          if (field.role != Role::kSkip) values[static_cast<std::size_t>(field.role)] = *value;
        }
      }
      if (const std::string problem = builder.add(values); !problem.empty()) {
        lines.fail("point " + std::to_string(read) + ": " + problem);
      }
      ++read;
    }
    if (read != header.points) {
      throw ParseError(path, lines.line_number(),
                       "file ends after " + std::to_string(read) + " of the " + std::to_string(header.points) +
                           " points the header announces (truncated file?)");
    }
    return builder.finish(report);
  }

  const auto* bytes = reinterpret_cast<const unsigned char*>(contents.data()) + header.data_offset;
  const auto points = static_cast<std::size_t>(header.points);
  if (header.data == "binary") {
    if (header.points > available / point_size) {
      throw ParseError(path, 0,
                       "truncated binary data: " + announced + ", but only " + std::to_string(available) +
                           " bytes follow the DATA line (from byte offset " + std::to_string(header.data_offset) + ")");
    }
    report.trailing_bytes = available - points * point_size;
    std::vector<std::size_t> stride(fields.size(), point_size);
    CloudBuilder builder(present, time_scale_of(fields), points);
    read_records(path, bytes, points, fields, offset, stride, "byte offset", header.data_offset, builder);
    return builder.finish(report);
  }

  // binary_compressed: uint32 compressed size, uint32 uncompressed size, LZF data holding the
  // fields column by column (all x, then all y, ...), as PCL's PCDWriter::writeBinaryCompressed.
  if (available < 8) {
    throw ParseError(path, 0,
                     "truncated binary_compressed data: expected 8 bytes of sizes at byte offset " +
                         std::to_string(header.data_offset) + ", found " + std::to_string(available));
  }
  std::uint32_t compressed_size = 0;
  std::uint32_t uncompressed_size = 0;
  std::memcpy(&compressed_size, bytes, 4);
  std::memcpy(&uncompressed_size, bytes + 4, 4);
  if (compressed_size > available - 8) {
    throw ParseError(path, 0,
                     "truncated binary_compressed data: the block at byte offset " +
                         std::to_string(header.data_offset) + " announces " + std::to_string(compressed_size) +
                         " compressed bytes, only " + std::to_string(available - 8) + " follow");
  }
  if (header.points > uncompressed_size / point_size || points * point_size != uncompressed_size) {
    throw ParseError(path, 0,
                     "binary_compressed block at byte offset " + std::to_string(header.data_offset) + " holds " +
                         std::to_string(uncompressed_size) + " bytes uncompressed, but " + announced);
  }
  // An LZF back reference of 3 bytes yields at most 264 bytes: refuse sizes the data cannot
  // reach before allocating them.
  if (static_cast<std::uint64_t>(uncompressed_size) > 88 * static_cast<std::uint64_t>(compressed_size)) {
    throw ParseError(path, 0,
                     "binary_compressed block at byte offset " + std::to_string(header.data_offset) + " announces " +
                         std::to_string(uncompressed_size) + " bytes from " + std::to_string(compressed_size) +
                         " compressed bytes: LZF cannot expand more than 88 times (corrupt file?)");
  }
  report.trailing_bytes = available - 8 - compressed_size;
  std::vector<unsigned char> decompressed(uncompressed_size);
  if (const std::string problem = lzf_decompress(bytes + 8, compressed_size, decompressed); !problem.empty()) {
    throw ParseError(
        path, 0,
        "corrupt binary_compressed data (block at byte offset " + std::to_string(header.data_offset) + "): " + problem);
  }
  std::vector<std::size_t> start;
  std::vector<std::size_t> stride;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    start.push_back(offset[f] * points);
    stride.push_back(fields[f].type.size * fields[f].count);
  }
  CloudBuilder builder(present, time_scale_of(fields), points);
  read_records(path, decompressed.data(), points, fields, start, stride, "decompressed byte", 0, builder);
  return builder.finish(report);
}

// ---------------------------------------------------------------------------------------------
// PLY (Turk 1994; paulbourke.net/dataformats/ply/).

struct PlyProperty {
  std::string name;
  ScalarType type;
  bool is_list = false;
  ScalarType count_type;  ///< for lists
  Role role = Role::kSkip;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::size_t line = 0;
  std::vector<PlyProperty> properties;
};

std::optional<ScalarType> ply_type(std::string_view name) {
  if (name == "char" || name == "int8") return ScalarType{'I', 1};
  if (name == "uchar" || name == "uint8") return ScalarType{'U', 1};
  if (name == "short" || name == "int16") return ScalarType{'I', 2};
  if (name == "ushort" || name == "uint16") return ScalarType{'U', 2};
  if (name == "int" || name == "int32") return ScalarType{'I', 4};
  if (name == "uint" || name == "uint32") return ScalarType{'U', 4};
  if (name == "float" || name == "float32") return ScalarType{'F', 4};
  if (name == "double" || name == "float64") return ScalarType{'F', 8};
  return std::nullopt;
}

PointCloud parse_ply(const std::string& path, const std::string& contents, PointCloudReadReport& report) {
  HeaderLines lines(path, contents, "PLY");
  lines.next();  // "ply", checked by the caller
  std::string format;
  std::vector<PlyElement> elements;
  while (true) {
    const std::optional<std::string_view> line = lines.next();
    if (!line) lines.fail("file ends inside the PLY header: expected 'end_header'");
    const std::vector<std::string_view> tokens = split_whitespace(*line);
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") {
      if (tokens.size() != 1) lines.fail("unexpected text after end_header: " + quote_token(*line));
      break;
    }
    if (key == "format") {
      if (!format.empty()) lines.fail("second format line: expected one");
      if (tokens.size() != 3 || tokens[2] != "1.0") {
        lines.fail("expected 'format ascii|binary_little_endian 1.0', found " + quote_token(*line));
      }
      if (tokens[1] == "binary_big_endian") {
        lines.fail("format binary_big_endian is not supported: convert the file to binary_little_endian or ascii");
      }
      if (tokens[1] != "ascii" && tokens[1] != "binary_little_endian") {
        lines.fail("unknown PLY format " + quote_token(tokens[1]) + ": expected ascii or binary_little_endian");
      }
      format = std::string(tokens[1]);
    } else if (key == "element") {
      if (tokens.size() != 3) lines.fail("expected 'element <name> <count>', found " + quote_token(*line));
      const auto count = parse_unsigned(tokens[2]);
      if (!count)
        lines.fail("expected a non-negative integer count for element " + quote_token(tokens[1]) + ", found " +
                   quote_token(tokens[2]));
      for (const PlyElement& e : elements) {
        if (e.name == tokens[1])
          lines.fail("element " + quote_token(tokens[1]) + " is declared twice (first on line " +
                     std::to_string(e.line) + ")");
      }
      elements.push_back(PlyElement{std::string(tokens[1]), *count, lines.line_number(), {}});
    } else if (key == "property") {
      if (elements.empty()) lines.fail("property before any element: expected 'element <name> <count>' first");
      PlyElement& element = elements.back();
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        const auto count_type = ply_type(tokens[2]);
        const auto item_type = ply_type(tokens[3]);
        if (!count_type || count_type->kind == 'F' || !item_type) {
          lines.fail("expected 'property list <integer type> <type> <name>', found " + quote_token(*line));
        }
        if (element.name == "vertex") {
          lines.fail("list property " + quote_token(tokens[4]) +
                     " in element vertex is not supported: expected scalar vertex properties");
        }
        property = PlyProperty{std::string(tokens[4]), *item_type, true, *count_type, Role::kSkip};
      } else if (tokens.size() == 3 && tokens[1] != "list") {
        const auto type = ply_type(tokens[1]);
        if (!type) {
          lines.fail("unknown property type " + quote_token(tokens[1]) +
                     ": expected char, uchar, short, ushort, int, uint, float, double (or int8 .. float64)");
        }
        property.name = std::string(tokens[2]);
        property.type = *type;
        if (element.name == "vertex") {
          property.role = role_of(property.name);
          if (property.role == Role::kRing && type->kind == 'F') {
            lines.fail("property 'ring' has a floating-point type: expected an integer type");
          }
        }
      } else {
        lines.fail("expected 'property <type> <name>' or 'property list <type> <type> <name>', found " +
                   quote_token(*line));
      }
      for (const PlyProperty& p : element.properties) {
        if (p.name == property.name)
          lines.fail("property " + quote_token(property.name) + " appears twice in element " +
                     quote_token(element.name));
      }
      element.properties.push_back(std::move(property));
    } else {
      lines.fail("unknown PLY header keyword " + quote_token(key) +
                 ": expected format, element, property, comment or end_header");
    }
  }
  const std::size_t end_line = lines.line_number();
  if (format.empty()) lines.fail_at(end_line, "no 'format' line in the PLY header");
  const PlyElement* vertex = nullptr;
  for (const PlyElement& element : elements) {
    if (element.name == "vertex") vertex = &element;
    if (element.count > 0 && element.properties.empty()) {
      lines.fail_at(element.line, "element " + quote_token(element.name) + " has no properties");
    }
  }
  if (vertex == nullptr) lines.fail_at(end_line, "no 'element vertex' in the PLY header");
  std::vector<Field> vertex_fields;
  for (const PlyProperty& p : vertex->properties) vertex_fields.push_back(Field{p.name, p.type, 1, p.role});
  std::array<bool, kRoles> present{};
  if (const std::string problem = check_roles(vertex_fields, present); !problem.empty()) {
    lines.fail_at(vertex->line, problem);
  }
  report.format = "ply " + format;
  const std::size_t data_offset = lines.offset();
  const std::size_t available = contents.size() - data_offset;

  // Counts the file cannot hold are refused before anything is allocated: every property takes
  // at least its size in binary (a list at least its count), and two characters in ASCII.
  const bool ascii = format == "ascii";
  {
    std::uint64_t needed = 0;
    for (const PlyElement& element : elements) {
      std::uint64_t each = 0;
      for (const PlyProperty& p : element.properties) each += ascii ? 2 : (p.is_list ? p.count_type.size : p.type.size);
      if (each == 0) continue;  // an empty element (count 0, checked above)
      if (element.count > (available + 1 - needed) / each) {
        lines.fail_at(element.line, "element " + quote_token(element.name) + " announces " +
                                        std::to_string(element.count) + " entries, more than the " +
                                        std::to_string(available) +
                                        " bytes after end_header can hold (truncated file?)");
      }
      needed += element.count * each;
    }
  }

  CloudBuilder builder(present, time_scale_of(vertex_fields), static_cast<std::size_t>(vertex->count));
  std::array<double, kRoles> values{};
  if (ascii) {
    TextTokens tokens(contents, data_offset, end_line + 1);
    for (const PlyElement& element : elements) {
      const bool is_vertex = &element == vertex;
      for (std::uint64_t i = 0; i < element.count; ++i) {
        for (const PlyProperty& p : element.properties) {
          const auto number = [&](const char* what) {
            const std::string_view token = tokens.next();
            if (token.empty()) {
              throw ParseError(path, tokens.line(),
                               "file ends in " + std::string(element.name) + " " + std::to_string(i) + " of " +
                                   std::to_string(element.count) + ": expected " + what + " " + quote_token(p.name) +
                                   " (truncated file?)");
            }
            const auto value = parse_number(token);
            if (!value) {
              throw ParseError(path, tokens.line(),
                               "expected a number for " + std::string(what) + " " + quote_token(p.name) + " of " +
                                   element.name + " " + std::to_string(i) + ", found " + printable(token));
            }
            return *value;
          };
          if (p.is_list) {
            const double n = number("the length of list");
            if (!(n >= 0.0 && n <= static_cast<double>(available) && n == std::floor(n))) {
              throw ParseError(path, tokens.line(),
                               "list " + quote_token(p.name) + " of " + element.name + " " + std::to_string(i) +
                                   " has length " + number_text(n) +
                                   ": expected a non-negative integer the file can hold");
            }
            for (std::size_t k = 0; k < static_cast<std::size_t>(n); ++k) number("an item of list");
          } else {
            const double value = number("property");
            if (is_vertex && p.role != Role::kSkip) values[static_cast<std::size_t>(p.role)] = value;
          }
        }
        if (is_vertex) {
          if (const std::string problem = builder.add(values); !problem.empty()) {
            throw ParseError(path, tokens.line(), "vertex " + std::to_string(i) + ": " + problem);
          }
        }
      }
    }
    if (const std::string_view extra = tokens.next(); !extra.empty()) {
      throw ParseError(path, tokens.line(), "unexpected data after the last element: " + printable(extra));
    }
    return builder.finish(report);
  }

  const auto* bytes = reinterpret_cast<const unsigned char*>(contents.data());
  std::size_t position = data_offset;
  for (const PlyElement& element : elements) {
    const bool is_vertex = &element == vertex;
    const bool fixed = std::none_of(element.properties.begin(), element.properties.end(),
                                    [](const PlyProperty& p) { return p.is_list; });
    std::size_t record = 0;
    for (const PlyProperty& p : element.properties) record += p.is_list ? 0 : p.type.size;
    for (std::uint64_t i = 0; i < element.count; ++i) {
      const std::size_t record_start = position;
      if (fixed && record > contents.size() - position) {
        throw ParseError(path, 0,
                         "truncated binary data: " + element.name + " " + std::to_string(i) + " of " +
                             std::to_string(element.count) + " needs " + std::to_string(record) +
                             " bytes at byte offset " + std::to_string(position) + ", only " +
                             std::to_string(contents.size() - position) + " remain");
      }
      for (const PlyProperty& p : element.properties) {
        if (p.is_list) {
          if (p.count_type.size > contents.size() - position) {
            throw ParseError(path, 0,
                             "truncated binary data: the length of list " + quote_token(p.name) + " of " +
                                 element.name + " " + std::to_string(i) + " at byte offset " +
                                 std::to_string(position) + " is cut off");
          }
          const double n = read_scalar(reinterpret_cast<const char*>(bytes + position), p.count_type);
          if (n < 0.0) {
            throw ParseError(path, 0,
                             "list " + quote_token(p.name) + " at byte offset " + std::to_string(position) +
                                 " has negative length " + number_text(n));
          }
          position += p.count_type.size;
          const auto items = static_cast<std::size_t>(n);
          if (items > (contents.size() - position) / p.type.size) {
            throw ParseError(path, 0,
                             "truncated binary data: list " + quote_token(p.name) + " of " + element.name + " " +
                                 std::to_string(i) + " at byte offset " + std::to_string(position - p.count_type.size) +
                                 " has " + std::to_string(items) + " items, more than the remaining bytes hold");
          }
          position += items * p.type.size;
        } else {
          if (p.type.size > contents.size() - position) {
            throw ParseError(path, 0,
                             "truncated binary data: property " + quote_token(p.name) + " of " + element.name + " " +
                                 std::to_string(i) + " at byte offset " + std::to_string(position) + " is cut off");
          }
          if (is_vertex && p.role != Role::kSkip) {
            values[static_cast<std::size_t>(p.role)] =
                read_scalar(reinterpret_cast<const char*>(bytes + position), p.type);
          }
          position += p.type.size;
        }
      }
      if (is_vertex) {
        if (const std::string problem = builder.add(values); !problem.empty()) {
          throw ParseError(
              path, 0,
              "vertex " + std::to_string(i) + " (byte offset " + std::to_string(record_start) + "): " + problem);
        }
      }
    }
  }
  report.trailing_bytes = contents.size() - position;
  return builder.finish(report);
}

// ---------------------------------------------------------------------------------------------
// KITTI Velodyne scans (devkit_odometry readme: float32 x, y, z, reflectance per point).

PointCloud parse_kitti_bin(const std::string& path, const std::string& contents, PointCloudReadReport& report) {
  constexpr std::size_t kPointBytes = 16;
  if (contents.size() % kPointBytes != 0) {
    throw ParseError(path, 0,
                     "KITTI .bin file of " + std::to_string(contents.size()) +
                         " bytes: expected a multiple of 16 (float32 x y z intensity per point; truncated file?)");
  }
  report.format = "kitti bin";
  std::array<bool, kRoles> present{};
  present[static_cast<std::size_t>(Role::kX)] = true;
  present[static_cast<std::size_t>(Role::kY)] = true;
  present[static_cast<std::size_t>(Role::kZ)] = true;
  present[static_cast<std::size_t>(Role::kIntensity)] = true;
  const std::size_t points = contents.size() / kPointBytes;
  CloudBuilder builder(present, 1.0, points);
  std::array<double, kRoles> values{};
  for (std::size_t i = 0; i < points; ++i) {
    for (std::size_t k = 0; k < 4; ++k) {
      float v = 0.0F;
      std::memcpy(&v, contents.data() + i * kPointBytes + 4 * k, 4);
      values[k] = static_cast<double>(v);  // x, y, z, intensity are roles 0..3
    }
    if (const std::string problem = builder.add(values); !problem.empty()) {
      throw ParseError(
          path, 0, "point " + std::to_string(i) + " (byte offset " + std::to_string(i * kPointBytes) + "): " + problem);
    }
  }
  return builder.finish(report);
}

/// `path` without a trailing compression suffix (.xz, .gz, .bz2), lower-cased extension test.
bool has_bin_extension(std::string_view path) {
  const auto ends_with = [](std::string_view s, std::string_view suffix) {
    if (s.size() < suffix.size()) return false;
    for (std::size_t i = 0; i < suffix.size(); ++i) {
      const char c = s[s.size() - suffix.size() + i];
      if ((c >= 'A' && c <= 'Z' ? static_cast<char>(c - 'A' + 'a') : c) != suffix[i]) return false;
    }
    return true;
  };
  for (const std::string_view suffix : {".xz", ".gz", ".bz2"}) {
    if (ends_with(path, suffix)) {
      path.remove_suffix(suffix.size());
      break;
    }
  }
  return ends_with(path, ".bin");
}

}  // namespace

PointCloud parse_point_cloud(const std::string& path, const std::string& contents, PointCloudReadReport* report) {
  PointCloudReadReport local;
  PointCloudReadReport& out = report != nullptr ? *report : local;
  out = PointCloudReadReport{};
  if (contents.empty()) {
    throw ParseError(path, 0, "file is empty: expected a point cloud (PCD, PLY or KITTI .bin)");
  }
  const std::string_view head(contents.data(), std::min<std::size_t>(contents.size(), 16));
  if (head.starts_with("# .PCD") || head.starts_with("VERSION")) return parse_pcd(path, contents, out);
  if (head.starts_with("ply\n") || head.starts_with("ply\r\n")) return parse_ply(path, contents, out);
  if (has_bin_extension(path)) return parse_kitti_bin(path, contents, out);
  throw ParseError(path, 0,
                   "unknown point-cloud format: expected a PCD header ('# .PCD' or 'VERSION'), 'ply' or a KITTI "
                   ".bin file name, found " +
                       printable(head));
}

PointCloud read_point_cloud(const std::string& path, PointCloudReadReport* report) {
  if (path == "-") return parse_point_cloud("standard input", standard_input(), report);
  return parse_point_cloud(path, read_maybe_compressed(path), report);
}

void recover_kitti_ring_and_time(PointCloud& cloud, double sweep_period_s) {
  CAIRN_ASSERT(std::isfinite(sweep_period_s) && sweep_period_s > 0.0,
               "recover_kitti_ring_and_time: sweep_period_s must be positive and finite");
  const std::size_t n = cloud.points.size();
  cloud.ring.assign(n, 0);
  cloud.time_s.assign(n, 0.0F);
  constexpr double kPi = std::numbers::pi;
  std::uint16_t ring = 0;
  bool wrapped = false;  // the current ring has passed behind the car (+pi -> -pi)
  double previous = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = cloud.points[i];
    const double azimuth = std::atan2(static_cast<double>(p.y()), static_cast<double>(p.x()));
    if (i > 0) {
      if (azimuth < previous - kPi) {
        wrapped = true;
      } else if (wrapped && previous < 0.0 && azimuth >= 0.0 && azimuth - previous < kPi) {
        if (ring < std::numeric_limits<std::uint16_t>::max()) ++ring;
        wrapped = false;
      }
    }
    previous = azimuth;
    cloud.ring[i] = ring;
    // Clockwise spin, sweep from behind the car (azimuth +pi) round to behind it again (-pi).
    cloud.time_s[i] = static_cast<float>((kPi - azimuth) / (2.0 * kPi) * sweep_period_s);
  }
}

void write_ply(std::ostream& out, const std::vector<Eigen::Vector3f>& points, const std::string& comment) {
  out << "ply\nformat binary_little_endian 1.0\n";
  if (!comment.empty()) out << "comment " << comment << '\n';
  out << "element vertex " << points.size() << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  static_assert(std::endian::native == std::endian::little, "write_ply assumes a little-endian machine");
  std::vector<float> buffer;
  buffer.reserve(3 * std::min<std::size_t>(points.size(), 65536));
  for (std::size_t i = 0; i < points.size(); ++i) {
    buffer.insert(buffer.end(), {points[i].x(), points[i].y(), points[i].z()});
    if (buffer.size() >= 3 * 65536 || i + 1 == points.size()) {
      out.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(buffer.size() * sizeof(float)));
      buffer.clear();
    }
  }
}

void write_pcd(std::ostream& out, const PointCloud& cloud, const std::string& comment) {
  const std::size_t n = cloud.size();
  const bool has_intensity = !cloud.intensity.empty();
  const bool has_ring = !cloud.ring.empty();
  const bool has_time = !cloud.time_s.empty();
  CAIRN_ASSERT((!has_intensity || cloud.intensity.size() == n) && (!has_ring || cloud.ring.size() == n) &&
                   (!has_time || cloud.time_s.size() == n),
               "write_pcd: every attribute needs one value per point (or none)");
  std::string fields = "x y z";
  std::string sizes = "4 4 4";
  std::string types = "F F F";
  std::string counts = "1 1 1";
  auto field = [&](const char* name, const char* size, const char* type) {
    fields += std::string(" ") + name;
    sizes += std::string(" ") + size;
    types += std::string(" ") + type;
    counts += " 1";
  };
  if (has_intensity) field("intensity", "4", "F");
  if (has_ring) field("ring", "2", "U");
  if (has_time) field("time", "4", "F");
  out << "# .PCD v0.7 - Point Cloud Data file format\n";
  if (!comment.empty()) out << "# " << comment << '\n';
  out << "VERSION 0.7\nFIELDS " << fields << "\nSIZE " << sizes << "\nTYPE " << types << "\nCOUNT " << counts
      << "\nWIDTH " << n << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n << "\nDATA binary\n";
  static_assert(std::endian::native == std::endian::little, "write_pcd assumes a little-endian machine");
  const std::size_t record = 12 + (has_intensity ? 4 : 0) + (has_ring ? 2 : 0) + (has_time ? 4 : 0);
  std::vector<char> buffer;
  buffer.reserve(record * std::min<std::size_t>(n, 65536));
  auto append = [&](const void* value, std::size_t bytes) {
    const auto* p = static_cast<const char*>(value);
    buffer.insert(buffer.end(), p, p + bytes);
  };
  for (std::size_t i = 0; i < n; ++i) {
    append(cloud.points[i].data(), 12);
    if (has_intensity) append(&cloud.intensity[i], 4);
    if (has_ring) append(&cloud.ring[i], 2);
    if (has_time) append(&cloud.time_s[i], 4);
    if (buffer.size() >= record * 65536 || i + 1 == n) {
      out.write(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      buffer.clear();
    }
  }
}

}  // namespace cairn::io
