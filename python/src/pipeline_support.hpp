#pragma once
/// \file
/// What the pipeline bindings (lidar3d.cpp, slam2d.cpp, vslam.cpp) share: paths, numbers and
/// times from Python, poses and indices as arrays, health words, the configuration from a file and
/// `set` as the commands make it, and `locked`: the GIL is released while a pipeline works; each
/// pipeline object serialises its own calls with a mutex, taken without the GIL (a thread waiting
/// for it must not hold up the others), so Python threads may share one.

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "cairn/core/health.hpp"
#include "cairn/core/time.hpp"
#include "cairn/io/parameters.hpp"

namespace cairn::python {

/// A str or os.PathLike as the path string the readers take.
std::string fspath(const py::handle& path);

/// `value`; ValueError naming `what` when it is not finite.
double finite_or_throw(double value, const char* what);

/// Seconds as core::Timestamp (from_seconds' precondition checked: finite, within +-9.2e9 s).
core::Timestamp timestamp_of(double seconds, const char* what);

/// One 4 x 4 matrix as a 4 x 4 float64 array.
py::array_t<double> matrix_to_array(const Matrix4& T);

/// Indices as a 1-D int64 array.
py::array_t<std::int64_t> indices_to_array(const std::vector<std::size_t>& indices);

/// 'ok', 'degraded' or 'lost'.
std::string health_word(core::Health health);

/// A `set` value as the text of `--set key=value`: booleans true/false (Python prints True),
/// numbers shortest round trip, sequences space-separated (scan_context.lateral_offsets_m).
std::string setting_text(const std::string& key, const py::handle& value);

/// The configuration file, then each key of `set` in order: `cairn <command> --config FILE --set
/// key=value ...`. Unknown keys and bad values raise ValueError naming the key (io::set_parameter),
/// a bad file cairn.ParseError.
template <class Options>
void apply_configuration(const io::Configuration<Options>& configuration, Options& options, const py::object& config,
                         const py::object& set) {
  if (!config.is_none()) configuration.load(fspath(config), options);
  if (set.is_none()) return;
  if (!py::isinstance<py::dict>(set)) throw py::type_error("set: expected a dict of key -> value");
  for (const auto& [key, value] : set.cast<py::dict>()) {
    const std::string name = py::str(key).cast<std::string>();
    configuration.set(name + "=" + setting_text(name, value), options);
  }
}

/// Runs `work` without the GIL and under `mutex`; what it returns is C++ data, converted after.
template <class Work>
auto locked(std::mutex& mutex, Work&& work) {
  const py::gil_scoped_release release;
  const std::lock_guard<std::mutex> lock(mutex);
  return work();
}

}  // namespace cairn::python
