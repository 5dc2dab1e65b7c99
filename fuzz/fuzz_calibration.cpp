// libFuzzer entry point for the camera calibration YAML reader of `cairn vslam --calib`
// (io/calibration_yaml.hpp). Any input must end in a calibration or a cairn::io::ParseError:
// another exception (yaml-cpp's own, a bad conversion), a crash, a hang or a sanitizer report is
// a bug. A calibration it accepts has positive, finite focal lengths and finite coefficients.
// Run with `make fuzz` (clang); the corpus in fuzz/corpus/calibration runs in `make test`.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cairn/io/calibration_yaml.hpp"
#include "cairn/io/parse_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const cairn::io::CameraCalibration c = cairn::io::parse_calibration_yaml("fuzz.yaml", text);
    if (!(c.fx > 0.0 && c.fy > 0.0 && std::isfinite(c.fx) && std::isfinite(c.fy) && std::isfinite(c.cx) && std::isfinite(c.cy)) ||
        !c.is_valid(nullptr)) {
      std::fprintf(stderr, "fuzz_calibration: an accepted calibration is not usable\n");
      std::abort();
    }
    (void)c.implausibilities(640, 480, true);
  } catch (const cairn::io::ParseError&) {
  }
  return 0;
}
