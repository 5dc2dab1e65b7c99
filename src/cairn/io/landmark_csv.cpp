#include "cairn/io/landmark_csv.hpp"

#include <cmath>
#include <numbers>
#include <string_view>

#include "cairn/io/carmen_log.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

constexpr std::string_view kMapHeader = "id,x_m,y_m";
constexpr std::string_view kObservationsHeader = "time_s,landmark_id,range_m,bearing_rad";

std::vector<std::string_view> csv_fields(const TextReader& reader, std::size_t expected, std::string_view header) {
  auto fields = split_fields(reader.line(), ',');
  if (fields.size() != expected) {
    throw ParseError(reader.path(), reader.line_number(),
                     "expected " + std::to_string(expected) + " comma-separated fields (" + std::string(header) +
                         "), found " + std::to_string(fields.size()));
  }
  return fields;
}

// Skips blank lines and '#' comments; refuses a missing or wrong header.
void expect_header(TextReader& reader, std::string_view header) {
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    if (reader.line() != header) {
      throw ParseError(reader.path(), reader.line_number(),
                       "expected the header '" + std::string(header) + "', found " + quote_token(reader.line()));
    }
    return;
  }
  throw ParseError(reader.path(), reader.line_number(), "expected the header '" + std::string(header) + "', found an empty file");
}

// "<seconds>.<6 digits>", rounded to the microsecond: the text sim::format_carmen_time gives a
// CARMEN log's ipc_timestamp, so an observation and a scan of the same instant read the same.
}  // namespace

std::map<std::int64_t, Vector2> read_landmark_map(const std::string& path) {
  TextReader reader(path);
  expect_header(reader, kMapHeader);
  std::map<std::int64_t, Vector2> map;
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const auto f = csv_fields(reader, 3, kMapHeader);
    const std::int64_t id = parse_id(reader, f[0], "the landmark id");
    const Vector2 p(parse_double(reader, f[1], "x_m"), parse_double(reader, f[2], "y_m"));
    if (!map.emplace(id, p).second) {
      throw ParseError(path, reader.line_number(), "landmark id " + std::to_string(id) + " appears twice");
    }
  }
  return map;
}

std::vector<LandmarkObservation> read_landmark_observations(const std::string& path,
                                                            const std::map<std::int64_t, Vector2>* known_ids) {
  TextReader reader(path);
  expect_header(reader, kObservationsHeader);
  std::vector<LandmarkObservation> observations;
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const auto f = csv_fields(reader, 4, kObservationsHeader);
    LandmarkObservation o;
    o.line = reader.line_number();
    const auto time = core::Timestamp::parse_seconds(f[0]);
    if (!time) {
      throw ParseError(path, o.line, "expected a time in seconds for time_s, found " + quote_token(f[0]));
    }
    o.time = *time;
    o.landmark_id = parse_id(reader, f[1], "landmark_id");
    o.range_m = parse_double(reader, f[2], "range_m");
    o.bearing_rad = parse_double(reader, f[3], "bearing_rad");
    if (!(o.range_m > 0.0)) {
      throw ParseError(path, o.line, "expected range_m > 0, found " + quote_token(f[2]));
    }
    if (std::abs(o.bearing_rad) > std::numbers::pi + 1e-9) {
      throw ParseError(path, o.line, "expected bearing_rad in [-pi, pi], found " + quote_token(f[3]));
    }
    if (known_ids != nullptr && known_ids->count(o.landmark_id) == 0) {
      throw ParseError(path, o.line,
                       "landmark_id " + std::to_string(o.landmark_id) + " is not in the landmark map (landmarks.csv)");
    }
    if (!observations.empty() && o.time < observations.back().time) {
      throw ParseError(path, o.line, "time_s goes backwards (previous line has a later time)");
    }
    observations.push_back(o);
  }
  return observations;
}

void write_landmark_map(const std::string& path, const std::vector<LandmarkPosition>& landmarks) {
  write_output(path, [&](std::ostream& out) {
    out << kMapHeader << '\n';
    std::string line;
    for (const auto& landmark : landmarks) {
      line = std::to_string(landmark.id);
      line += ',';
      append_number(line, landmark.x_m);
      line += ',';
      append_number(line, landmark.y_m);
      line += '\n';
      out << line;
    }
  });
}

void write_landmark_observations(const std::string& path, const std::vector<LandmarkObservation>& observations) {
  write_output(path, [&](std::ostream& out) {
    out << kObservationsHeader << '\n';
    std::string line;
    for (const auto& o : observations) {
      line = format_carmen_time(o.time);
      line += ',';
      line += std::to_string(o.landmark_id);
      line += ',';
      append_number(line, o.range_m);
      line += ',';
      append_number(line, o.bearing_rad);
      line += '\n';
      out << line;
    }
  });
}

}  // namespace cairn::io
