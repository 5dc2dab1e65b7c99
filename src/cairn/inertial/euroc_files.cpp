#include "cairn/inertial/euroc_files.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <ostream>

#include "cairn/inertial/imu_rows.hpp"
#include "cairn/io/compressed_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::inertial {
namespace {

constexpr const char* kImuHeader =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
    "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]";
constexpr const char* kImuLayout = "timestamp [ns], w_RS_S xyz [rad/s], a_RS_S xyz [m/s^2]";
constexpr const char* kGroundTruthHeader =
    "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],v_RS_R_x [m s^-1],"
    "v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
    "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]";
constexpr const char* kGroundTruthLayout =
    "timestamp [ns], p xyz [m], q wxyz, v xyz [m/s], gyro bias xyz [rad/s], accel bias xyz [m/s^2]";

// A sensor.yaml is a handful of keys: a larger file is not one (and yaml-cpp builds its tree
// in memory first).
constexpr std::size_t kMaxCalibrationBytes = std::size_t{1} << 20;
// A quaternion further than this from unit norm is not a rotation written with few digits.
constexpr double kMaxQuaternionNormError = 1e-2;
// T_BS's rotation block: EuRoC's camera extrinsics, printed with 16 digits, are 1e-8 from
// orthonormal; a matrix 1e-6 off is not a rotation.
constexpr double kMaxRotationError = 1e-6;

Vector3 parse_vector(const io::TextReader& reader, const std::vector<std::string_view>& fields, std::size_t first,
                     const char* name) {
  static constexpr std::array<const char*, 3> kAxes{"_x", "_y", "_z"};
  Vector3 v;
  for (int k = 0; k < 3; ++k) {
    v[k] = io::parse_double(reader, fields[first + static_cast<std::size_t>(k)], std::string(name) + kAxes[static_cast<std::size_t>(k)]);
  }
  return v;
}

std::vector<std::string_view> fields_of(const io::TextReader& reader, std::size_t expected, const char* layout) {
  auto fields = io::split_fields(reader.line(), ',');
  if (fields.size() != expected) {
    reader.fail("expected " + std::to_string(expected) + " comma-separated columns (" + layout + "), found " +
                std::to_string(fields.size()));
  }
  return fields;
}

void append_row_numbers(std::string& line, std::initializer_list<double> values) {
  for (const double v : values) {
    line += ',';
    io::append_number(line, v);
  }
}

// Refuses what a reader would refuse: empty, non-finite, stamps not increasing or out of range.
template <class Row, class Finite>
void check_writable(const std::string& path, const std::vector<Row>& rows, const char* what, Finite finite) {
  const std::string prefix = std::string("cannot write ") + what + ": ";
  if (rows.empty()) throw io::ParseError(path, 0, prefix + "no rows (readers refuse an empty file)");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const std::int64_t ns = rows[i].stamp.nanoseconds();
    if (ns < -kMaxAbsImuStampNs || ns > kMaxAbsImuStampNs) {
      throw io::ParseError(path, 0, prefix + "row " + std::to_string(i) + " has a stamp beyond +-9.2e9 s");
    }
    if (i > 0 && !(rows[i - 1].stamp < rows[i].stamp)) {
      throw io::ParseError(path, 0, prefix + "stamps must increase, row " + std::to_string(i) + " does not");
    }
    if (!finite(rows[i])) throw io::ParseError(path, 0, prefix + "row " + std::to_string(i) + " holds a non-finite value");
  }
}

}  // namespace

std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path) { return read_euroc_imu(path, nullptr); }

std::vector<ImuSample> read_euroc_imu(const std::filesystem::path& path, std::vector<std::string>* warnings) {
  io::TextReader reader(resolve_dataset_file(path, {"data.csv", "imu0/data.csv"}, "an IMU data.csv"));
  std::vector<ImuSample> samples;
  IncreasingStampCheck order;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto fields = fields_of(reader, 7, kImuLayout);
    ImuSample sample;
    sample.stamp = parse_stamp_ns(reader, fields[0], "the timestamp");
    sample.gyro_rad_s = parse_vector(reader, fields, 1, "w_RS_S");
    sample.accel_mps2 = parse_vector(reader, fields, 4, "a_RS_S");
    order.check(reader, sample.stamp);
    samples.push_back(sample);
  }
  if (samples.empty()) throw io::ParseError(reader.path(), 0, std::string("no IMU samples: expected lines of ") + kImuLayout);
  if (reader.last_line_unterminated() && warnings != nullptr) warnings->push_back(reader.unterminated_last_line_warning());
  return samples;
}

void write_euroc_imu(const std::filesystem::path& path, const std::vector<ImuSample>& samples) {
  check_writable(path.string(), samples, "EuRoC IMU data", [](const ImuSample& s) {
    return s.gyro_rad_s.allFinite() && s.accel_mps2.allFinite();
  });
  io::write_output(path.string(), [&](std::ostream& out) {
    out << kImuHeader << '\n';
    std::string line;
    for (const ImuSample& s : samples) {
      line = std::to_string(s.stamp.nanoseconds());
      append_row_numbers(line, {s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z(), s.accel_mps2.x(), s.accel_mps2.y(),
                                s.accel_mps2.z()});
      line += '\n';
      out << line;
    }
  });
}

std::vector<GroundTruthState> read_euroc_ground_truth(const std::filesystem::path& path) {
  io::TextReader reader(resolve_dataset_file(path, {"data.csv", "state_groundtruth_estimate0/data.csv"},
                                             "a state ground-truth CSV"));
  std::vector<GroundTruthState> states;
  IncreasingStampCheck order;
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto fields = fields_of(reader, 17, kGroundTruthLayout);
    GroundTruthState row;
    row.stamp = parse_stamp_ns(reader, fields[0], "the timestamp");
    const Vector3 p = parse_vector(reader, fields, 1, "p_RS_R");
    Quaternion q(io::parse_double(reader, fields[4], "q_RS_w"), io::parse_double(reader, fields[5], "q_RS_x"),
                 io::parse_double(reader, fields[6], "q_RS_y"), io::parse_double(reader, fields[7], "q_RS_z"));
    const double norm = q.norm();
    if (!(std::abs(norm - 1.0) <= kMaxQuaternionNormError)) {
      reader.fail("expected a unit quaternion q_RS (norm within 1e-2 of 1), found norm " + std::to_string(norm));
    }
    row.state.T_world_body = core::SE3(core::SO3(q), p);
    row.state.v_world_mps = parse_vector(reader, fields, 8, "v_RS_R");
    row.bias.gyro_rad_s = parse_vector(reader, fields, 11, "b_w_RS_S");
    row.bias.accel_mps2 = parse_vector(reader, fields, 14, "b_a_RS_S");
    order.check(reader, row.stamp);
    states.push_back(row);
  }
  if (states.empty()) {
    throw io::ParseError(reader.path(), 0, std::string("no ground-truth states: expected lines of ") + kGroundTruthLayout);
  }
  return states;
}

void write_euroc_ground_truth(const std::filesystem::path& path, const std::vector<GroundTruthState>& states) {
  check_writable(path.string(), states, "EuRoC ground truth", [](const GroundTruthState& s) {
    return s.state.T_world_body.translation().allFinite() && s.state.v_world_mps.allFinite() &&
           s.bias.gyro_rad_s.allFinite() && s.bias.accel_mps2.allFinite();
  });
  io::write_output(path.string(), [&](std::ostream& out) {
    out << kGroundTruthHeader << '\n';
    std::string line;
    for (const GroundTruthState& s : states) {
      const Vector3& p = s.state.T_world_body.translation();
      const Quaternion& q = s.state.T_world_body.unit_quaternion();
      const Vector3& v = s.state.v_world_mps;
      const Vector3& bw = s.bias.gyro_rad_s;
      const Vector3& ba = s.bias.accel_mps2;
      line = std::to_string(s.stamp.nanoseconds());
      append_row_numbers(line, {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), v.x(), v.y(), v.z(), bw.x(), bw.y(),
                                bw.z(), ba.x(), ba.y(), ba.z()});
      line += '\n';
      out << line;
    }
  });
}

// ---------------------------------------------------------------------------------------------
// sensor.yaml

namespace {

std::size_t line_of(const YAML::Node& node) {
  return node.Mark().line >= 0 ? static_cast<std::size_t>(node.Mark().line + 1) : 0;
}

struct YamlFile {
  std::string name;
  YAML::Node root;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& detail) const {
    throw io::ParseError(name, line_of(node), detail);
  }

  // A finite number under `key` (its line in errors); `positive`: also > 0.
  double number(const YAML::Node& node, const std::string& key, bool positive) const {
    double value = 0.0;
    try {
      if (!node.IsScalar()) fail(node, "\"" + key + "\": expected a number, found a list or map");
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      fail(node, "\"" + key + "\": expected a number, found \"" + node.Scalar().substr(0, 40) + "\"");
    }
    if (!std::isfinite(value) || (positive && !(value > 0.0))) {
      fail(node, "\"" + key + "\": expected a finite number" + (positive ? " > 0" : "") + ", found " + node.Scalar().substr(0, 40));
    }
    return value;
  }

  double required(const char* key, bool positive) const {
    const YAML::Node node = root[key];
    if (!node) throw io::ParseError(name, 0, std::string("missing key \"") + key + "\"");
    return number(node, key, positive);
  }
};

core::SE3 parse_T_BS(const YamlFile& file, const YAML::Node& node) {
  if (!node.IsMap()) file.fail(node, "\"T_BS\": expected a map {rows: 4, cols: 4, data: [16 numbers]}");
  for (const char* key : {"rows", "cols"}) {
    const YAML::Node size = node[key];
    if (!size) file.fail(node, std::string("\"T_BS\": missing \"") + key + "\" (expected 4)");
    if (file.number(size, std::string("T_BS.") + key, true) != 4.0) {
      file.fail(size, std::string("\"T_BS.") + key + "\": expected 4, found " + size.Scalar().substr(0, 40));
    }
  }
  const YAML::Node data = node["data"];
  if (!data || !data.IsSequence() || data.size() != 16) {
    file.fail(data ? data : node, "\"T_BS.data\": expected a list of 16 numbers (4x4, row-major)" +
                                      std::string(data && data.IsSequence() ? ", found " + std::to_string(data.size()) : ""));
  }
  Matrix4 T;
  for (std::size_t k = 0; k < 16; ++k) {
    T(static_cast<Eigen::Index>(k / 4), static_cast<Eigen::Index>(k % 4)) = file.number(data[k], "T_BS.data[" + std::to_string(k) + "]", false);
  }
  if (!((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= 1e-12)) {
    file.fail(data, "\"T_BS\": expected a rigid transform with last row 0 0 0 1");
  }
  const Matrix3 R = T.topLeftCorner<3, 3>();
  const double error = (R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff();
  if (!(error <= kMaxRotationError) || !(R.determinant() > 0.0)) {
    file.fail(data, "\"T_BS\": expected a rigid transform, but its rotation block is " +
                        std::string(error <= kMaxRotationError ? "a reflection (det < 0)"
                                                               : "not orthonormal (|R^T R - I| = " + std::to_string(error) + ")"));
  }
  return core::SE3(core::SO3::from_matrix(R), T.topRightCorner<3, 1>());
}

// The YAML document of `file_path` (at most kMaxCalibrationBytes), its syntax errors with their line.
YamlFile load_yaml_file(const std::string& file_path) {
  const std::string text = io::read_maybe_compressed(file_path, kMaxCalibrationBytes);
  YamlFile file{file_path == "-" ? "standard input" : file_path, {}};
  try {
    file.root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw io::ParseError(file.name, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line + 1) : 0, "not valid YAML: " + e.msg);
  }
  return file;
}

}  // namespace

core::SE3 read_euroc_T_BS(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::path file_path = std::filesystem::is_directory(path, error) ? path / "sensor.yaml" : path;
  if (!std::filesystem::is_regular_file(file_path, error)) {
    throw io::ParseError(file_path.string(), 0, "expected a sensor.yaml with T_BS (the sensor in the body frame), found no such file");
  }
  const YamlFile file = load_yaml_file(file_path.string());
  if (!file.root.IsMap() || !file.root["T_BS"]) {
    throw io::ParseError(file.name, 0, "expected a key \"T_BS\" (the sensor in the body frame, EuRoC's sensor.yaml), found none");
  }
  return parse_T_BS(file, file.root["T_BS"]);
}

ImuCalibration read_euroc_imu_calibration(const std::filesystem::path& path) {
  const std::string file_path = resolve_dataset_file(path, {"sensor.yaml", "imu0/sensor.yaml"}, "an IMU sensor.yaml");
  YamlFile file = load_yaml_file(file_path);
  if (!file.root.IsMap()) {
    throw io::ParseError(file.name, 0, "expected a YAML map of IMU keys (gyroscope_noise_density, ..., T_BS)");
  }
  ImuCalibration calibration;
  calibration.noise.gyro_noise_density = file.required("gyroscope_noise_density", true);
  calibration.noise.gyro_random_walk = file.required("gyroscope_random_walk", true);
  calibration.noise.accel_noise_density = file.required("accelerometer_noise_density", true);
  calibration.noise.accel_random_walk = file.required("accelerometer_random_walk", true);
  if (file.root["rate_hz"]) {
    calibration.rate_hz = file.required("rate_hz", true);
  } else if (file.root["update_rate"]) {
    calibration.rate_hz = file.required("update_rate", true);
  } else {
    throw io::ParseError(file.name, 0, "missing key \"rate_hz\" (EuRoC; Kalibr's \"update_rate\" is accepted too)");
  }
  if (const YAML::Node T = file.root["T_BS"]) calibration.T_body_imu = parse_T_BS(file, T);
  return calibration;
}

void write_euroc_imu_calibration(const std::filesystem::path& path, const ImuCalibration& calibration) {
  std::string why;
  if (!calibration.noise.is_valid(&why) || !(std::isfinite(calibration.rate_hz) && calibration.rate_hz > 0.0) ||
      !calibration.T_body_imu.translation().allFinite()) {
    throw io::ParseError(path.string(), 0,
                         "cannot write an IMU sensor.yaml: " + (why.empty() ? "rate_hz and T_BS must be finite, rate > 0" : why));
  }
  std::string text = "%YAML:1.0\nsensor_type: imu\ncomment: written by cairn\n\n# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [";
  const Matrix4 T = calibration.T_body_imu.matrix();
  for (int k = 0; k < 16; ++k) {
    if (k > 0) text += k % 4 == 0 ? ",\n         " : ", ";
    io::append_number(text, T(k / 4, k % 4));
  }
  text += "]\nrate_hz: ";
  io::append_number(text, calibration.rate_hz);
  const auto key = [&](const char* name, double value, const char* unit) {
    text += std::string("\n") + name + ": ";
    io::append_number(text, value);
    text += std::string("  # [ ") + unit + " ]";
  };
  text += "\n\n# inertial sensor noise model parameters (static)";
  key("gyroscope_noise_density", calibration.noise.gyro_noise_density, "rad / s / sqrt(Hz)");
  key("gyroscope_random_walk", calibration.noise.gyro_random_walk, "rad / s^2 / sqrt(Hz)");
  key("accelerometer_noise_density", calibration.noise.accel_noise_density, "m / s^2 / sqrt(Hz)");
  key("accelerometer_random_walk", calibration.noise.accel_random_walk, "m / s^3 / sqrt(Hz)");
  text += '\n';
  io::write_output(path.string(), [&](std::ostream& out) { out << text; });
}

}  // namespace cairn::inertial
