// The helpers the pipeline bindings share (pipeline_support.hpp).

#include "pipeline_support.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace cairn::python {

/// A str or os.PathLike as the path string the readers take.
std::string fspath(const py::handle& path) {
  return py::str(py::module_::import("os").attr("fspath")(path)).cast<std::string>();
}

double finite_or_throw(double value, const char* what) {
  if (!std::isfinite(value)) throw_value_error(std::string(what) + ": not a finite number");
  return value;
}

/// Seconds as core::Timestamp (from_seconds' precondition checked: finite, within +-9.2e9 s).
core::Timestamp timestamp_of(double seconds, const char* what) {
  if (!(std::abs(seconds) < 9.2e9)) throw_value_error(std::string(what) + ": expected finite seconds within +-9.2e9");
  return core::Timestamp::from_seconds(seconds);
}

py::array_t<double> matrix_to_array(const Matrix4& T) {
  py::array_t<double> out({py::ssize_t{4}, py::ssize_t{4}});
  auto view = out.mutable_unchecked<2>();
  for (py::ssize_t r = 0; r < 4; ++r) {
    for (py::ssize_t c = 0; c < 4; ++c) view(r, c) = T(r, c);
  }
  return out;
}

py::array_t<std::int64_t> indices_to_array(const std::vector<std::size_t>& indices) {
  py::array_t<std::int64_t> out(static_cast<py::ssize_t>(indices.size()));
  auto view = out.mutable_unchecked<1>();
  for (std::size_t k = 0; k < indices.size(); ++k) view(static_cast<py::ssize_t>(k)) = static_cast<std::int64_t>(indices[k]);
  return out;
}

std::string health_word(core::Health health) { return std::string(core::to_string(health)); }

/// A `set` value as the text of `--set key=value`: booleans true/false (Python prints True),
/// numbers shortest round trip, sequences space-separated (scan_context.lateral_offsets_m).
std::string setting_text(const std::string& key, const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  const py::module_ numbers = py::module_::import("numbers");
  if (py::isinstance(value, numbers.attr("Integral"))) return py::str(py::int_(py::reinterpret_borrow<py::object>(value)));
  if (py::isinstance(value, numbers.attr("Real"))) return py::repr(py::float_(py::reinterpret_borrow<py::object>(value)));
  if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
    std::string text;
    for (const py::handle item : value) text += (text.empty() ? "" : " ") + setting_text(key, item);
    return text;
  }
  throw_value_error("set['" + key + "']: expected a bool, number, string or list of numbers, found " +
                    py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>());
}

}  // namespace cairn::python
