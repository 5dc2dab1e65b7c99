// libFuzzer entry point for the trajectory readers (TUM, KITTI with and without a times file,
// EuRoC). Any input must end in a trajectory or a cairn::io::ParseError: another exception, a
// crash, a hang or a sanitizer report is a bug. What a reader accepts must also survive every
// writer: written and read back it gives the same stamps and poses (bit for bit for TUM and
// EuRoC, to rounding for KITTI's matrices), and a writer refusing it is a bug too. Run with
// `make fuzz` (clang); the corpus in fuzz/corpus/trajectory runs in `make test`.

#include <unistd.h>

#include <bit>
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

#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"

namespace {

using cairn::io::Trajectory;

std::string prefix_for_cleanup() {
  return (std::filesystem::temp_directory_path() / ("cairn_fuzz_trajectory_" + std::to_string(::getpid())))
      .string();
}

// Scratch files, one set per process, reused for every input and removed at exit.
std::string scratch_path(const char* suffix) {
  static const std::string prefix = [] {
    std::atexit([] {
      std::error_code ignored;
      for (const char* s : {".txt", ".kitti", ".copy", ".copy_times"}) {
        std::filesystem::remove(prefix_for_cleanup() + s, ignored);
      }
    });
    return prefix_for_cleanup();
  }();
  return prefix + suffix;
}

void write_bytes(const std::string& path, const char* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz_trajectory: cannot write scratch file %s\n", path.c_str());
    std::abort();
  }
}

void check(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "fuzz_trajectory: invariant broken: %s\n", what);
  std::abort();
}

bool same_bits(double a, double b) { return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b); }

void check_invariants(const Trajectory& t) {
  check(t.size() > 0, "a successful read has poses");
  check(t.stamps.empty() || t.stamps.size() == t.size(), "one stamp per pose");
  for (std::size_t i = 1; i < t.stamps.size(); ++i) check(t.stamps[i - 1] < t.stamps[i], "stamps increase");
  for (const auto& pose : t.poses) {
    check(pose.translation().allFinite(), "finite translation");
    check(std::abs(pose.unit_quaternion().norm() - 1.0) < 1e-12, "unit quaternion");
  }
}

// Same stamps; translations bit for bit; quaternions bit for bit (exact) or rotation matrices
// within 1e-9 (after KITTI's matrix round trip).
void check_same(const Trajectory& a, const Trajectory& b, bool exact) {
  check(a.size() == b.size(), "round trip keeps the pose count");
  check(a.stamps == b.stamps, "round trip keeps the stamps");
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      check(same_bits(a.poses[i].translation()[k], b.poses[i].translation()[k]), "round trip keeps translations");
    }
    if (exact) {
      for (int k = 0; k < 4; ++k) {
        check(same_bits(a.poses[i].unit_quaternion().coeffs()[k], b.poses[i].unit_quaternion().coeffs()[k]),
              "round trip keeps quaternions bit for bit");
      }
    } else {
      const double error =
          (a.poses[i].rotation_matrix() - b.poses[i].rotation_matrix()).cwiseAbs().maxCoeff();
      check(error < 1e-9, "KITTI round trip keeps rotations");
    }
  }
}

// Writes `t` in every format it can be written in and reads it back. Exceptions propagate on
// purpose: a writer refusing what a reader accepted is a bug.
void round_trip(const Trajectory& t) {
  static const std::string copy = scratch_path(".copy");
  static const std::string copy_times = scratch_path(".copy_times");
  cairn::io::write_kitti(copy, t, t.has_stamps() ? copy_times : "");
  check_same(t, cairn::io::read_kitti(copy, t.has_stamps() ? copy_times : ""), false);
  if (!t.has_stamps()) return;
  cairn::io::write_tum(copy, t);
  check_same(t, cairn::io::read_tum(copy), true);
  cairn::io::write_euroc(copy, t);
  check_same(t, cairn::io::read_euroc(copy), true);
}

template <class Read>
void read_and_check(Read read) {
  std::optional<Trajectory> t;
  try {
    t = read();
  } catch (const cairn::io::ParseError&) {
    return;  // expected for malformed input
  }
  check_invariants(*t);
  round_trip(*t);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = scratch_path(".txt");
  // Three valid poses, so the input is also tried as their KITTI times file.
  static const std::string kitti_poses = [] {
    const std::string p = scratch_path(".kitti");
    const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
    const std::string text = identity + identity + identity;
    write_bytes(p, text.data(), text.size());
    return p;
  }();
  write_bytes(path, reinterpret_cast<const char*>(data), size);
  read_and_check([&] { return cairn::io::read_tum(path); });
  read_and_check([&] { return cairn::io::read_kitti(path); });
  read_and_check([&] { return cairn::io::read_kitti(kitti_poses, path); });
  read_and_check([&] { return cairn::io::read_euroc(path); });
  return 0;
}
