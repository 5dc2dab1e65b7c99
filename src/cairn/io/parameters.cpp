#include "cairn/io/parameters.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "cairn/io/input_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {
namespace {

template <typename Integer>
bool parse_integer(const std::string& text, Integer* target) {
  Integer v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size()) return false;
  *target = v;
  return true;
}

}  // namespace

bool parse_parameter(const std::string& text, Parameter& parameter) {
  if (auto* d = std::get_if<double*>(&parameter.value)) {
    double v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return false;
    **d = v;
    return true;
  }
  if (auto* i = std::get_if<int*>(&parameter.value)) return parse_integer(text, *i);
  if (auto* n = std::get_if<std::size_t*>(&parameter.value)) return parse_integer(text, *n);
  if (auto* choice = std::get_if<Choice>(&parameter.value)) {
    if (std::find(choice->words.begin(), choice->words.end(), text) == choice->words.end()) return false;
    choice->set(text);
    return true;
  }
  bool* b = std::get<bool*>(parameter.value);
  if (text == "true") *b = true;
  else if (text == "false") *b = false;
  else return false;
  return true;
}

std::string expected_value(const Parameter& parameter) {
  if (std::holds_alternative<double*>(parameter.value)) return "a finite number";
  if (std::holds_alternative<int*>(parameter.value)) return "an integer";
  if (std::holds_alternative<std::size_t*>(parameter.value)) return "a whole number >= 0";
  if (const auto* choice = std::get_if<Choice>(&parameter.value)) {
    std::string words;
    for (const std::string& w : choice->words) words += (words.empty() ? "" : ", ") + w;
    return "one of " + words;
  }
  return "true or false";
}

std::string parameter_text(const Parameter& parameter) {
  std::string value;
  if (auto* d = std::get_if<double*>(&parameter.value)) append_number(value, **d);
  else if (auto* i = std::get_if<int*>(&parameter.value)) value = std::to_string(**i);
  else if (auto* n = std::get_if<std::size_t*>(&parameter.value)) value = std::to_string(**n);
  else if (auto* choice = std::get_if<Choice>(&parameter.value)) value = choice->get();
  else value = *std::get<bool*>(parameter.value) ? "true" : "false";
  return value;
}

void set_parameter(Parameters& parameters, const std::string& assignment, std::string_view command) {
  const auto eq = assignment.find('=');
  if (eq == std::string::npos) throw std::invalid_argument("--set expects section.key=value, got '" + assignment + "'");
  const std::string name = assignment.substr(0, eq);
  const std::string value = assignment.substr(eq + 1);
  for (Parameter& parameter : parameters) {
    if (parameter.full() != name) continue;
    if (!parse_parameter(value, parameter))
      throw std::invalid_argument("--set " + name + ": expected " + expected_value(parameter) + ", got '" + value + "'");
    return;
  }
  throw std::invalid_argument("--set: unknown key '" + name + "' (cairn " + std::string(command) +
                              " --print-config lists them)");
}

void load_parameters(Parameters& parameters, const std::string& path, std::string_view command) {
  check_input_file(path, "a YAML configuration file");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ParseError(path, 0, "cannot open the configuration file");
  } catch (const YAML::Exception& e) {
    throw ParseError(path, static_cast<std::size_t>(e.mark.line + 1), "YAML syntax error: " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw ParseError(path, static_cast<std::size_t>(root.Mark().line + 1), "expected a map of sections");
  for (const auto& section : root) {
    const std::string section_name = section.first.as<std::string>();
    const auto line = static_cast<std::size_t>(section.first.Mark().line + 1);
    if (!section.second.IsMap()) throw ParseError(path, line, "section '" + section_name + "' must be a map of keys");
    for (const auto& entry : section.second) {
      const std::string name = section_name + "." + entry.first.as<std::string>();
      const auto entry_line = static_cast<std::size_t>(entry.first.Mark().line + 1);
      auto it = std::find_if(parameters.begin(), parameters.end(), [&](const Parameter& p) { return p.full() == name; });
      if (it == parameters.end()) {
        throw ParseError(path, entry_line,
                         "unknown key '" + name + "' (cairn " + std::string(command) + " --print-config lists them)");
      }
      if (!entry.second.IsScalar() || !parse_parameter(entry.second.Scalar(), *it))
        throw ParseError(path, entry_line, "'" + name + "' expects " + expected_value(*it));
    }
  }
}

std::string parameters_yaml(const Parameters& parameters, std::string_view header) {
  std::ostringstream out;
  out << header << '\n';
  std::string section;
  for (const Parameter& parameter : parameters) {
    if (parameter.section != section) {
      section = parameter.section;
      out << section << ":\n";
    }
    out << "  " << parameter.name << ": " << parameter_text(parameter) << "  # " << parameter.doc << '\n';
  }
  return out.str();
}

nlohmann::json parameters_json(const Parameters& parameters) {
  nlohmann::json j = nlohmann::json::object();
  for (const Parameter& parameter : parameters) {
    nlohmann::json& slot = j[parameter.section][parameter.name];
    if (auto* d = std::get_if<double*>(&parameter.value)) slot = **d;
    else if (auto* i = std::get_if<int*>(&parameter.value)) slot = **i;
    else if (auto* n = std::get_if<std::size_t*>(&parameter.value)) slot = **n;
    else if (auto* choice = std::get_if<Choice>(&parameter.value)) slot = choice->get();
    else slot = *std::get<bool*>(parameter.value);
  }
  return j;
}

}  // namespace cairn::io
