#include "cairn/gnss/gnss_reader.hpp"

#include <Eigen/Eigenvalues>
#include <array>
#include <charconv>
#include <cstdio>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string_view>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"
#include "cairn/gnss/local_frame.hpp"

namespace cairn::gnss {
namespace {

using io::TextReader;

// Larger standard deviations are no fix (and their squares would leave the range of doubles).
constexpr double kMaxSigmaM = 1e7;

enum Column : int {
  kTimeS, kTimeNs, kLatitude, kLongitude, kAltitude,
  kStdEast, kStdNorth, kStdUp,
  kCovEE, kCovEN, kCovEU, kCovNN, kCovNU, kCovUU,
  kStatus, kColumnCount
};

constexpr std::array<std::string_view, kColumnCount> kColumnNames = {
    "time_s", "time_ns", "lat_deg", "lon_deg", "alt_m",
    "std_east_m", "std_north_m", "std_up_m",
    "cov_ee_m2", "cov_en_m2", "cov_eu_m2", "cov_nn_m2", "cov_nu_m2", "cov_uu_m2",
    "status"};

std::string column_list() {
  std::string out;
  for (const std::string_view name : kColumnNames) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

// Where each column is on a line (-1: absent) and how many fields a line has.
struct CsvLayout {
  std::array<int, kColumnCount> index{};
  std::size_t fields = 0;
  bool has(Column c) const { return index[c] >= 0; }
  bool has_any(Column first, Column last) const {
    for (int c = first; c <= last; ++c) if (index[c] >= 0) return true;
    return false;
  }
  bool has_all(Column first, Column last) const {
    for (int c = first; c <= last; ++c) if (index[c] < 0) return false;
    return true;
  }
};

void check_layout(const TextReader& reader, const CsvLayout& layout) {
  if (layout.has(kTimeS) == layout.has(kTimeNs)) {
    reader.fail(std::string("expected exactly one time column, time_s or time_ns, found ") +
                (layout.has(kTimeS) ? "both" : "neither"));
  }
  for (const Column c : {kLatitude, kLongitude, kAltitude}) {
    if (!layout.has(c)) reader.fail("expected a column " + std::string(kColumnNames[c]) + ", found none");
  }
  if (layout.has_any(kStdEast, kStdUp) && !layout.has_all(kStdEast, kStdUp)) {
    reader.fail("expected all three of std_east_m, std_north_m, std_up_m or none, found only some");
  }
  if (layout.has_any(kCovEE, kCovUU) && !layout.has_all(kCovEE, kCovUU)) {
    reader.fail("expected all six of cov_ee_m2 ... cov_uu_m2 or none, found only some");
  }
  if (layout.has_any(kStdEast, kStdUp) && layout.has_any(kCovEE, kCovUU)) {
    reader.fail("expected standard deviations (std_*_m) or a covariance (cov_*_m2), found both");
  }
}

CsvLayout parse_header(const TextReader& reader) {
  CsvLayout layout;
  layout.index.fill(-1);
  const std::vector<std::string_view> names = io::split_fields(reader.line(), ',');
  layout.fields = names.size();
  for (std::size_t i = 0; i < names.size(); ++i) {
    int found = -1;
    for (int c = 0; c < kColumnCount; ++c) {
      if (names[i] == kColumnNames[c]) found = c;
    }
    if (found < 0) {
      reader.fail("expected a header of known columns (" + column_list() + "), found " + io::quote_token(names[i]));
    }
    if (layout.index[found] >= 0) reader.fail("column " + std::string(names[i]) + " appears twice in the header");
    layout.index[found] = static_cast<int>(i);
  }
  check_layout(reader, layout);
  return layout;
}

std::string number_text(double value) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%.10g", value);
  return text.data();
}

bool is_nan_token(std::string_view token) {
  if (!token.empty() && (token.front() == '-' || token.front() == '+')) token.remove_prefix(1);
  if (token.size() != 3) return false;
  const auto lower = [](char ch) { return static_cast<char>(ch >= 'A' && ch <= 'Z' ? ch - 'A' + 'a' : ch); };
  return lower(token[0]) == 'n' && lower(token[1]) == 'a' && lower(token[2]) == 'n';
}

// A latitude, longitude or altitude: a finite number, or NaN (the fix is then dropped).
double parse_coordinate(const TextReader& reader, std::string_view token, std::string_view what) {
  if (is_nan_token(token)) return std::numeric_limits<double>::quiet_NaN();
  return io::parse_double(reader, token, what);
}

core::Timestamp parse_time(const TextReader& reader, const CsvLayout& layout,
                           const std::vector<std::string_view>& fields) {
  if (layout.has(kTimeS)) {
    const std::string_view token = fields[static_cast<std::size_t>(layout.index[kTimeS])];
    const std::optional<core::Timestamp> stamp = core::Timestamp::parse_seconds(token);
    if (!stamp) reader.fail("expected a time in seconds for time_s, found " + io::quote_token(token));
    return *stamp;
  }
  const std::string_view token = fields[static_cast<std::size_t>(layout.index[kTimeNs])];
  const std::optional<core::Timestamp> stamp = core::Timestamp::parse_nanoseconds(token);
  if (!stamp) reader.fail("expected an integer count of nanoseconds for time_ns, found " + io::quote_token(token));
  return *stamp;
}

int parse_status(const TextReader& reader, std::string_view token) {
  int status = 0;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), status);
  if (error != std::errc() || end != token.data() + token.size() || status < kStatusNoFix || status > kStatusGbasFix) {
    reader.fail("expected a status -1, 0, 1 or 2 (sensor_msgs/NavSatStatus), found " + io::quote_token(token));
  }
  return status;
}

Matrix3 parse_standard_deviations(const TextReader& reader, const CsvLayout& layout,
                                  const std::vector<std::string_view>& fields) {
  Matrix3 covariance = Matrix3::Zero();
  for (int axis = 0; axis < 3; ++axis) {
    const Column c = static_cast<Column>(kStdEast + axis);
    const std::string_view token = fields[static_cast<std::size_t>(layout.index[c])];
    const double sigma = io::parse_double(reader, token, kColumnNames[c]);
    if (!(sigma > 0.0 && sigma <= kMaxSigmaM)) {
      reader.fail("expected a standard deviation in (0, 1e7] m for " + std::string(kColumnNames[c]) + ", found " +
                  io::quote_token(token));
    }
    covariance(axis, axis) = sigma * sigma;
  }
  return covariance;
}

Matrix3 parse_covariance(const TextReader& reader, const CsvLayout& layout, const std::vector<std::string_view>& fields) {
  // Upper triangle row by row: ee en eu nn nu uu.
  constexpr std::array<std::pair<int, int>, 6> kCells = {{{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}}};
  Matrix3 covariance = Matrix3::Zero();
  for (int k = 0; k < 6; ++k) {
    const Column c = static_cast<Column>(kCovEE + k);
    const double value = io::parse_double(reader, fields[static_cast<std::size_t>(layout.index[c])], kColumnNames[c]);
    covariance(kCells[k].first, kCells[k].second) = value;
    covariance(kCells[k].second, kCells[k].first) = value;
  }
  if (!(covariance.cwiseAbs().maxCoeff() <= kMaxSigmaM * kMaxSigmaM)) {
    reader.fail("expected covariance entries of at most 1e14 m^2 (1e7 m standard deviation), found more");
  }
  if (!(covariance.diagonal().minCoeff() > 0.0)) {
    reader.fail("expected a covariance with cov_ee_m2, cov_nn_m2, cov_uu_m2 > 0, found a diagonal entry <= 0");
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3> eigen(covariance, Eigen::EigenvaluesOnly);
  if (eigen.eigenvalues()(0) < -1e-9 * eigen.eigenvalues()(2)) {
    reader.fail("expected a positive semi-definite covariance, found an eigenvalue of " +
                number_text(eigen.eigenvalues()(0)) + " m^2");
  }
  return covariance;
}

void check_position(const TextReader& reader, const GnssFix& fix) {
  std::string why;
  if (!is_valid_geodetic({fix.latitude_deg, fix.longitude_deg, fix.altitude_m}, &why)) {
    reader.fail("expected a position on Earth, found " + number_text(fix.latitude_deg) + " deg, " +
                number_text(fix.longitude_deg) + " deg, " + number_text(fix.altitude_m) + " m: " + why);
  }
}

void drop(GnssReadReport& report, std::size_t& counter, const std::string& where, const std::string& why) {
  ++counter;
  if (report.first_dropped.empty()) report.first_dropped = where + ": " + why;
}

// One data line: a fix to keep, or nothing (dropped and counted); its stamp in *stamp either way.
std::optional<GnssFix> parse_row(const TextReader& reader, const CsvLayout& layout, GnssReadReport& report,
                                 core::Timestamp* stamp) {
  const std::vector<std::string_view> fields = io::split_fields(reader.line(), ',');
  if (fields.size() != layout.fields) {
    reader.fail("expected " + std::to_string(layout.fields) + " comma-separated fields as the header names, found " +
                std::to_string(fields.size()));
  }
  const auto field = [&](Column c) { return fields[static_cast<std::size_t>(layout.index[c])]; };
  GnssFix fix;
  fix.stamp = parse_time(reader, layout, fields);
  *stamp = fix.stamp;
  fix.latitude_deg = parse_coordinate(reader, field(kLatitude), "lat_deg");
  fix.longitude_deg = parse_coordinate(reader, field(kLongitude), "lon_deg");
  fix.altitude_m = parse_coordinate(reader, field(kAltitude), "alt_m");
  if (layout.has(kStatus)) fix.status = parse_status(reader, field(kStatus));
  if (layout.has(kStdEast)) fix.covariance_enu_m2 = parse_standard_deviations(reader, layout, fields);
  if (layout.has(kCovEE)) fix.covariance_enu_m2 = parse_covariance(reader, layout, fields);
  fix.covariance_known = layout.has(kStdEast) || layout.has(kCovEE);
  const std::string where = reader.path() + ":" + std::to_string(reader.line_number());
  if (fix.status == kStatusNoFix) {
    drop(report, report.dropped_no_fix, where, "status -1 (no fix)");
    return std::nullopt;
  }
  if (!std::isfinite(fix.latitude_deg) || !std::isfinite(fix.longitude_deg) || !std::isfinite(fix.altitude_m)) {
    drop(report, report.dropped_not_finite, where, "NaN position");
    return std::nullopt;
  }
  check_position(reader, fix);
  return fix;
}

// NavSatFix's covariance as a GnssFix keeps it (see read_gnss_bag); false when declared known but unusable.
bool set_covariance(const bag::NavSatFix& message, GnssFix& fix) {
  fix.covariance_known = false;
  if (message.position_covariance_type == 0) return true;
  Matrix3 covariance;
  for (int i = 0; i < 9; ++i) covariance(i / 3, i % 3) = message.position_covariance[static_cast<std::size_t>(i)];
  if (message.position_covariance_type == 2) covariance = Matrix3(covariance.diagonal().asDiagonal());
  if (!(covariance.cwiseAbs().maxCoeff() <= kMaxSigmaM * kMaxSigmaM) || !(covariance.diagonal().minCoeff() > 0.0)) {
    return false;  // NaN fails the first test too
  }
  fix.covariance_enu_m2 = 0.5 * (covariance + covariance.transpose());
  fix.covariance_known = true;
  return true;
}

// One decoded message: a fix to keep, or nothing (dropped and counted). `where` names the message.
std::optional<GnssFix> fix_of(const bag::NavSatFix& message, const std::string& where, GnssReadReport& report) {
  GnssFix fix;
  fix.stamp = core::Timestamp::from_nanoseconds(message.header.stamp_ns);
  fix.status = message.status;
  fix.latitude_deg = message.latitude_deg;
  fix.longitude_deg = message.longitude_deg;
  fix.altitude_m = message.altitude_m;
  if (fix.status == kStatusNoFix) {
    drop(report, report.dropped_no_fix, where, "status -1 (no fix)");
    return std::nullopt;
  }
  if (!std::isfinite(fix.latitude_deg) || !std::isfinite(fix.longitude_deg) || !std::isfinite(fix.altitude_m)) {
    drop(report, report.dropped_not_finite, where, "NaN position");
    return std::nullopt;
  }
  if (fix.status < kStatusNoFix || fix.status > kStatusGbasFix) {
    throw io::ParseError(where, 0, "expected a status -1, 0, 1 or 2, found " + std::to_string(fix.status));
  }
  std::string why;
  if (!is_valid_geodetic({fix.latitude_deg, fix.longitude_deg, fix.altitude_m}, &why)) {
    throw io::ParseError(where, 0, "expected a position on Earth: " + why);
  }
  if (!set_covariance(message, fix)) {
    ++report.covariance_invalid;
    if (report.covariance_invalid == 1) {
      report.warnings.push_back(where + ": position_covariance declared known (type " +
                                std::to_string(message.position_covariance_type) +
                                ") but has a non-finite, huge (> 1e14 m^2) or non-positive entry on its diagonal or off it: used as unknown");
    }
  }
  return fix;
}

}  // namespace

std::vector<GnssFix> read_gnss_csv(const std::string& path, GnssReadReport* report_out) {
  TextReader reader(path);
  GnssReadReport report;
  std::optional<CsvLayout> layout;
  std::optional<core::Timestamp> previous;
  std::vector<GnssFix> fixes;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    if (!layout) {
      layout = parse_header(reader);
      continue;
    }
    ++report.records;
    // Every line's stamp counts for the order, dropped or not: a file out of order is refused.
    core::Timestamp stamp;
    const std::optional<GnssFix> fix = parse_row(reader, *layout, report, &stamp);
    if (previous && !(stamp > *previous)) {
      reader.fail("expected a time after the previous line's " + previous->to_seconds_string() + " s, found " +
                  stamp.to_seconds_string() + " s");
    }
    previous = stamp;
    if (!fix) continue;
    if (!fix->covariance_known) ++report.covariance_unknown;
    fixes.push_back(*fix);
  }
  if (!layout) throw io::ParseError(reader.path(), 0, "expected a header line naming the columns (" + column_list() + "), found none (the file is empty or only comments)");
  if (reader.last_line_unterminated()) report.warnings.push_back(reader.unterminated_last_line_warning());
  report.fixes = fixes.size();
  if (report_out != nullptr) *report_out = report;
  return fixes;
}

std::vector<GnssFix> read_gnss_bag(const std::string& bag_path, const std::string& topic_name,
                                   GnssReadReport* report_out) {
  bag::Bag bag = bag::Bag::open(bag_path);
  const std::size_t topic = bag::choose_topic(bag, topic_name, {{"sensor_msgs/NavSatFix"}, "GNSS fix", "--gnss-topic"});
  bag::MessageDecoder decoder(bag);
  GnssReadReport report;
  std::vector<GnssFix> fixes;
  const auto stream = bag.read({topic});
  bag::BagMessage message;
  while (stream->next(&message)) {
    ++report.records;
    const std::string where = bag_path + ": " + bag.topics()[topic].name + " message " + std::to_string(report.records);
    bag::NavSatFix decoded;
    try {
      decoded = bag::to_nav_sat_fix(decoder.decode(message));
    } catch (const io::ParseError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw io::ParseError(where, 0, e.what());
    }
    const std::optional<GnssFix> fix = fix_of(decoded, where, report);
    if (!fix) continue;
    if (!fixes.empty() && !(fix->stamp > fixes.back().stamp)) {
      drop(report, report.dropped_out_of_order, where,
           "stamp " + fix->stamp.to_seconds_string() + " s does not follow " + fixes.back().stamp.to_seconds_string() + " s");
      continue;
    }
    if (!fix->covariance_known) ++report.covariance_unknown;
    fixes.push_back(*fix);
  }
  report.fixes = fixes.size();
  if (report_out != nullptr) *report_out = report;
  return fixes;
}

}  // namespace cairn::gnss
