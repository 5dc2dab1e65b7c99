// libFuzzer entry point for the landmark CSV readers of `cairn landmarks`
// (io/landmark_csv.hpp): landmark_observations.csv (with and without a landmark map to
// check ids against) and landmarks.csv. Any input must end in a result or a
// cairn::io::ParseError; another exception, a crash, a hang or a sanitizer report is a bug. What
// is accepted holds finite numbers, ranges > 0, bearings in [-pi, pi] and times that never go
// back. Run with `make fuzz` (clang); the corpus in fuzz/corpus/landmarks runs in `make test`.

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <string>
#include <system_error>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/landmark_csv.hpp"

namespace {

std::string scratch_path() {
  static const std::string path = [] {
    const std::string p =
        (std::filesystem::temp_directory_path() / ("cairn_fuzz_landmarks_" + std::to_string(::getpid()) + ".csv")).string();
    std::atexit([] {
      std::error_code ignored;
      std::filesystem::remove(
          std::filesystem::temp_directory_path() / ("cairn_fuzz_landmarks_" + std::to_string(::getpid()) + ".csv"), ignored);
    });
    return p;
  }();
  return path;
}

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_landmarks: invariant broken: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = scratch_path();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    check(static_cast<bool>(out), "the scratch file can be written");
  }
  static const std::map<std::int64_t, Eigen::Vector2d> known{{0, {1.0, 2.0}}, {1, {3.0, 4.0}}, {7, {5.0, 6.0}}};
  for (const auto* ids : {static_cast<const std::map<std::int64_t, Eigen::Vector2d>*>(nullptr), &known}) {
    try {
      const auto observations = cairn::io::read_landmark_observations(path, ids);
      for (std::size_t i = 0; i < observations.size(); ++i) {
        const auto& o = observations[i];
        check(std::isfinite(o.range_m) && o.range_m > 0.0, "ranges are finite and > 0");
        check(std::abs(o.bearing_rad) <= std::numbers::pi + 1e-9, "bearings lie in [-pi, pi]");
        check(i == 0 || !(o.time < observations[i - 1].time), "times never go back");
        check(ids == nullptr || ids->count(o.landmark_id) == 1, "ids are in the map");
      }
    } catch (const cairn::io::ParseError&) {
    }
  }
  try {
    for (const auto& [id, p] : cairn::io::read_landmark_map(path)) {
      check(id >= 0 && p.allFinite(), "landmarks have ids >= 0 and finite positions");
    }
  } catch (const cairn::io::ParseError&) {
  }
  return 0;
}
