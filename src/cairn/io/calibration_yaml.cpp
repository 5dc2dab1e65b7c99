#include "cairn/io/calibration_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <stdexcept>
#include <utility>
#include <vector>

#include "cairn/io/compressed_file.hpp"
#include "cairn/io/input_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

// A calibration is a handful of keys: a larger file is not one (and YAML's parser would build
// a tree of it in memory first).
constexpr std::size_t kMaxCalibrationBytes = std::size_t{1} << 20;

std::size_t line_of(const YAML::Node& node) { return node.Mark().line >= 0 ? static_cast<std::size_t>(node.Mark().line + 1) : 0; }

}  // namespace

CameraCalibration parse_calibration_yaml(const std::string& name, const std::string& text) {
  if (text.size() > kMaxCalibrationBytes) {
    throw ParseError(name, 0, "is " + std::to_string(text.size()) + " bytes: expected a calibration YAML of a few keys (at most 1 MiB)");
  }
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ParseError(name, e.mark.line >= 0 ? static_cast<std::size_t>(e.mark.line + 1) : 0, "not valid YAML: " + e.msg);
  }
  if (!root.IsMap()) throw ParseError(name, 0, "expected a YAML map of calibration keys (fx, fy, cx, cy, ...)");
  CameraCalibration c;
  const std::vector<std::pair<const char*, double*>> keys{
      {"fx", &c.fx}, {"fy", &c.fy}, {"cx", &c.cx}, {"cy", &c.cy}, {"k1", &c.k1}, {"k2", &c.k2}, {"p1", &c.p1}, {"p2", &c.p2},
      {"k3", &c.k3}, {"baseline_m", &c.baseline_m}, {"depth_units_per_m", &c.depth_units_per_m},
      {"virtual_baseline_m", &c.virtual_baseline_m}};
  std::vector<std::string> seen;
  for (const auto& entry : root) {
    const std::size_t line = line_of(entry.first);
    if (!entry.first.IsScalar()) throw ParseError(name, line, "expected a key name (fx, fy, ...), found a list or map as a key");
    const std::string key = entry.first.Scalar();
    if (std::find(seen.begin(), seen.end(), key) != seen.end()) throw ParseError(name, line, "key \"" + key + "\" given twice");
    seen.push_back(key);
    auto it = std::find_if(keys.begin(), keys.end(), [&](const auto& k) { return key == k.first; });
    if (it == keys.end() && key != "width" && key != "height") {
      throw ParseError(name, line,
                       "unknown key \"" + key +
                           "\" (expected fx, fy, cx, cy, k1, k2, p1, p2, k3, width, height, baseline_m, depth_units_per_m, "
                           "virtual_baseline_m)");
    }
    try {
      if (!entry.second.IsScalar()) throw YAML::Exception(entry.second.Mark(), "not a scalar");
      if (it != keys.end()) *it->second = entry.second.as<double>();
      else if (key == "width") c.width = entry.second.as<int>();
      else c.height = entry.second.as<int>();
    } catch (const YAML::Exception&) {
      throw ParseError(name, line, "\"" + key + "\" must be a number" + (key == "width" || key == "height" ? " of pixels (a whole number)" : ""));
    }
  }
  for (const char* required : {"fx", "fy", "cx", "cy"}) {
    if (std::find(seen.begin(), seen.end(), required) == seen.end()) {
      throw ParseError(name, 0, std::string("missing required key \"") + required + "\"");
    }
  }
  if (std::string p; !c.is_valid(&p)) throw ParseError(name, 0, p);
  return c;
}

CameraCalibration read_calibration_yaml(const std::string& path) {
  check_input_file(path, "a calibration YAML file");
  return parse_calibration_yaml(path == "-" ? "standard input" : path, read_maybe_compressed(path, kMaxCalibrationBytes));
}

CameraCalibration tum_calibration_preset(const std::string& name) {
  CameraCalibration c;
  if (name == "tum-fr1") {
    c = {517.306408, 516.469215, 318.643040, 255.313989, 0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  } else if (name == "tum-fr2") {
    c = {520.908620, 521.007327, 325.141442, 249.701764, 0.231222, -0.784899, -0.003257, -0.000105, 0.917205};
  } else if (name == "tum-fr3") {
    c = {535.4, 539.2, 320.1, 247.6};
  } else {
    throw std::invalid_argument("--camera must be tum-fr1, tum-fr2 or tum-fr3 (or give --calib FILE)");
  }
  c.width = 640;
  c.height = 480;
  c.depth_units_per_m = 5000.0;
  c.virtual_baseline_m = 40.0 / c.fx;
  return c;
}

}  // namespace cairn::io
