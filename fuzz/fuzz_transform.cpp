// libFuzzer entry point for the rigid-transform reader (io/transform_file.hpp, `cairn register
// --guess`). Any input must end in a rigid transform with finite entries and an orthonormal
// rotation, or a cairn::io::ParseError. The corpus in fuzz/corpus/transform runs in `make test`.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/transform_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const cairn::core::SE3 T =
        cairn::io::parse_transform("fuzz.txt", std::string(reinterpret_cast<const char*>(data), size));
    const cairn::Matrix3 R = T.rotation_matrix();
    if (!T.matrix().allFinite() || !(R.transpose() * R - cairn::Matrix3::Identity()).isZero(1e-9)) std::abort();
  } catch (const cairn::io::ParseError&) {
    // Expected for malformed input.
  }
  return 0;
}
