#include "cairn/inertial/imu_csv.hpp"

#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_rows.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::inertial {
namespace {

constexpr std::size_t kAbsent = std::numeric_limits<std::size_t>::max();
constexpr double kDegreesToRadians = std::numbers::pi / 180.0;
constexpr std::array<const char*, 3> kAxes{"x", "y", "z"};

// Where each quantity is in a row of the plain CSV, and the factor to SI units.
struct CsvLayout {
  std::size_t fields = 0;
  std::size_t time = kAbsent;
  bool time_in_ns = false;
  std::array<std::size_t, 6> column{kAbsent, kAbsent, kAbsent, kAbsent, kAbsent, kAbsent};  // gyro xyz, accel xyz
  std::array<double, 6> scale{};
};

// The quantity a header name stands for: -1 time, 0..5 gyro xyz / accel xyz, -2 none.
int quantity_of(std::string_view name, double* scale, bool* in_ns) {
  if (name == "time_s" || name == "time_ns") {
    *in_ns = name == "time_ns";
    return -1;
  }
  for (int axis = 0; axis < 3; ++axis) {
    const std::string a = kAxes[static_cast<std::size_t>(axis)];
    const std::array<std::pair<std::string, double>, 4> units{{{"gyro_" + a + "_rad_s", 1.0},
                                                               {"gyro_" + a + "_deg_s", kDegreesToRadians},
                                                               {"accel_" + a + "_mps2", 1.0},
                                                               {"accel_" + a + "_g", kStandardGravity}}};
    for (std::size_t u = 0; u < units.size(); ++u) {
      if (name == units[u].first) {
        *scale = units[u].second;
        return axis + (u < 2 ? 0 : 3);
      }
    }
  }
  return -2;
}

std::string quantity_names(int quantity) {
  if (quantity < 0) return "time_s or time_ns";
  const std::string a = kAxes[static_cast<std::size_t>(quantity % 3)];
  return quantity < 3 ? "gyro_" + a + "_rad_s or gyro_" + a + "_deg_s" : "accel_" + a + "_mps2 or accel_" + a + "_g";
}

CsvLayout parse_header(const io::TextReader& reader) {
  const auto names = io::split_fields(reader.line(), ',');
  CsvLayout layout;
  layout.fields = names.size();
  for (std::size_t i = 0; i < names.size(); ++i) {
    double scale = 1.0;
    bool in_ns = false;
    const int quantity = quantity_of(names[i], &scale, &in_ns);
    if (quantity == -2) continue;
    std::size_t& slot = quantity < 0 ? layout.time : layout.column[static_cast<std::size_t>(quantity)];
    if (slot != kAbsent) {
      reader.fail("header names two columns for one quantity (" + quantity_names(quantity) + "): '" +
                  std::string(names[slot]) + "' (column " + std::to_string(slot + 1) + ") and '" + std::string(names[i]) +
                  "' (column " + std::to_string(i + 1) + ")");
    }
    slot = i;
    if (quantity < 0) layout.time_in_ns = in_ns;
    else layout.scale[static_cast<std::size_t>(quantity)] = scale;
  }
  std::string missing;
  for (int quantity = -1; quantity < 6; ++quantity) {
    const std::size_t slot = quantity < 0 ? layout.time : layout.column[static_cast<std::size_t>(quantity)];
    if (slot == kAbsent) missing += (missing.empty() ? "" : "; ") + quantity_names(quantity);
  }
  if (!missing.empty()) {
    reader.fail("expected a header row naming the IMU columns (docs/formats.md, \"IMU data\"), found " +
                io::quote_token(reader.line()) + ", which lacks: " + missing);
  }
  return layout;
}

ImuSample parse_row(const io::TextReader& reader, const CsvLayout& layout) {
  const auto fields = io::split_fields(reader.line(), ',');
  if (fields.size() != layout.fields) {
    reader.fail("expected " + std::to_string(layout.fields) + " comma-separated columns (as the header names), found " +
                std::to_string(fields.size()));
  }
  ImuSample sample;
  sample.stamp = layout.time_in_ns ? parse_stamp_ns(reader, fields[layout.time], "time_ns")
                                   : parse_stamp_s(reader, fields[layout.time], "time_s");
  for (std::size_t q = 0; q < 6; ++q) {
    const std::string what = quantity_names(static_cast<int>(q));
    const double value = io::parse_double(reader, fields[layout.column[q]], std::string(q < 3 ? "gyro " : "accel ") + kAxes[q % 3]);
    const double si = value * layout.scale[q];
    if (!std::isfinite(si)) reader.fail("expected a finite number for " + what + ", found " + io::quote_token(fields[layout.column[q]]));
    (q < 3 ? sample.gyro_rad_s : sample.accel_mps2)[static_cast<Eigen::Index>(q % 3)] = si;
  }
  return sample;
}

bool starts_with_number(std::string_view line) {
  const auto fields = io::split_fields(line, ',');
  if (fields.empty() || fields[0].empty()) return false;
  double value = 0.0;
  std::string_view first = fields[0];
  if (first.front() == '+') first.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(first.data(), first.data() + first.size(), value);
  return ptr != first.data() && ec != std::errc::invalid_argument;
}

}  // namespace

std::vector<ImuSample> read_imu_csv(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  io::TextReader reader(resolve_dataset_file(path, {}, "a plain IMU CSV file"));
  std::optional<CsvLayout> layout;
  std::vector<ImuSample> samples;
  IncreasingStampCheck order;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    if (!layout) {
      layout = parse_header(reader);
      continue;
    }
    samples.push_back(parse_row(reader, *layout));
    order.check(reader, samples.back().stamp);
  }
  if (!layout) throw io::ParseError(reader.path(), 0, "no header row: expected a plain IMU CSV (docs/formats.md)");
  if (samples.empty()) throw io::ParseError(reader.path(), 0, "no IMU samples after the header row");
  if (reader.last_line_unterminated() && warnings != nullptr) warnings->push_back(reader.unterminated_last_line_warning());
  return samples;
}

void write_imu_csv(const std::filesystem::path& path, const std::vector<ImuSample>& samples) {
  const std::string name = path.string();
  if (samples.empty()) throw io::ParseError(name, 0, "cannot write a plain IMU CSV: no samples (readers refuse an empty file)");
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const std::int64_t ns = samples[i].stamp.nanoseconds();
    if (ns < -kMaxAbsImuStampNs || ns > kMaxAbsImuStampNs || (i > 0 && !(samples[i - 1].stamp < samples[i].stamp)) ||
        !samples[i].gyro_rad_s.allFinite() || !samples[i].accel_mps2.allFinite()) {
      throw io::ParseError(name, 0, "cannot write a plain IMU CSV: sample " + std::to_string(i) +
                                        " has a non-finite value, or a stamp that does not increase or is beyond +-9.2e9 s");
    }
  }
  io::write_output(name, [&](std::ostream& out) {
    out << "time_ns,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_mps2,accel_y_mps2,accel_z_mps2\n";
    std::string line;
    for (const ImuSample& s : samples) {
      line = std::to_string(s.stamp.nanoseconds());
      for (const double v : {s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z(), s.accel_mps2.x(), s.accel_mps2.y(),
                             s.accel_mps2.z()}) {
        line += ',';
        io::append_number(line, v);
      }
      line += '\n';
      out << line;
    }
  });
}

std::vector<ImuSample> read_imu_file(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  if (path != "-" && bag::is_bag(path.string())) return read_imu_topic(path, "");
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) return read_euroc_imu(path, warnings);
  {
    io::TextReader reader(resolve_dataset_file(path, {}, "an IMU file"));
    while (reader.next_line()) {
      if (io::is_blank_or_comment(reader.line())) continue;
      if (starts_with_number(reader.line())) break;
      return read_imu_csv(path, warnings);
    }
  }
  return read_euroc_imu(path, warnings);
}

namespace {

ImuSample sample_of(const bag::Imu& imu, const std::string& where) {
  ImuSample sample;
  sample.stamp = core::Timestamp::from_nanoseconds(imu.header.stamp_ns);
  sample.gyro_rad_s = imu.angular_velocity_rad_s;
  sample.accel_mps2 = imu.linear_acceleration_m_s2;
  if (!sample.gyro_rad_s.allFinite() || !sample.accel_mps2.allFinite()) {
    throw io::ParseError(where, 0, "expected a finite angular_velocity and linear_acceleration, found a NaN or infinity");
  }
  if (imu.header.stamp_ns < -kMaxAbsImuStampNs || imu.header.stamp_ns > kMaxAbsImuStampNs) {
    throw io::ParseError(where, 0, "header stamp beyond +-9.2e9 s");
  }
  return sample;
}

}  // namespace

std::vector<ImuSample> read_imu_topic(const std::filesystem::path& bag_path, const std::string& topic_name) {
  const std::string path = bag_path.string();
  bag::Bag bag = bag::Bag::open(path);
  const std::size_t topic = bag::choose_topic(bag, topic_name, {{"sensor_msgs/Imu"}, "IMU", "--imu-topic"});
  const std::string& name = bag.topics()[topic].name;
  bag::MessageDecoder decoder(bag);
  if (std::string why; !decoder.can_decode(topic, &why)) {
    throw io::ParseError(path, 0, "topic " + name + " (sensor_msgs/Imu) cannot be decoded: " + why);
  }
  std::vector<ImuSample> samples;
  const auto stream = bag.read({topic});
  bag::BagMessage message;
  while (stream->next(&message)) {
    const std::string where = path + ": " + name + " message " + std::to_string(samples.size() + 1);
    bag::Imu imu;
    try {
      imu = bag::to_imu(decoder.decode(message));
    } catch (const io::ParseError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw io::ParseError(where, 0, e.what());
    }
    const ImuSample sample = sample_of(imu, where);
    if (!samples.empty() && !(samples.back().stamp < sample.stamp)) {
      throw io::ParseError(where, 0, std::string(samples.back().stamp == sample.stamp ? "duplicated" : "out-of-order") +
                                         " header stamp: expected a stamp after " + samples.back().stamp.to_seconds_string() +
                                         " s (the previous message's), found " + sample.stamp.to_seconds_string() + " s");
    }
    samples.push_back(sample);
  }
  if (samples.empty()) throw io::ParseError(path, 0, "topic " + name + " holds no message");
  return samples;
}

}  // namespace cairn::inertial
