#include "cairn/lidar3d/sensor_extrinsic.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <string>

#include "cairn/core/types.hpp"
#include "cairn/io/compressed_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::lidar3d {
namespace {

// A sensor.yaml is a handful of keys (and yaml-cpp builds its tree in memory first).
constexpr std::size_t kMaxBytes = std::size_t{1} << 20;
// EuRoC's extrinsics, printed with 16 digits, are 1e-8 from orthonormal; 1e-6 off is not a rotation.
constexpr double kMaxRotationError = 1e-6;

std::size_t line_of(const YAML::Node& node) {
  return node.Mark().line >= 0 ? static_cast<std::size_t>(node.Mark().line + 1) : 0;
}

double number_of(const std::string& file, const YAML::Node& node, const std::string& key) {
  double value = 0.0;
  try {
    if (!node.IsScalar()) throw io::ParseError(file, line_of(node), "\"" + key + "\": expected a number, found a list or map");
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    throw io::ParseError(file, line_of(node), "\"" + key + "\": expected a number, found \"" + node.Scalar().substr(0, 40) + "\"");
  }
  if (!std::isfinite(value)) {
    throw io::ParseError(file, line_of(node), "\"" + key + "\": expected a finite number, found " + node.Scalar().substr(0, 40));
  }
  return value;
}

Matrix4 matrix_of(const std::string& file, const YAML::Node& node) {
  if (!node.IsMap()) throw io::ParseError(file, line_of(node), "\"T_BS\": expected a map {rows: 4, cols: 4, data: [16 numbers]}");
  for (const char* key : {"rows", "cols"}) {
    const YAML::Node size = node[key];
    if (!size) throw io::ParseError(file, line_of(node), std::string("\"T_BS\": missing \"") + key + "\" (expected 4)");
    if (number_of(file, size, std::string("T_BS.") + key) != 4.0) {
      throw io::ParseError(file, line_of(size), std::string("\"T_BS.") + key + "\": expected 4, found " + size.Scalar().substr(0, 40));
    }
  }
  const YAML::Node data = node["data"];
  if (!data || !data.IsSequence() || data.size() != 16) {
    throw io::ParseError(file, line_of(data ? data : node),
                         "\"T_BS.data\": expected a list of 16 numbers (4x4, row-major)" +
                             std::string(data && data.IsSequence() ? ", found " + std::to_string(data.size()) : ""));
  }
  Matrix4 T;
  for (std::size_t k = 0; k < 16; ++k) {
    T(static_cast<Eigen::Index>(k / 4), static_cast<Eigen::Index>(k % 4)) =
        number_of(file, data[k], "T_BS.data[" + std::to_string(k) + "]");
  }
  return T;
}

}  // namespace

core::SE3 read_sensor_extrinsic(const std::filesystem::path& path) {
  std::error_code error;
  const std::filesystem::path file_path = std::filesystem::is_directory(path, error) ? path / "sensor.yaml" : path;
  const std::string file = file_path.string();
  if (!std::filesystem::is_regular_file(file_path, error)) {
    throw io::ParseError(file, 0, "expected a sensor.yaml with T_BS (the sensor in the body frame), found no such file");
  }
  const std::string text = io::read_maybe_compressed(file, kMaxBytes);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw io::ParseError(file, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line + 1) : 0, "not valid YAML: " + e.msg);
  }
  if (!root.IsMap() || !root["T_BS"]) {
    throw io::ParseError(file, 0, "expected a key \"T_BS\" (the sensor in the body frame, EuRoC's sensor.yaml), found none");
  }
  const Matrix4 T = matrix_of(file, root["T_BS"]);
  const std::size_t line = line_of(root["T_BS"]["data"]);
  if (!((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() <= 1e-12)) {
    throw io::ParseError(file, line, "\"T_BS\": expected a rigid transform with last row 0 0 0 1");
  }
  const Matrix3 R = T.topLeftCorner<3, 3>();
  const double rotation_error = (R.transpose() * R - Matrix3::Identity()).cwiseAbs().maxCoeff();
  if (!(rotation_error <= kMaxRotationError) || !(R.determinant() > 0.0)) {
    throw io::ParseError(file, line,
                         "\"T_BS\": expected a rigid transform, but its rotation block is " +
                             std::string(rotation_error <= kMaxRotationError
                                             ? "a reflection (det < 0)"
                                             : "not orthonormal (|R^T R - I| = " + std::to_string(rotation_error) + ")"));
  }
  return core::SE3(core::SO3::from_matrix(R), T.topRightCorner<3, 1>());
}

}  // namespace cairn::lidar3d
