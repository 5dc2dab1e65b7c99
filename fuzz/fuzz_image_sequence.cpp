// libFuzzer entry point for the image-sequence readers (io/image_sequence.hpp) and the image
// decoders behind cairn vslam (libpng / libjpeg, vision/image_file.hpp, and vision/features.hpp).
// Any input must give a result or a cairn::io::ParseError: as a KITTI calib.txt, as an EuRoC
// sensor.yaml, as a TUM image list, as a TUM associations file in a scratch folder, and as an
// image file (grey and 16-bit depth); decoded from memory, a result or a
// cairn::vision::ImageFileError. Another exception, a crash, a hang or a sanitizer report is a
// bug. Run with `make fuzz` (clang); the corpus in fuzz/corpus/image_sequence (PNGs of several
// kinds, JPEGs, broken ones) runs in `make test`.

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/image_file.hpp"

namespace {

namespace fs = std::filesystem;

const fs::path& scratch() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("cairn_fuzz_image_sequence_" + std::to_string(::getpid()));
    fs::create_directories(d / "tum");
    std::atexit([] {
      std::error_code ignored;
      fs::remove_all(fs::temp_directory_path() / ("cairn_fuzz_image_sequence_" + std::to_string(::getpid())), ignored);
    });
    return d;
  }();
  return dir;
}

void write_bytes(const fs::path& path, const char* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz_image_sequence: cannot write scratch file %s\n", path.c_str());
    std::abort();
  }
}

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_image_sequence: invariant broken: %s\n", what);
  std::abort();
}

template <class F>
void expect_result_or_parse_error(F f) {
  try {
    f();
  } catch (const cairn::io::ParseError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const char* bytes = reinterpret_cast<const char*>(data);
  const fs::path calib = scratch() / "calib.txt";
  write_bytes(calib, bytes, size);
  expect_result_or_parse_error([&] {
    const cairn::io::CameraCalibration c = cairn::io::read_kitti_calibration(calib.string());
    check(c.fx > 0.0 && c.fy > 0.0 && c.baseline_m > 0.0 && std::isfinite(c.baseline_m), "an accepted calibration is usable");
  });
  expect_result_or_parse_error([&] {
    cairn::core::SE3 T_body_camera;
    const cairn::io::CameraCalibration c = cairn::io::read_euroc_camera(calib.string(), &T_body_camera);
    check(c.fx > 0.0 && c.fy > 0.0 && T_body_camera.translation().allFinite(), "an accepted EuRoC camera is usable");
  });
  expect_result_or_parse_error([&] {
    const auto list = cairn::io::read_tum_image_list(calib.string());
    check(!list.empty(), "an accepted list has images");
    for (std::size_t i = 1; i < list.size(); ++i) check(list[i - 1].first < list[i].first, "stamps increase");
  });
  const fs::path tum = scratch() / "tum";
  write_bytes(tum / "associations.txt", bytes, size);
  expect_result_or_parse_error([&] {
    const cairn::io::ImageSequence seq = cairn::io::read_tum_rgbd(tum.string());
    check(!seq.frames.empty(), "an accepted sequence has frames");
  });
  for (const cairn::vision::ImageMode mode : {cairn::vision::ImageMode::kGray8, cairn::vision::ImageMode::kUnchanged}) {
    try {
      const cv::Mat decoded = cairn::vision::decode_image(data, size, mode, "fuzz input");
      check(!decoded.empty() && decoded.total() <= cairn::vision::kMaxImagePixels, "a decoded image has pixels, within the limit");
      check(mode == cairn::vision::ImageMode::kUnchanged || decoded.type() == CV_8UC1, "a grey decode is 8-bit, one channel");
    } catch (const cairn::vision::ImageFileError&) {
    }
  }
  const fs::path image = scratch() / "image.png";
  write_bytes(image, bytes, size);
  expect_result_or_parse_error([&] { check(!cairn::vision::read_gray_image(image.string()).empty(), "a decoded image has pixels"); });
  expect_result_or_parse_error([&] { check(!cairn::vision::read_depth_image(image.string()).empty(), "a decoded depth image has pixels"); });
  return 0;
}
