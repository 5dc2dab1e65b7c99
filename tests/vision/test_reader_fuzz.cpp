// Deterministic mutation fuzzing of the visual-input readers (io/image_sequence.hpp and
// vision/vocabulary.hpp): each reader gets a small valid input built here (no shared data), then a
// fixed number of mutated copies of one of its files (fixed std::mt19937_64 seed). Every mutated
// input must either read, with every number that reaches calibration, times and poses finite and
// times strictly increasing where promised, or be refused with a ParseError that names the
// mutated file (or the folder) and says something. Any other exception fails the test; a crash or
// a hang fails the test binary. The cases the fuzzing found are repeated as plain regressions at
// the end.

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <typeinfo>
#include <vector>

#include <opencv2/core.hpp>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/vocabulary.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;

// 200 per file by default (the whole suite runs in about 2 s); CAIRN_READER_FUZZ_MUTATIONS
// overrides it for a longer exploratory run (same seeds, so the default run is a prefix of it).
int mutations_per_target() {
  const char* env = std::getenv("CAIRN_READER_FUZZ_MUTATIONS");
  return env != nullptr && std::atoi(env) > 0 ? std::atoi(env) : 200;
}
const int kMutationsPerTarget = mutations_per_target();

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_reader_fuzz_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

// A printable, shortened copy of a mutated input for failure messages.
std::string show(const std::string& s) {
  std::string out;
  for (std::size_t i = 0; i < s.size() && out.size() < 300; ++i) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c >= 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", c);
      out += hex;
    } else {
      out += static_cast<char>(c);
    }
  }
  if (out.size() >= 300) out += "... (" + std::to_string(s.size()) + " bytes)";
  return out;
}

// ---------------------------------------------------------------------------------------------
// Mutations.

class Mutator {
 public:
  explicit Mutator(std::uint64_t seed) : rng_(seed) {}

  std::size_t below(std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng_() % n); }

  // One to three stacked mutations of `in`; `what` says which.
  std::string mutate(const std::string& in, std::string* what) {
    std::string s = in;
    what->clear();
    const std::size_t count = below(4) == 0 ? 2 + below(2) : 1;
    for (std::size_t m = 0; m < count; ++m) s = mutate_once(s, what);
    return s;
  }

 private:
  static std::vector<std::string> lines_of(const std::string& s) {
    std::vector<std::string> lines;
    std::size_t pos = 0;
    while (true) {
      const std::size_t end = s.find('\n', pos);
      if (end == std::string::npos) {
        lines.push_back(s.substr(pos));
        break;
      }
      lines.push_back(s.substr(pos, end - pos));
      pos = end + 1;
    }
    return lines;  // the text is the lines joined with '\n'
  }
  static std::string join(const std::vector<std::string>& lines) {
    std::string s;
    for (std::size_t i = 0; i < lines.size(); ++i) s += (i ? "\n" : "") + lines[i];
    return s;
  }
  static bool separator(char c) {
    return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == ',' || c == '[' || c == ']' || c == '{' || c == '}' ||
           c == ':' || c == '"';
  }
  // [begin, end) of every token (a run of non-separator characters).
  static std::vector<std::pair<std::size_t, std::size_t>> tokens_of(const std::string& s) {
    std::vector<std::pair<std::size_t, std::size_t>> tokens;
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && separator(s[i])) ++i;
      const std::size_t begin = i;
      while (i < s.size() && !separator(s[i])) ++i;
      if (i > begin) tokens.emplace_back(begin, i);
    }
    return tokens;
  }
  std::string replace_token(const std::string& s, const std::vector<std::string>& choices, std::string* what) {
    const auto tokens = tokens_of(s);
    if (tokens.empty()) return s;
    const auto [b, e] = tokens[below(tokens.size())];
    const std::string& with = choices[below(choices.size())];
    *what += "token '" + s.substr(b, std::min<std::size_t>(e - b, 30)) + "' -> '" + with.substr(0, 30) + "'; ";
    return s.substr(0, b) + with + s.substr(e);
  }

  std::string mutate_once(const std::string& s, std::string* what) {
    static const std::vector<std::string> kSpecial = {"nan", "inf", "-inf", "1e999", "-0", "", "abc", "0x10", std::string(400, '9'), "1,5"};
    static const std::vector<std::string> kExtreme = {"1e308",  "-1e308", "1e300", "1e-310", "9.3e9", "-9.3e9", "99999999999.5",
                                                      "9223372036854775808", "-9223372036854775809", "18446744073709551616", "0"};
    if (below(100) < 3) {  // a line of 1 MiB (the TextReader limit) or one byte more
      auto lines = lines_of(s);
      const std::size_t size = (std::size_t{1} << 20) + below(2);
      lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(below(lines.size() + 1)), std::string(size, below(2) ? '7' : 'a'));
      *what += "line of " + std::to_string(size) + " bytes; ";
      return join(lines);
    }
    if (below(100) < 5) {  // every copy of a token replaced (values that must agree, e.g. fx in P0 and P1)
      const auto tokens = tokens_of(s);
      if (tokens.empty()) return s;
      const auto [b, e] = tokens[below(tokens.size())];
      const std::string from = s.substr(b, e - b);
      const std::string& to = below(2) ? kSpecial[below(kSpecial.size())] : kExtreme[below(kExtreme.size())];
      std::string out;
      std::size_t pos = 0;
      for (const auto& [tb, te] : tokens) {
        out += s.substr(pos, tb - pos);
        out += s.compare(tb, te - tb, from) == 0 ? to : s.substr(tb, te - tb);
        pos = te;
      }
      out += s.substr(pos);
      *what += "every '" + from.substr(0, 30) + "' -> '" + to.substr(0, 30) + "'; ";
      return out;
    }
    switch (below(10)) {
      case 0: {
        const std::size_t at = below(s.size());
        *what += "truncated at " + std::to_string(at) + "; ";
        return s.substr(0, at);
      }
      case 1: {
        auto lines = lines_of(s);
        const std::size_t i = below(lines.size());
        lines.erase(lines.begin() + static_cast<std::ptrdiff_t>(i));
        *what += "deleted line " + std::to_string(i + 1) + "; ";
        return join(lines);
      }
      case 2: {
        auto lines = lines_of(s);
        const std::size_t i = below(lines.size());
        lines.insert(lines.begin() + static_cast<std::ptrdiff_t>(i), lines[i]);
        *what += "duplicated line " + std::to_string(i + 1) + "; ";
        return join(lines);
      }
      case 3: {
        auto lines = lines_of(s);
        const std::size_t i = below(lines.size()), j = below(lines.size());
        std::swap(lines[i], lines[j]);
        *what += "swapped lines " + std::to_string(i + 1) + " and " + std::to_string(j + 1) + "; ";
        return join(lines);
      }
      case 4: return replace_token(s, kSpecial, what);
      case 5: return replace_token(s, kExtreme, what);
      case 6: {
        std::string out = s;
        if (out.empty()) return out;
        const std::size_t flips = 1 + below(4);
        for (std::size_t f = 0; f < flips; ++f) {
          const std::size_t at = below(out.size());
          const std::size_t how = below(4);
          out[at] = how == 0 ? '\0' : how == 1 ? '\xff' : how == 2 ? static_cast<char>(rng_() & 0xff) : static_cast<char>(out[at] ^ (1 << below(8)));
          *what += "byte " + std::to_string(at) + " changed; ";
        }
        return out;
      }
      case 7: {
        std::string garbage;
        const std::size_t n = 1 + below(32);
        for (std::size_t k = 0; k < n; ++k) garbage += static_cast<char>(rng_() & 0xff);
        const std::size_t at = below(s.size() + 1);
        *what += std::to_string(n) + " garbage bytes at " + std::to_string(at) + "; ";
        return s.substr(0, at) + garbage + s.substr(at);
      }
      case 8: *what += "emptied; "; return "";
      default: {  // one digit changed to another
        std::vector<std::size_t> digits;
        for (std::size_t i = 0; i < s.size(); ++i) {
          if (s[i] >= '0' && s[i] <= '9') digits.push_back(i);
        }
        if (digits.empty()) return s;
        std::string out = s;
        const std::size_t at = digits[below(digits.size())];
        out[at] = static_cast<char>('0' + below(10));
        *what += "digit at " + std::to_string(at) + " -> " + out[at] + "; ";
        return out;
      }
    }
  }

  std::mt19937_64 rng_;
};

// ---------------------------------------------------------------------------------------------
// Invariants of a successful read ("" when every one holds).

std::string check_calibration(const CameraCalibration& c, const std::string& who) {
  std::string out;
  for (const double v : {c.fx, c.fy, c.cx, c.cy, c.k1, c.k2, c.p1, c.p2, c.k3, c.baseline_m, c.depth_units_per_m, c.virtual_baseline_m}) {
    if (!std::isfinite(v)) out += who + ": a calibration number is not finite; ";
  }
  if (!(c.fx > 0.0) || !(c.fy > 0.0)) out += who + ": fx / fy not positive; ";
  if (c.width < 0 || c.height < 0) out += who + ": negative image size; ";
  if (std::string p; !c.is_valid(&p)) out += who + ": " + p + "; ";
  return out;
}

std::string check_increasing(const std::vector<core::Timestamp>& stamps, const std::string& who) {
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    if (!(stamps[i - 1] < stamps[i])) {
      return who + ": times not strictly increasing at " + std::to_string(i) + " (" + stamps[i - 1].to_seconds_string() + ", " +
             stamps[i].to_seconds_string() + "); ";
    }
  }
  return "";
}

std::string check_pose(const core::SE3& T, const std::string& who) {
  const Eigen::Matrix4d m = T.matrix();
  if (!m.allFinite()) return who + ": a pose is not finite; ";
  const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6) return who + ": a pose rotation is not a rotation; ";
  return "";
}

std::string check_trajectory(const Trajectory& t, const std::string& who) {
  std::string out;
  if (t.poses.empty()) out += who + ": empty trajectory; ";
  for (const core::SE3& T : t.poses) {
    out += check_pose(T, who);
    if (!out.empty()) break;
  }
  if (t.has_stamps() && t.stamps.size() != t.poses.size()) out += who + ": stamps and poses differ in number; ";
  out += check_increasing(t.stamps, who);
  return out;
}

std::string check_frames(const ImageSequence& seq) {
  std::string out;
  if (seq.frames.empty()) out += "no frames; ";
  std::vector<core::Timestamp> stamps;
  for (const ImageFrame& f : seq.frames) {
    stamps.push_back(f.time);
    if (f.image.empty()) out += "a frame without image; ";
    if (seq.kind == SequenceKind::kStereo && f.right_image.empty()) out += "a stereo frame without right image; ";
    if (seq.kind == SequenceKind::kRgbd && f.depth_image.empty()) out += "an RGB-D frame without depth image; ";
  }
  out += check_increasing(stamps, "frames");
  if (seq.ground_truth) out += check_trajectory(*seq.ground_truth, "ground truth");
  return out;
}

// ---------------------------------------------------------------------------------------------
// The runner.

struct Counts {
  int tried = 0, accepted = 0, rejected = 0, failures = 0;
};

// `read` reads the input and returns the broken invariants ("" = none). `blame` are the paths a
// ParseError may name besides `file` (a folder-level problem, a pairing of two lists).
Counts fuzz_file(const std::string& name, const fs::path& file, const std::string& valid, const std::vector<fs::path>& blame,
                 const std::function<std::string()>& read, std::uint64_t seed) {
  Counts n;
  write(file, valid);
  try {
    const std::string problems = read();
    EXPECT_EQ(problems, "") << name << ": the valid input";
  } catch (const std::exception& e) {
    ADD_FAILURE() << name << ": the valid input is refused: " << e.what();
    return n;
  }
  Mutator mutator(seed);
  auto fail = [&](const std::string& why, const std::string& what, const std::string& content) {
    ++n.failures;
    if (n.failures <= 5) ADD_FAILURE() << name << " [" << what << "]: " << why << "\n  input: " << show(content);
  };
  for (int i = 0; i < kMutationsPerTarget; ++i) {
    std::string what;
    const std::string content = mutator.mutate(valid, &what);
    write(file, content);
    ++n.tried;
    const auto start = std::chrono::steady_clock::now();
    try {
      const std::string problems = read();
      ++n.accepted;
      if (!problems.empty()) fail("accepted with " + problems, what, content);
    } catch (const ParseError& e) {
      ++n.rejected;
      const bool named = e.file() == file.string() ||
                         std::any_of(blame.begin(), blame.end(), [&](const fs::path& p) { return e.file() == p.string(); });
      if (!named) fail("ParseError names " + e.file() + ", expected " + file.string() + ": " + e.what(), what, content);
      if (std::string(e.what()).empty() || e.detail().empty()) fail("ParseError without a message", what, content);
    } catch (const std::exception& e) {
      fail(std::string("threw ") + typeid(e).name() + " (not ParseError): " + e.what(), what, content);
    } catch (...) {
      fail("threw a non-std exception", what, content);
    }
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (seconds > 2.0) fail("took " + std::to_string(seconds) + " s", what, content);
  }
  write(file, valid);
  std::printf("[ReaderFuzz] %-44s tried %3d  accepted %3d  rejected %3d\n", name.c_str(), n.tried, n.accepted, n.rejected);
  EXPECT_EQ(n.failures, 0) << name;
  EXPECT_GT(n.rejected, 0) << name << ": no mutation reached the checks";
  return n;
}

// ---------------------------------------------------------------------------------------------
// Valid inputs.

const char* kP0 = "718.856 0 607.1928 0 0 718.856 185.2157 0 0 0 1 0";
const char* kP1 = "718.856 0 607.1928 -386.1448 0 718.856 185.2157 0 0 0 1 0";

fs::path make_kitti(const std::string& name) {
  const fs::path dir = scratch(name);
  for (const char* side : {"image_0", "image_1"}) {
    for (const char* image : {"000000.png", "000001.png", "000002.png"}) write(dir / side / image, "");  // listed, never decoded
  }
  write(dir / "calib.txt", std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP0 + "\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  write(dir / "times.txt", "0.000000e+00\n1.036614e-01\n2.073228e-01\n");
  write(dir / "poses.txt",
        "1.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00 0.000000e+00 "
        "0.000000e+00 0.000000e+00 1.000000e+00 0.000000e+00\n"
        "9.999978e-01 5.272628e-04 -2.066935e-03 -4.690294e-02 -5.296506e-04 9.999992e-01 -1.154865e-03 -2.839928e-02 "
        "2.066324e-03 1.155958e-03 9.999971e-01 8.586941e-01\n"
        "9.999910e-01 1.048972e-03 -4.131348e-03 -9.374345e-02 -1.058514e-03 9.999968e-01 -2.308104e-03 -5.676064e-02 "
        "4.128913e-03 2.312456e-03 9.999887e-01 1.716275e+00\n");
  return dir;
}

std::string check_kitti(const ImageSequence& seq) {
  std::string out = check_calibration(seq.calibration, "calibration") + check_frames(seq);
  if (!(seq.calibration.baseline_m > 0.0)) out += "baseline not positive; ";
  if (seq.frames.size() != 3) out += "expected 3 frames; ";
  return out;
}

TEST(ReaderFuzz, KittiStereo) {
  const fs::path dir = make_kitti("kitti");
  auto read = [&] { return check_kitti(read_kitti_stereo(dir.string())); };
  const std::string calib = std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\nP2: " + kP0 + "\nTr: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::string times = "0.000000e+00\n1.036614e-01\n2.073228e-01\n";
  std::string poses;
  {
    std::ifstream in(dir / "poses.txt");
    std::ostringstream s;
    s << in.rdbuf();
    poses = s.str();
  }
  fuzz_file("read_kitti_stereo calib.txt (P0:/P1: labels)", dir / "calib.txt", calib, {dir}, read, 11);
  fuzz_file("read_kitti_stereo times.txt", dir / "times.txt", times, {dir}, read, 12);
  fuzz_file("read_kitti_stereo poses.txt", dir / "poses.txt", poses, {dir}, read, 13);
  fs::remove_all(dir);
}

TEST(ReaderFuzz, KittiCalibrationUnlabelled) {
  const fs::path dir = scratch("kitti_calibration");
  const fs::path path = dir / "calib.txt";
  auto read = [&] {
    const CameraCalibration c = read_kitti_calibration(path.string());
    std::string out = check_calibration(c, "calibration");
    if (!(c.baseline_m > 0.0)) out += "baseline not positive; ";
    return out;
  };
  fuzz_file("read_kitti_calibration (unlabelled lines)", path, std::string(kP0) + "\n" + kP1 + "\n" + kP0 + "\n", {}, read, 21);
  fs::remove_all(dir);
}

fs::path make_tum(const std::string& name) {
  const fs::path dir = scratch(name);
  write(dir / "rgb.txt", "# color images\n# timestamp filename\n1305031102.175304 rgb/1305031102.175304.png\n"
                         "1305031102.211214 rgb/1305031102.211214.png\n1305031102.243211 rgb/1305031102.243211.png\n");
  write(dir / "depth.txt", "# depth maps\n# timestamp filename\n1305031102.160407 depth/1305031102.160407.png\n"
                           "1305031102.226738 depth/1305031102.226738.png\n1305031102.262886 depth/1305031102.262886.png\n");
  write(dir / "groundtruth.txt", "# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n"
                                 "1305031098.6659 1.3563 0.6305 1.6380 0.6132 0.5962 -0.3311 -0.3986\n"
                                 "1305031098.6758 1.3543 0.6306 1.6360 0.6129 0.5966 -0.3316 -0.3980\n"
                                 "1305031098.6859 1.3524 0.6308 1.6340 0.6126 0.5972 -0.3320 -0.3973\n");
  return dir;
}

TEST(ReaderFuzz, TumRgbd) {
  const fs::path dir = make_tum("tum");
  auto read_file = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  };
  const std::string rgb = read_file(dir / "rgb.txt"), depth = read_file(dir / "depth.txt"), gt = read_file(dir / "groundtruth.txt");
  auto read = [&] { return check_frames(read_tum_rgbd(dir.string())); };
  // No depth map near any colour image is reported on depth.txt, whichever list moved.
  fuzz_file("read_tum_rgbd rgb.txt", dir / "rgb.txt", rgb, {dir, dir / "depth.txt"}, read, 31);
  fuzz_file("read_tum_rgbd depth.txt", dir / "depth.txt", depth, {dir}, read, 32);
  fuzz_file("read_tum_rgbd groundtruth.txt", dir / "groundtruth.txt", gt, {dir}, read, 33);
  auto read_list = [&] {
    const auto list = read_tum_image_list((dir / "rgb.txt").string());
    std::vector<core::Timestamp> stamps;
    std::string out;
    for (const auto& [t, file] : list) {
      stamps.push_back(t);
      if (file.empty()) out += "empty file name; ";
    }
    return out + check_increasing(stamps, "list");
  };
  fuzz_file("read_tum_image_list", dir / "rgb.txt", rgb, {}, read_list, 34);

  const fs::path assoc = scratch("tum_associations");
  const std::string associations = "# rgb depth\n1305031102.175304 rgb/a.png 1305031102.160407 depth/a.png\n"
                                   "1305031102.211214 rgb/b.png 1305031102.226738 depth/b.png\n"
                                   "1305031102.243211 rgb/c.png 1305031102.262886 depth/c.png\n";
  auto read_assoc = [&] { return check_frames(read_tum_rgbd(assoc.string())); };
  fuzz_file("read_tum_rgbd associations.txt", assoc / "associations.txt", associations, {assoc}, read_assoc, 35);
  fs::remove_all(dir);
  fs::remove_all(assoc);
}

std::string euroc_sensor_yaml(double tx) {
  std::ostringstream s;
  s << "# General sensor definitions.\nsensor_type: camera\ncomment: VI-Sensor cam0 (MT9M034)\n\n"
       "# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n"
       "  data: [0.0148655429818, -0.999880929698, 0.00414029679422, "
    << tx
    << ",\n         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
       "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
       "         0.0, 0.0, 0.0, 1.0]\n\n# Camera specific definitions.\nrate_hz: 20\nresolution: [752, 480]\n"
       "camera_model: pinhole\nintrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv\n"
       "distortion_model: radial-tangential\ndistortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n";
  return s.str();
}

TEST(ReaderFuzz, EurocStereo) {
  const fs::path dir = scratch("euroc");
  const fs::path mav = dir / "mav0";
  const std::string yaml0 = euroc_sensor_yaml(-0.0216401454975);
  write(mav / "cam0" / "sensor.yaml", yaml0);
  write(mav / "cam1" / "sensor.yaml", euroc_sensor_yaml(0.0883));
  const std::string csv0 = "#timestamp [ns],filename\n1403636579763555584,1403636579763555584.png\n"
                           "1403636579813555456,1403636579813555456.png\n1403636579863555584,1403636579863555584.png\n";
  write(mav / "cam0" / "data.csv", csv0);
  write(mav / "cam1" / "data.csv", csv0);
  const std::string gt = "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1]\n"
                         "1403636580838555648,4.688319,-1.786938,0.783338,0.534108,-0.153029,-0.827383,-0.082152,-0.027876\n"
                         "1403636580843555328,4.688177,-1.786770,0.787350,0.534640,-0.152990,-0.826976,-0.082863,-0.029272\n"
                         "1403636580848555520,4.688028,-1.786598,0.791382,0.535178,-0.152945,-0.826562,-0.083605,-0.030571\n";
  write(mav / "state_groundtruth_estimate0" / "data.csv", gt);
  auto read = [&] {
    const ImageSequence seq = read_euroc_stereo(dir.string());
    std::string out = check_frames(seq) + check_calibration(seq.calibration, "calibration");
    if (!seq.rig) return out + "no rig; ";
    out += check_calibration(seq.rig->left, "cam0") + check_calibration(seq.rig->right, "cam1");
    out += check_pose(seq.rig->T_body_left, "T_BS cam0") + check_pose(seq.rig->T_body_right, "T_BS cam1");
    return out;
  };
  fuzz_file("read_euroc_stereo cam0/sensor.yaml", mav / "cam0" / "sensor.yaml", yaml0, {dir}, read, 41);
  // A cam0 list that no longer shares a stamp with cam1 is reported on cam1/data.csv.
  fuzz_file("read_euroc_stereo cam0/data.csv", mav / "cam0" / "data.csv", csv0, {dir, mav / "cam1" / "data.csv"}, read, 42);
  fuzz_file("read_euroc_stereo groundtruth data.csv", mav / "state_groundtruth_estimate0" / "data.csv", gt, {dir}, read, 43);
  auto read_camera = [&] {
    core::SE3 T;
    const CameraCalibration c = read_euroc_camera((mav / "cam0" / "sensor.yaml").string(), &T);
    return check_calibration(c, "camera") + check_pose(T, "T_BS");
  };
  fuzz_file("read_euroc_camera sensor.yaml", mav / "cam0" / "sensor.yaml", yaml0, {}, read_camera, 44);
  fs::remove_all(dir);
}

TEST(ReaderFuzz, ImageFolderTimes) {
  const fs::path dir = scratch("folder");
  for (const char* image : {"frame_1.png", "frame_2.png", "frame_10.png"}) write(dir / image, "");
  auto read = [&] {
    const ImageSequence seq = read_image_folder(dir.string());
    std::string out = check_frames(seq);
    if (seq.frames.size() != 3) out += "expected 3 frames; ";
    return out;
  };
  fuzz_file("read_image_folder times.txt", dir / "times.txt", "# seconds\n0.0\n0.05\n1.5e-01\n", {dir}, read, 51);
  fs::remove_all(dir);
}

// The times a folder's file names give (time_from_name): every returned time must be the name's.
TEST(ReaderFuzz, ImageFolderTimesFromFileNames) {
  const fs::path dir = scratch("folder_names");
  const std::vector<std::string> stems = {"1403636579763555584", "1403636579813555456", "1403636579863555584"};
  Mutator mutator(61);
  Counts n;
  auto check = [&](const ImageSequence& seq, const std::vector<std::string>& names) {
    std::string out = check_frames(seq);
    if (seq.frames.size() != names.size()) return out + "wrong frame count; ";
    if (std::find(seq.notes.begin(), seq.notes.end(), "times taken from the image file names") == seq.notes.end()) return out;
    for (const ImageFrame& f : seq.frames) {
      const std::string stem = fs::path(f.image).stem().string();
      // The name as a number (long double: 19 digits survive), in seconds.
      const long double value = std::strtold(stem.c_str(), nullptr);
      const long double expected = stem.find('.') == std::string::npos ? value * 1e-9L : value;
      const long double got = static_cast<long double>(f.time.nanoseconds()) * 1e-9L;
      if (!(std::fabs(got - expected) <= 1e-6L + 1e-12L * std::fabs(expected))) {
        out += "the time of " + stem + " is " + f.time.to_seconds_string() + " s; ";
      }
    }
    return out;
  };
  // The valid folder reads its times from the names.
  for (const auto& s : stems) write(dir / (s + ".png"), "");
  {
    const ImageSequence seq = read_image_folder(dir.string());
    ASSERT_EQ(seq.frames.size(), 3u);
    EXPECT_TRUE(seq.times_from_file);
    EXPECT_EQ(check(seq, {"a", "b", "c"}), "");
  }
  int failures = 0;
  for (int i = 0; i < kMutationsPerTarget; ++i) {
    std::vector<std::string> names = stems;
    const std::size_t which = mutator.below(names.size());
    std::string what;
    std::string stem = mutator.mutate(names[which], &what);
    for (char& c : stem) {
      if (c == '/' || c == '\0' || c == '\n' || static_cast<unsigned char>(c) >= 0x80 || c < 0x20) c = '_';
    }
    if (stem.empty() || stem == "." || stem == ".." || stem.size() > 200) continue;  // not a file name
    if (std::find(names.begin(), names.end(), stem) != names.end()) continue;         // the same file twice
    names[which] = stem;
    fs::remove_all(dir);
    fs::create_directories(dir);
    for (const auto& s : names) write(dir / (s + ".png"), "");
    ++n.tried;
    try {
      const ImageSequence seq = read_image_folder(dir.string());
      ++n.accepted;
      if (const std::string p = check(seq, names); !p.empty() && ++failures <= 5) ADD_FAILURE() << "name '" << stem << "' [" << what << "]: " << p;
    } catch (const ParseError& e) {
      ++n.rejected;
      if (e.detail().empty() && ++failures <= 5) ADD_FAILURE() << "ParseError without a message";
    } catch (const std::exception& e) {
      if (++failures <= 5) ADD_FAILURE() << "name '" << stem << "' [" << what << "]: threw " << typeid(e).name() << ": " << e.what();
    }
  }
  std::printf("[ReaderFuzz] %-44s tried %3d  accepted %3d  rejected %3d\n", "read_image_folder file names", n.tried, n.accepted, n.rejected);
  EXPECT_EQ(failures, 0);
  EXPECT_GT(n.tried, kMutationsPerTarget / 2);
  // Every name stays a .png image, so a folder is always readable: nothing to reject here, but
  // times that are not the names' would be caught above.
  EXPECT_EQ(n.rejected, 0);
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Vocabularies.

std::string bytes_text(int value) {
  std::string s;
  for (int i = 0; i < 32; ++i) s += std::to_string(value) + " ";
  return s;
}

std::string check_vocabulary(const vision::Vocabulary& v) {
  std::string out;
  if (v.words() == 0 || v.nodes() < v.words() + 1) out += "no words or too few nodes; ";
  if (v.branching() < 2 || v.branching() > 64 || v.depth() < 1 || v.depth() > 12) out += "k or L out of range; ";
  for (std::uint32_t w = 0; w < v.words(); ++w) {
    const double weight = v.word_weight(w);
    if (!std::isfinite(weight) || weight < 0.0) out += "word weight " + std::to_string(weight) + "; ";
    if (v.word_node(w) == 0 || v.word_node(w) >= v.nodes()) out += "word node out of range; ";
  }
  if (!out.empty()) return out;
  std::mt19937_64 rng(7);
  cv::Mat d(8, 32, CV_8U);
  for (int r = 0; r < d.rows; ++r) {
    for (int c = 0; c < 32; ++c) d.at<unsigned char>(r, c) = static_cast<unsigned char>(rng() & 0xff);
  }
  std::vector<std::uint32_t> words;
  const vision::BowVector bow = v.transform(d, &words);
  double sum = 0.0;
  for (const auto& [w, weight] : bow) {
    if (w >= v.words() || !std::isfinite(weight) || !(weight > 0.0)) out += "bad BoW entry; ";
    sum += weight;
  }
  if (!bow.empty() && std::abs(sum - 1.0) > 1e-9) out += "BoW vector not L1-normalised; ";
  for (const std::uint32_t w : words) {
    if (w >= v.words()) out += "feature word out of range; ";
  }
  return out;
}

TEST(ReaderFuzz, VocabularyFormats) {
  const fs::path dir = scratch("vocabulary");
  auto read_at = [](const fs::path& p) { return [p] { return check_vocabulary(vision::Vocabulary::load(p.string())); }; };

  // DBoW2 text, k = 2, L = 2: nodes 1 and 2 inner, 3..6 words.
  const std::string text = "2 2 0 0\n0 0 " + bytes_text(0) + "0\n0 0 " + bytes_text(255) + "0\n1 1 " + bytes_text(1) + "0.5\n1 1 " +
                           bytes_text(16) + "1.0\n2 1 " + bytes_text(254) + "1.5\n2 1 " + bytes_text(200) + "2\n";
  fuzz_file("Vocabulary::load DBoW2 text", dir / "voc.txt", text, {}, read_at(dir / "voc.txt"), 71);

  const std::string yaml = "%YAML:1.0\n---\nvocabulary:\n   k: 2\n   L: 2\n   scoringType: 0\n   weightingType: 0\n   nodes:\n"
                           "      - { nodeId:1, parentId:0, weight:0.,\n          descriptor:\"" + bytes_text(0) + "\" }\n"
                           "      - { nodeId:2, parentId:0, weight:0., descriptor:\"" + bytes_text(255) + "\" }\n"
                           "      - { nodeId:3, parentId:1, weight:5.0000000000000000e-01, descriptor:\"" + bytes_text(1) + "\" }\n"
                           "      - { nodeId:4, parentId:1, weight:1., descriptor:\"" + bytes_text(16) + "\" }\n"
                           "      - { nodeId: 5, parentId: 2, weight: 1.5, descriptor: \"" + bytes_text(254) + "\" }\n"
                           "      - { nodeId:6, parentId:2, weight:2., descriptor:\"" + bytes_text(200) + "\" }\n"
                           "   words:\n      - { wordId:0, nodeId:3 }\n      - { wordId:1, nodeId:4 }\n"
                           "      - { wordId:2, nodeId:5 }\n      - { wordId:3, nodeId:6 }\n";
  fuzz_file("Vocabulary::load DBoW2 YAML", dir / "voc.yml", yaml, {}, read_at(dir / "voc.yml"), 72);

  // cairn's binary format, from a small trained vocabulary.
  std::mt19937_64 rng(3);
  std::vector<cv::Mat> images;
  for (int i = 0; i < 4; ++i) {
    cv::Mat m(12, 32, CV_8U);
    for (int r = 0; r < m.rows; ++r) {
      for (int c = 0; c < 32; ++c) m.at<unsigned char>(r, c) = static_cast<unsigned char>(rng() & 0xff);
    }
    images.push_back(m);
  }
  vision::VocabularyOptions options;
  options.branching = 3;
  options.depth = 2;
  options.max_threads = 1;
  const vision::Vocabulary trained = vision::Vocabulary::train(images, options);
  trained.save((dir / "voc.cairn").string());
  std::string binary;
  {
    std::ifstream in(dir / "voc.cairn", std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    binary = s.str();
  }
  fuzz_file("Vocabulary::load cairn binary", dir / "voc.cairn", binary, {}, read_at(dir / "voc.cairn"), 73);
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------------------------
// Regressions: the inputs the fuzzing above found accepted with wrong times or throwing
// std::out_of_range (fixed in io/image_sequence.cpp, frame_times and time_from_name).

template <typename F>
void expect_parse_error(F&& f, const fs::path& file, std::size_t line, const std::string& says) {
  try {
    f();
    ADD_FAILURE() << "no error; expected " << says;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), file.string()) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(says), std::string::npos) << e.what();
  }
}

TEST(ReaderFuzzRegression, TimesBeyondTheTimestampRangeAreRefused) {
  // Timestamp::from_seconds overflowed: 1e308 s, 99999999999.5 s and 2^63 s became -9223372036.854775808 s.
  const fs::path kitti = make_kitti("regression_kitti");
  for (const char* t : {"1e308", "99999999999.5", "9223372036854775808", "-9.3e9"}) {
    write(kitti / "times.txt", std::string("0.000000e+00\n") + t + "\n2.073228e-01\n");
    expect_parse_error([&] { read_kitti_stereo(kitti.string()); }, kitti / "times.txt", 2, "expected a time in seconds");
  }
  const fs::path folder = scratch("regression_folder");
  for (const char* image : {"a.png", "b.png", "c.png"}) write(folder / image, "");
  write(folder / "times.txt", "# seconds\n0.0\n18446744073709551616\n1.5e-01\n");
  expect_parse_error([&] { read_image_folder(folder.string()); }, folder / "times.txt", 3, "expected a time in seconds");
  write(folder / "times.txt", "0.0\n0.05\n0.1\n");
  const ImageSequence seq = read_image_folder(folder.string());
  ASSERT_EQ(seq.frames.size(), 3u);
  EXPECT_EQ(seq.frames[1].time.nanoseconds(), 50'000'000);
  fs::remove_all(kitti);
  fs::remove_all(folder);
}

TEST(ReaderFuzzRegression, TimesLessThanANanosecondApartAreRefused) {
  // 1.036614e-81 > 0 as doubles, but both are 0 ns: the frames had equal stamps.
  const fs::path kitti = make_kitti("regression_kitti_ns");
  for (const char* t : {"1.036614e-81", "0.0000000001"}) {
    write(kitti / "times.txt", std::string("0.000000e+00\n") + t + "\n2.073228e-01\n");
    expect_parse_error([&] { read_kitti_stereo(kitti.string()); }, kitti / "times.txt", 2, "times must increase strictly");
  }
  fs::remove_all(kitti);
}

TEST(ReaderFuzzRegression, FileNamesBeyondTheTimestampRangeAreNotTimes) {
  // std::stoll threw std::out_of_range on a 19-digit name above 2^63 - 1; 99999999999.5 s
  // overflowed Timestamp::from_seconds. Neither is a time: the frames are 0.1 s apart.
  for (const char* first : {"9223372036854775808", "99999999999.5"}) {
    const fs::path dir = scratch("regression_names");
    write(dir / (std::string(first) + ".png"), "");
    // A time in nanoseconds; in natural order after 99999999999.5, whose garbage time
    // (-9223372036.854775808 s) came before it, so the old code took both names as times.
    write(dir / "1403636579813555456.png", "");
    const ImageSequence seq = read_image_folder(dir.string());
    ASSERT_EQ(seq.frames.size(), 2u);
    EXPECT_FALSE(seq.times_from_file) << first;
    EXPECT_EQ(seq.frames[0].time.nanoseconds(), 0);
    EXPECT_EQ(seq.frames[1].time.nanoseconds(), 100'000'000);
    fs::remove_all(dir);
  }
  // The largest names that are times still are.
  const fs::path dir = scratch("regression_names_max");
  write(dir / "9223372036854775806.png", "");
  write(dir / "9223372036854775807.png", "");
  const ImageSequence seq = read_image_folder(dir.string());
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_TRUE(seq.times_from_file);
  EXPECT_EQ(seq.frames[1].time.nanoseconds(), 9223372036854775807);
  fs::remove_all(dir);
}

TEST(ReaderFuzzRegression, KittiCalibrationWithAnInfiniteBaselineIsRefused) {
  // fx = 1e-310 (subnormal, every '718.856' replaced) and P1[0,3] - P0[0,3] = -inf gave
  // baseline_m = inf, accepted.
  const fs::path dir = scratch("regression_calib");
  const fs::path path = dir / "calib.txt";
  write(path, "P0: 1e-310 0 607.1928 0 0 1e-310 185.2157 0 0 0 1 0\nP1: 1e-310 0 607.1928 -386.1448 0 1e-310 185.2157 0 0 0 1 0\n");
  expect_parse_error([&] { read_kitti_calibration(path.string()); }, path, 2, "baseline");
  write(path, std::string("# calibration\n") + "718.856 0 607.1928 1e308 0 718.856 185.2157 0 0 0 1 0\n" +
                  "718.856 0 607.1928 -1e308 0 718.856 185.2157 0 0 0 1 0\n");
  expect_parse_error([&] { read_kitti_calibration(path.string()); }, path, 3, "baseline");
  write(path, std::string("P0: ") + kP0 + "\nP1: " + kP1 + "\n");
  EXPECT_NEAR(read_kitti_calibration(path.string()).baseline_m, 386.1448 / 718.856, 1e-12);
  fs::remove_all(dir);
}

TEST(ReaderFuzzRegression, VocabularyWeightNearDblMaxIsRefused) {
  // A word weight of 1e308 loaded; transform() then summed two features' weights to inf and
  // returned NaN weights.
  const fs::path dir = scratch("regression_vocabulary");
  const std::string text = "2 2 0 0\n0 0 " + bytes_text(0) + "0\n0 0 " + bytes_text(255) + "0\n1 1 " + bytes_text(1) + "0.5\n1 1 " +
                           bytes_text(16) + "1.0\n2 1 " + bytes_text(254) + "1e308\n2 1 " + bytes_text(200) + "2\n";
  write(dir / "voc.txt", text);
  try {
    vision::Vocabulary::load((dir / "voc.txt").string());
    ADD_FAILURE() << "a weight of 1e308 loaded";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), (dir / "voc.txt").string());
    EXPECT_EQ(e.line(), 6u) << e.what();
    EXPECT_NE(e.detail().find("weight 1e+308, expected at most 1e6"), std::string::npos) << e.what();
  }
  // Plausible idf weights still load.
  std::string ok = text;
  ok.replace(ok.find("1e308"), 5, "22.1");
  write(dir / "voc.txt", ok);
  EXPECT_EQ(vision::Vocabulary::load((dir / "voc.txt").string()).words(), 4u);
  fs::remove_all(dir);
}

TEST(ReaderFuzzRegression, EurocResolutionBeyondIntAndEmptyFileNamesAreRefused) {
  // resolution: [1e300, 480] was converted to int (undefined behaviour); a data.csv line
  // "123," was accepted with the image folder itself as the image.
  const fs::path dir = scratch("regression_euroc");
  const fs::path mav = dir / "mav0";
  std::string yaml = euroc_sensor_yaml(-0.0216401454975);
  yaml.replace(yaml.find("[752, 480]"), 10, "[1e300, 480]");
  write(mav / "cam0" / "sensor.yaml", yaml);
  core::SE3 T;
  expect_parse_error([&] { read_euroc_camera((mav / "cam0" / "sensor.yaml").string(), &T); }, mav / "cam0" / "sensor.yaml", 16,
                     "whole pixels");
  write(mav / "cam0" / "sensor.yaml", euroc_sensor_yaml(-0.0216401454975));
  EXPECT_EQ(read_euroc_camera((mav / "cam0" / "sensor.yaml").string(), &T).width, 752);
  write(mav / "cam1" / "sensor.yaml", euroc_sensor_yaml(0.0883));
  const std::string csv = "#timestamp [ns],filename\n1403636579763555584,1403636579763555584.png\n1403636579813555456, \n";
  write(mav / "cam0" / "data.csv", csv);
  write(mav / "cam1" / "data.csv", csv);
  expect_parse_error([&] { read_euroc_stereo(dir.string()); }, mav / "cam0" / "data.csv", 3, "image file name");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::io
