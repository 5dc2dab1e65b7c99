// libFuzzer entry point for the IMU readers of cairn::inertial: EuRoC imu0/data.csv, the plain IMU
// CSV, read_imu_file's choice between them, imu0/sensor.yaml and the state ground truth. Any input
// must end in samples (states, a calibration) or a cairn::io::ParseError: another exception, a
// crash, a hang or a sanitizer report is a bug. What a reader accepts must survive its writer:
// written and read back it is the same, bit for bit (sensor.yaml's T_BS to 1e-12). Run with
// `make fuzz` (clang); the corpus in fuzz/corpus/imu runs in `make test`.

#include <unistd.h>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_csv.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

using cairn::inertial::GroundTruthState;
using cairn::inertial::ImuCalibration;
using cairn::inertial::ImuSample;

std::string prefix_for_cleanup() {
  return (std::filesystem::temp_directory_path() / ("cairn_fuzz_imu_" + std::to_string(::getpid()))).string();
}

// Scratch files, one set per process, reused for every input and removed at exit.
std::string scratch_path(const char* suffix) {
  static const std::string prefix = [] {
    std::atexit([] {
      std::error_code ignored;
      for (const char* s : {".input", ".copy"}) std::filesystem::remove(prefix_for_cleanup() + s, ignored);
    });
    return prefix_for_cleanup();
  }();
  return prefix + suffix;
}

void write_bytes(const std::string& path, const char* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz_imu: cannot write scratch file %s\n", path.c_str());
    std::abort();
  }
}

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_imu: invariant broken: %s\n", what);
  std::abort();
}

void check_samples(const std::vector<ImuSample>& samples) {
  check(!samples.empty(), "a successful read has samples");
  for (std::size_t i = 0; i < samples.size(); ++i) {
    check(samples[i].gyro_rad_s.allFinite() && samples[i].accel_mps2.allFinite(), "finite readings");
    check(i == 0 || samples[i - 1].stamp < samples[i].stamp, "stamps increase");
  }
}

bool same(const std::vector<ImuSample>& a, const std::vector<ImuSample>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].stamp != b[i].stamp || a[i].gyro_rad_s != b[i].gyro_rad_s || a[i].accel_mps2 != b[i].accel_mps2) return false;
  }
  return true;
}

// Writers may not refuse what a reader accepted: their exceptions propagate (a bug).
void round_trip(const std::vector<ImuSample>& samples) {
  static const std::string copy = scratch_path(".copy");
  check_samples(samples);
  cairn::inertial::write_euroc_imu(copy, samples);
  check(same(samples, cairn::inertial::read_euroc_imu(copy)), "EuRoC IMU round trip is exact");
  cairn::inertial::write_imu_csv(copy, samples);
  check(same(samples, cairn::inertial::read_imu_csv(copy)), "plain IMU CSV round trip is exact");
}

void round_trip(const std::vector<GroundTruthState>& states) {
  static const std::string copy = scratch_path(".copy");
  check(!states.empty(), "a successful read has states");
  cairn::inertial::write_euroc_ground_truth(copy, states);
  const auto back = cairn::inertial::read_euroc_ground_truth(copy);
  check(back.size() == states.size(), "ground-truth round trip keeps the count");
  for (std::size_t i = 0; i < states.size(); ++i) {
    check(back[i].stamp == states[i].stamp, "ground-truth round trip keeps stamps");
    check(back[i].state.T_world_body.translation() == states[i].state.T_world_body.translation() &&
              back[i].state.T_world_body.unit_quaternion().coeffs() == states[i].state.T_world_body.unit_quaternion().coeffs() &&
              back[i].state.v_world_mps == states[i].state.v_world_mps && back[i].bias.gyro_rad_s == states[i].bias.gyro_rad_s &&
              back[i].bias.accel_mps2 == states[i].bias.accel_mps2,
          "ground-truth round trip is exact");
  }
}

void round_trip(const ImuCalibration& calibration) {
  static const std::string copy = scratch_path(".copy");
  cairn::inertial::write_euroc_imu_calibration(copy, calibration);
  const ImuCalibration back = cairn::inertial::read_euroc_imu_calibration(copy);
  check(back.rate_hz == calibration.rate_hz && back.noise.gyro_noise_density == calibration.noise.gyro_noise_density &&
            back.noise.accel_noise_density == calibration.noise.accel_noise_density &&
            back.noise.gyro_random_walk == calibration.noise.gyro_random_walk &&
            back.noise.accel_random_walk == calibration.noise.accel_random_walk,
        "sensor.yaml round trip keeps the numbers");
  check(back.T_body_imu.translation() == calibration.T_body_imu.translation(), "sensor.yaml round trip keeps t_BS");
  check((back.T_body_imu.rotation_matrix() - calibration.T_body_imu.rotation_matrix()).cwiseAbs().maxCoeff() < 1e-12,
        "sensor.yaml round trip keeps R_BS");
}

template <class Read>
void read_and_check(Read read) {
  std::optional<decltype(read())> result;
  try {
    result = read();
  } catch (const cairn::io::ParseError&) {
    return;  // expected for malformed input
  }
  round_trip(*result);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = scratch_path(".input");
  write_bytes(path, reinterpret_cast<const char*>(data), size);
  read_and_check([&] { return cairn::inertial::read_euroc_imu(path); });
  read_and_check([&] { return cairn::inertial::read_imu_csv(path); });
  read_and_check([&] { return cairn::inertial::read_imu_file(path); });
  read_and_check([&] { return cairn::inertial::read_euroc_imu_calibration(path); });
  read_and_check([&] { return cairn::inertial::read_euroc_ground_truth(path); });
  return 0;
}
