#pragma once
/// \file
/// One description of a pipeline's options, used for everything that names them: `--set
/// section.key=value`, a YAML configuration file, `--print-config` (docs/configuration.md is its
/// output), and report.json's "options". Each pipeline lists its keys once, as pointers into its
/// Options struct with a section, a name and what the key means (slam2d/config.cpp,
/// lidar3d/config.cpp, vslam/config.cpp); nothing else copies options field by field.
///
///   io::Parameters keys = parameters(options);      // pointers into `options`
///   io::set_parameter(keys, "icp.max_iterations=20", "slam2d");
///   nlohmann::json j = io::parameters_json(keys);   // {"icp": {"max_iterations": 20, ...}, ...}

#include <cstddef>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

namespace cairn::io {

/// A key whose value is one of a few words (an enum): read and written through the two functions.
struct Choice {
  std::vector<std::string> words;
  std::function<std::string()> get;
  std::function<void(const std::string&)> set;  ///< called only with one of `words`
};

struct Parameter {
  std::string section;
  std::string name;
  std::variant<double*, int*, bool*, std::size_t*, Choice> value;
  std::string doc;
  std::string full() const { return section + "." + name; }
};
using Parameters = std::vector<Parameter>;

/// Parses `text` into the parameter. False (the value unchanged) when it is not a finite number,
/// a whole number in range, true/false, or one of the words, as the parameter's type asks.
bool parse_parameter(const std::string& text, Parameter& parameter);
/// "a finite number", "an integer", "a whole number >= 0", "true or false", "one of a, b".
std::string expected_value(const Parameter& parameter);
/// The value as text: numbers shortest round-trip (io::append_number), booleans true/false.
std::string parameter_text(const Parameter& parameter);

/// "section.key=value". Throws std::invalid_argument on a malformed assignment, an unknown key
/// (naming `cairn <command> --print-config`) or a bad value.
void set_parameter(Parameters& parameters, const std::string& assignment, std::string_view command);
/// Reads the YAML file at `path` (a map of sections, each a map of keys) into the parameters;
/// keys absent from the file keep their value. Throws io::ParseError naming the file and line on a
/// syntax error, an unknown key or a wrong type.
void load_parameters(Parameters& parameters, const std::string& path, std::string_view command);
/// Every key with its value and a comment saying what it means, after `header` (a comment line).
std::string parameters_yaml(const Parameters& parameters, std::string_view header);
/// {section: {key: value}}: numbers as numbers, booleans as booleans, choices as their word.
nlohmann::json parameters_json(const Parameters& parameters);

/// A pipeline's configuration: the function that describes its Options (`parameters(Options&)`),
/// the command that names the keys in messages, and the comment line that --print-config starts
/// with. The four operations every pipeline offers, written once:
///
///   const io::Configuration<LidarSlamOptions>& c = lidar3d::configuration();
///   c.load("slam3d.yaml", options); c.set("odometry.voxel_size_m=0.5", options);
///   std::cout << c.yaml(options);   report["options"] = c.json(options);
template <class Options>
class Configuration {
 public:
  using Describe = Parameters (*)(Options&);
  Configuration(Describe describe, std::string command, std::string header)
      : describe_(describe), command_(std::move(command)), header_(std::move(header)) {}

  /// "section.key=value" (set_parameter).
  void set(const std::string& assignment, Options& options) const {
    Parameters keys = describe_(options);
    set_parameter(keys, assignment, command_);
  }
  /// A YAML file over `options` (load_parameters).
  void load(const std::string& path, Options& options) const {
    Parameters keys = describe_(options);
    load_parameters(keys, path, command_);
  }
  /// Every key with its value and meaning (--print-config).
  std::string yaml(const Options& options) const {
    Options copy = options;
    return parameters_yaml(describe_(copy), header_);
  }
  /// {section: {key: value}} (report.json's "options").
  nlohmann::json json(const Options& options) const {
    Options copy = options;
    return parameters_json(describe_(copy));
  }

 private:
  Describe describe_;
  std::string command_;
  std::string header_;
};

}  // namespace cairn::io
