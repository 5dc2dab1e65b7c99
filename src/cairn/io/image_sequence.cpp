#include "cairn/io/image_sequence.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <tuple>

#include "cairn/core/problems.hpp"
#include "cairn/io/file_names.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;

std::string lower_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

}  // namespace

bool is_image_file_name(const std::string& path) {
  const std::string ext = lower_extension(path);
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg";
}

std::vector<std::string> image_files_in(const std::string& folder) {
  std::vector<std::string> names;
  std::map<std::string, int> unread;  // image formats cairn does not decode, by extension
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string path = entry.path().string();
    if (is_image_file_name(path)) {
      names.push_back(path);
    } else {
      const std::string ext = lower_extension(path);
      if (ext == ".pgm" || ext == ".ppm" || ext == ".pnm" || ext == ".bmp" || ext == ".tif" || ext == ".tiff") ++unread[ext];
    }
  }
  if (ec) throw ParseError(folder, 0, "cannot list the folder: " + ec.message());
  if (names.empty()) {
    if (!unread.empty()) {
      const auto& [ext, count] = *unread.begin();
      throw ParseError(folder, 0, "holds " + std::to_string(count) + " " + ext + " images, which cairn does not read (PNG and JPEG only): " +
                                      "convert them first, e.g. `mogrify -format png *" + ext + "` (ImageMagick)");
    }
    throw ParseError(folder, 0, "no images (.png, .jpg, .jpeg) in the folder");
  }
  // Natural order ("frame_9" before "frame_10"); the same as by bytes for zero-padded names.
  std::sort(names.begin(), names.end(),
            [](const std::string& a, const std::string& b) { return natural_less(fs::path(a).filename().string(), fs::path(b).filename().string()); });
  return names;
}

bool CameraCalibration::is_valid(std::string* why) const {
  core::Problems problems;
  auto add = [&](const std::string& p) { problems.add(p); };
  for (const auto& [name, v] : {std::pair{"fx", fx}, {"fy", fy}}) {
    if (!(std::isfinite(v) && v > 0.0)) add(std::string(name) + " must be a positive number");
  }
  for (const auto& [name, v] : {std::pair{"cx", cx}, {"cy", cy}, {"k1", k1}, {"k2", k2}, {"p1", p1}, {"p2", p2}, {"k3", k3},
                                {"baseline_m", baseline_m}, {"depth_units_per_m", depth_units_per_m},
                                {"virtual_baseline_m", virtual_baseline_m}}) {
    if (!std::isfinite(v)) add(std::string(name) + " must be finite");
  }
  if (width < 0 || height < 0) add("width and height must not be negative");
  if (baseline_m < 0.0 || depth_units_per_m < 0.0 || virtual_baseline_m < 0.0) add("baselines and depth scale must not be negative");
  return problems.report(why);
}

std::string CameraCalibration::implausibilities(int image_width, int image_height, bool stereo) const {
  std::string out;
  auto add = [&](const std::string& p) { out += (out.empty() ? "" : "; ") + p; };
  auto g = [](double v) {
    char buffer[32];
    std::snprintf(buffer, sizeof buffer, "%.6g", v);
    return std::string(buffer);
  };
  constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
  for (const auto& [axis, f, pixels] : {std::tuple{"horizontal", fx, image_width}, {"vertical", fy, image_height}}) {
    if (!(f > 0.0) || pixels <= 0) continue;
    const double fov_deg = 2.0 * std::atan(0.5 * static_cast<double>(pixels) / f) * kDegPerRad;
    if (!(fov_deg >= 1.0 && fov_deg <= 170.0)) {
      add(std::string(axis) + " field of view " + g(fov_deg) + " deg (" + (axis[0] == 'h' ? "fx " : "fy ") + g(f) +
          " px over " + std::to_string(pixels) + " px): expected 1 to 170 deg of a pinhole camera; are the focal lengths in pixels?");
    }
  }
  if (image_width > 0 && image_height > 0 &&
      !(cx >= 0.0 && cx <= static_cast<double>(image_width) && cy >= 0.0 && cy <= static_cast<double>(image_height))) {
    add("principal point (" + g(cx) + ", " + g(cy) + ") lies outside the " + std::to_string(image_width) + " x " +
        std::to_string(image_height) + " image");
  }
  if (stereo && !(baseline_m >= 1e-3 && baseline_m <= 10.0)) {
    add("stereo baseline " + g(baseline_m) + " m: expected 1 mm to 10 m of a real stereo camera");
  }
  return out;
}

std::string_view to_string(SequenceKind kind) {
  switch (kind) {
    case SequenceKind::kStereo: return "stereo";
    case SequenceKind::kRgbd: return "rgbd";
    case SequenceKind::kMonocular: return "monocular";
  }
  return "?";
}

std::string detect_image_layout(const std::string& folder) {
  const fs::path dir(folder);
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ParseError(folder, 0, "not a folder (expected a KITTI or TUM RGB-D sequence folder)");
  if (fs::exists(dir / "calib.txt", ec) &&
      ((fs::is_directory(dir / "image_0", ec) && fs::is_directory(dir / "image_1", ec)) ||
       (fs::is_directory(dir / "image_l", ec) && fs::is_directory(dir / "image_r", ec)))) {
    return "kitti";
  }
  if (fs::exists(dir / "rgb.txt", ec) || fs::exists(dir / "associations.txt", ec)) return "tum";
  if (fs::is_directory(dir / "mav0" / "cam0", ec) || fs::is_directory(dir / "cam0", ec)) return "euroc";
  if (fs::is_directory(dir / "left", ec) && fs::is_directory(dir / "right", ec)) return "folder";
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (entry.is_regular_file(ec) && is_image_file_name(entry.path().string())) return "folder";
  }
  throw ParseError(folder, 0,
                   "not a known image sequence: expected calib.txt with image_0/ and image_1/ (or image_l/ and image_r/) "
                   "(KITTI odometry stereo), rgb.txt / associations.txt (TUM RGB-D), mav0/cam0 (EuRoC), left/ and right/ "
                   "(rectified stereo images) or images (.png, .jpg) in the folder itself (monocular)");
}

CameraCalibration read_kitti_calibration(const std::string& path) {
  TextReader reader(path);
  std::vector<std::vector<double>> rows;
  std::vector<std::string> labels;
  std::optional<std::vector<double>> p0, p1;
  std::size_t unlabelled = 0, p1_line = 0;
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    std::vector<std::string_view> tokens = split_whitespace(reader.line());
    std::string label;
    if (!tokens.empty() && tokens.front().back() == ':') {
      label = std::string(tokens.front().substr(0, tokens.front().size() - 1));
      tokens.erase(tokens.begin());
    }
    if (label.empty() && unlabelled >= 2) continue;  // further unlabelled lines: not P0/P1
    if (!label.empty() && label != "P0" && label != "P1") continue;  // P2, P3, Tr: not needed
    if (tokens.size() != 12) {
      reader.fail("expected 12 numbers (a 3x4 projection matrix" + (label.empty() ? std::string() : " " + label) +
                  "), found " + std::to_string(tokens.size()) + " fields");
    }
    std::vector<double> values;
    for (const auto& t : tokens) values.push_back(parse_double(reader, t, "a projection-matrix entry"));
    if (label == "P0" || (label.empty() && unlabelled == 0)) {
      p0 = values;
    } else {
      p1 = values;
      p1_line = reader.line_number();
    }
    if (label.empty()) ++unlabelled;
  }
  if (!p0 || !p1) throw ParseError(path, 0, "expected the projection matrices P0 and P1 (labelled, or the first two lines)");
  CameraCalibration c;
  c.fx = (*p0)[0];
  c.fy = (*p0)[5];
  c.cx = (*p0)[2];
  c.cy = (*p0)[6];
  if (!(c.fx > 0.0) || !(c.fy > 0.0)) throw ParseError(path, 0, "P0 has no positive focal length (P0[0,0], P0[1,1])");
  if ((*p1)[0] != (*p0)[0] || (*p1)[2] != (*p0)[2] || (*p1)[6] != (*p0)[6]) {
    throw ParseError(path, 0, "P0 and P1 differ in fx, cx or cy: the images are not a rectified stereo pair");
  }
  c.baseline_m = -((*p1)[3] - (*p0)[3]) / c.fx;
  if (!std::isfinite(c.baseline_m)) {  // a subnormal fx (1e-310) or P1[0,3] near -DBL_MAX overflows
    throw ParseError(path, p1_line, "the baseline -(P1[0,3] - P0[0,3]) / fx is not a finite number: expected fx and P1[0,3] of a real camera");
  }
  if (!(c.baseline_m > 0.0)) {
    throw ParseError(path, 0, "P1[0,3] - P0[0,3] must be negative (camera 1 right of camera 0), found a baseline of " +
                                  std::to_string(c.baseline_m) + " m");
  }
  return c;
}

namespace {

// The file names of left/ that have a partner of the same name in right/ (each left image must;
// right images without a partner are counted in seq.notes).
std::vector<std::string> paired_stereo_names(const fs::path& left, const fs::path& right, ImageSequence& seq) {
  std::vector<std::string> names, right_names;
  for (const std::string& p : image_files_in(left.string())) names.push_back(fs::path(p).filename().string());
  for (const std::string& p : image_files_in(right.string())) right_names.push_back(fs::path(p).filename().string());
  const std::set<std::string> right_set(right_names.begin(), right_names.end());
  for (const std::string& name : names) {
    if (!right_set.count(name)) {
      throw ParseError((right / name).string(), 0, "missing: every left image needs its right image of the same name");
    }
  }
  if (right_names.size() != names.size()) {
    seq.notes.push_back(std::to_string(right_names.size() - names.size()) + " right images have no left partner and are ignored");
  }
  return names;
}

// A file name's stem as a time: an integer of 16 or more digits is nanoseconds (EuRoC's
// 1403636579763555584.png), a number with a decimal point seconds (TUM's 1305031102.175304.png);
// anything else (frame numbers such as KITTI's 000042.png) is not a time.
std::optional<core::Timestamp> time_from_name(const std::string& name) {
  const std::string stem = fs::path(name).stem().string();
  if (stem.empty()) return std::nullopt;
  const bool digits = std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
  // parse_nanoseconds / parse_seconds: nullopt (not a time) beyond int64 nanoseconds, where
  // std::stoll threw std::out_of_range and Timestamp::from_seconds overflowed.
  if (digits && stem.size() >= 16 && stem.size() <= 19) return core::Timestamp::parse_nanoseconds(stem);
  const std::size_t dot = stem.find('.');
  if (dot == std::string::npos || dot == 0 || dot + 1 == stem.size() || stem.find('.', dot + 1) != std::string::npos) {
    return std::nullopt;
  }
  const auto digit = [](unsigned char c) { return std::isdigit(c) != 0; };
  if (!std::all_of(stem.begin(), stem.begin() + static_cast<std::ptrdiff_t>(dot), digit) ||
      !std::all_of(stem.begin() + static_cast<std::ptrdiff_t>(dot) + 1, stem.end(), digit)) {
    return std::nullopt;
  }
  return core::Timestamp::parse_seconds(stem);
}

// One time per frame: from `times_path` (one time in seconds per line) when it exists; else, when
// `from_names`, from the file names if every one is a time (time_from_name) and they increase;
// else 0.1 s apart (KITTI's 10 Hz), said in seq.notes.
std::vector<core::Timestamp> frame_times(const fs::path& times_path, const std::vector<std::string>& names, bool from_names,
                                         ImageSequence& seq) {
  std::vector<core::Timestamp> stamps;
  std::error_code ec;
  if (fs::exists(times_path, ec)) {
    TextReader reader(times_path.string());
    while (reader.next_line()) {
      if (is_blank_or_comment(reader.line())) continue;
      const auto tokens = split_whitespace(reader.line());
      if (tokens.size() != 1) reader.fail("expected one time in seconds per line");
      // Parsed to the nanosecond and bounded (Timestamp::from_seconds overflows beyond 9.2e9 s),
      // and compared as stored: two times less than 1 ns apart would be one stamp.
      const std::optional<core::Timestamp> t = core::Timestamp::parse_seconds(tokens[0]);
      if (!t) reader.fail("expected a time in seconds (a finite number at most 9.2e9 s from 0), found " + quote_token(tokens[0]));
      if (!stamps.empty() && !(*t > stamps.back())) {
        reader.fail("times must increase strictly (to the nanosecond): " + t->to_seconds_string() + " s follows " +
                    stamps.back().to_seconds_string() + " s");
      }
      stamps.push_back(*t);
    }
    if (stamps.size() != names.size()) {
      throw ParseError(times_path.string(), 0, "expected one time per frame: " + std::to_string(names.size()) + " frames, " +
                                                   std::to_string(stamps.size()) + " times");
    }
    seq.times_from_file = true;
    return stamps;
  }
  if (from_names) {
    for (const std::string& name : names) {
      const std::optional<core::Timestamp> t = time_from_name(name);
      if (!t || (!stamps.empty() && !(*t > stamps.back()))) {
        stamps.clear();
        break;
      }
      stamps.push_back(*t);
    }
    if (!stamps.empty()) {
      seq.times_from_file = true;
      seq.notes.push_back("times taken from the image file names");
      return stamps;
    }
  }
  for (std::size_t k = 0; k < names.size(); ++k) stamps.push_back(core::Timestamp::from_nanoseconds(static_cast<std::int64_t>(k) * 100'000'000));
  seq.notes.push_back(from_names ? "no times.txt and the file names are not times: frames taken as 0.1 s apart"
                                 : "no times.txt: frames taken as 0.1 s apart (KITTI's 10 Hz)");
  return stamps;
}

}  // namespace

ImageSequence read_image_folder(const std::string& folder) {
  const fs::path dir(folder);
  ImageSequence seq;
  seq.layout = "folder";
  seq.folder = folder;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw ParseError(folder, 0, "not a folder");
  const fs::path left = dir / "left", right = dir / "right";
  std::vector<std::string> names;
  if (fs::is_directory(left, ec) && fs::is_directory(right, ec)) {
    seq.kind = SequenceKind::kStereo;
    names = paired_stereo_names(left, right, seq);
  } else {
    seq.kind = SequenceKind::kMonocular;
    for (const std::string& p : image_files_in(folder)) names.push_back(fs::path(p).filename().string());
  }
  const std::vector<core::Timestamp> stamps = frame_times(dir / "times.txt", names, true, seq);
  for (std::size_t k = 0; k < names.size(); ++k) {
    ImageFrame f;
    f.time = stamps[k];
    if (seq.kind == SequenceKind::kStereo) {
      f.image = (left / names[k]).string();
      f.right_image = (right / names[k]).string();
    } else {
      f.image = (dir / names[k]).string();
    }
    seq.frames.push_back(std::move(f));
  }
  return seq;
}

ImageSequence read_kitti_stereo(const std::string& folder) {
  const fs::path dir(folder);
  ImageSequence seq;
  seq.kind = SequenceKind::kStereo;
  seq.layout = "kitti";
  seq.folder = folder;
  std::error_code ec;
  fs::path left = dir / "image_0", right = dir / "image_1";
  if (!fs::is_directory(left, ec)) {
    left = dir / "image_l";
    right = dir / "image_r";
  }
  if (!fs::is_directory(left, ec) || !fs::is_directory(right, ec)) {
    throw ParseError(folder, 0, "expected image_0/ and image_1/ (or image_l/ and image_r/)");
  }
  seq.calibration = read_kitti_calibration((dir / "calib.txt").string());
  seq.calibration_from_dataset = true;
  const std::vector<std::string> names = paired_stereo_names(left, right, seq);
  const std::vector<core::Timestamp> stamps = frame_times(dir / "times.txt", names, false, seq);
  for (std::size_t k = 0; k < names.size(); ++k) {
    ImageFrame f;
    f.time = stamps[k];
    f.image = (left / names[k]).string();
    f.right_image = (right / names[k]).string();
    seq.frames.push_back(std::move(f));
  }
  const fs::path poses = dir / "poses.txt";
  if (fs::exists(poses, ec)) {
    Trajectory gt = read_kitti(poses.string());
    if (gt.size() != names.size()) {
      throw ParseError(poses.string(), 0, "expected one pose per frame: " + std::to_string(names.size()) + " frames, " +
                                              std::to_string(gt.size()) + " poses");
    }
    gt.stamps = stamps;
    seq.ground_truth = std::move(gt);
    seq.ground_truth_path = poses.string();
  }
  return seq;
}

std::vector<std::pair<core::Timestamp, std::string>> read_tum_image_list(const std::string& path) {
  TextReader reader(path);
  std::vector<std::pair<core::Timestamp, std::string>> out;
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const auto tokens = split_whitespace(reader.line());
    if (tokens.size() != 2) reader.fail("expected \"timestamp filename\", found " + std::to_string(tokens.size()) + " fields");
    const auto t = core::Timestamp::parse_seconds(tokens[0]);
    if (!t) reader.fail("expected a timestamp in seconds, found " + quote_token(tokens[0]));
    if (!out.empty() && !(out.back().first < *t)) reader.fail("timestamps must increase strictly");
    out.emplace_back(*t, std::string(tokens[1]));
  }
  if (out.empty()) throw ParseError(path, 0, "no images listed");
  return out;
}

ImageSequence read_tum_rgbd(const std::string& folder, double max_difference_s) {
  const fs::path dir(folder);
  ImageSequence seq;
  seq.kind = SequenceKind::kRgbd;
  seq.layout = "tum";
  seq.folder = folder;
  seq.times_from_file = true;
  std::error_code ec;
  const fs::path associations = dir / "associations.txt";
  if (fs::exists(associations, ec)) {
    TextReader reader(associations.string());
    while (reader.next_line()) {
      if (is_blank_or_comment(reader.line())) continue;
      const auto tokens = split_whitespace(reader.line());
      if (tokens.size() != 4) reader.fail("expected \"rgb_time rgb_file depth_time depth_file\", found " + std::to_string(tokens.size()) + " fields");
      const auto t = core::Timestamp::parse_seconds(tokens[0]);
      const auto td = core::Timestamp::parse_seconds(tokens[2]);
      if (!t || !td) reader.fail("expected timestamps in seconds in fields 1 and 3");
      if (!seq.frames.empty() && !(seq.frames.back().time < *t)) reader.fail("timestamps must increase strictly");
      ImageFrame f;
      f.time = *t;
      f.image = (dir / std::string(tokens[1])).string();
      f.depth_image = (dir / std::string(tokens[3])).string();
      seq.frames.push_back(std::move(f));
    }
    if (seq.frames.empty()) throw ParseError(associations.string(), 0, "no frames listed");
  } else {
    const auto rgb = read_tum_image_list((dir / "rgb.txt").string());
    const fs::path depth_path = dir / "depth.txt";
    if (!fs::exists(depth_path, ec)) throw ParseError(depth_path.string(), 0, "missing: an RGB-D sequence needs depth.txt or associations.txt");
    const auto depth = read_tum_image_list(depth_path.string());
    // associate.py: every pair within max_difference, closest first, each stamp used once.
    std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
    for (std::size_t i = 0; i < rgb.size(); ++i) {
      const double t = rgb[i].first.seconds();
      auto it = std::lower_bound(depth.begin(), depth.end(), t - max_difference_s,
                                 [](const auto& d, double v) { return d.first.seconds() < v; });
      for (; it != depth.end() && it->first.seconds() <= t + max_difference_s; ++it) {
        candidates.emplace_back(std::abs(it->first.seconds() - t), i, static_cast<std::size_t>(it - depth.begin()));
      }
    }
    std::sort(candidates.begin(), candidates.end());
    std::vector<bool> rgb_used(rgb.size()), depth_used(depth.size());
    std::vector<std::pair<std::size_t, std::size_t>> pairs;
    for (const auto& [dt, i, j] : candidates) {
      if (rgb_used[i] || depth_used[j]) continue;
      rgb_used[i] = depth_used[j] = true;
      pairs.emplace_back(i, j);
    }
    std::sort(pairs.begin(), pairs.end());
    for (const auto& [i, j] : pairs) {
      ImageFrame f;
      f.time = rgb[i].first;
      f.image = (dir / rgb[i].second).string();
      f.depth_image = (dir / depth[j].second).string();
      seq.frames.push_back(std::move(f));
    }
    const std::size_t dropped = rgb.size() - pairs.size();
    if (dropped > 0) seq.notes.push_back(std::to_string(dropped) + " colour images have no depth map within " + std::to_string(max_difference_s) + " s and are skipped");
    if (seq.frames.empty()) throw ParseError(depth_path.string(), 0, "no depth map lies within " + std::to_string(max_difference_s) + " s of a colour image");
  }
  const fs::path gt = dir / "groundtruth.txt";
  if (fs::exists(gt, ec)) {
    seq.ground_truth = read_tum(gt.string());
    seq.ground_truth_path = gt.string();
  }
  return seq;
}

namespace {

// The numbers of `key: [a, b, ...]` (the list may span lines) or, for T_BS, of its `data:` list.
// Returns the line of the key (0 when absent).
std::size_t yaml_list(const std::vector<std::string>& lines, const std::string& key, std::vector<double>& out, const std::string& path) {
  out.clear();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string line = lines[i].substr(0, lines[i].find('#'));
    const std::size_t k = line.find(key + ":");
    if (k == std::string::npos || line.find_first_not_of(" \t") != k) continue;
    std::string text = line.substr(k + key.size() + 1);
    std::size_t j = i;
    if (key == "T_BS") {
      // cols / rows / data lines follow; take the data list.
      for (j = i + 1; j < lines.size(); ++j) {
        const std::string l = lines[j].substr(0, lines[j].find('#'));
        const std::size_t d = l.find("data:");
        if (d != std::string::npos) {
          text = l.substr(d + 5);
          break;
        }
      }
      if (j == lines.size()) throw ParseError(path, i + 1, "T_BS has no data: list");
    }
    while (text.find(']') == std::string::npos) {
      if (++j >= lines.size()) throw ParseError(path, i + 1, "the list of " + key + " is not closed by ']'");
      text += " " + lines[j].substr(0, lines[j].find('#'));
    }
    const std::size_t open = text.find('['), close = text.find(']');
    if (open == std::string::npos || close < open) throw ParseError(path, i + 1, "expected " + key + ": [numbers, ...]");
    std::string body = text.substr(open + 1, close - open - 1);
    std::replace(body.begin(), body.end(), ',', ' ');
    for (const std::string_view token : split_whitespace(body)) {
      char* end = nullptr;
      const std::string t(token);
      const double value = std::strtod(t.c_str(), &end);
      if (end != t.c_str() + t.size() || !std::isfinite(value)) throw ParseError(path, i + 1, key + ": expected a finite number, found " + quote_token(token));
      out.push_back(value);
    }
    return i + 1;
  }
  return 0;
}

}  // namespace

CameraCalibration read_euroc_camera(const std::string& path, core::SE3* T_body_camera) {
  std::vector<std::string> lines;
  {
    TextReader reader(path);
    while (reader.next_line()) lines.emplace_back(reader.line());
  }
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string l = lines[i].substr(0, lines[i].find('#'));
    if (l.find("camera_model:") != std::string::npos && l.find("pinhole") == std::string::npos) {
      throw ParseError(path, i + 1, "only camera_model: pinhole is supported");
    }
    if (l.find("distortion_model:") != std::string::npos && l.find("radial-tangential") == std::string::npos &&
        l.find("radtan") == std::string::npos) {
      throw ParseError(path, i + 1, "only distortion_model: radial-tangential is supported");
    }
  }
  std::vector<double> v;
  CameraCalibration c;
  std::size_t line = yaml_list(lines, "intrinsics", v, path);
  if (line == 0) throw ParseError(path, 0, "missing intrinsics: [fu, fv, cu, cv]");
  if (v.size() != 4) throw ParseError(path, line, "intrinsics: expected 4 numbers [fu, fv, cu, cv], found " + std::to_string(v.size()));
  c.fx = v[0];
  c.fy = v[1];
  c.cx = v[2];
  c.cy = v[3];
  line = yaml_list(lines, "distortion_coefficients", v, path);
  if (line > 0) {
    if (v.size() != 4 && v.size() != 5) throw ParseError(path, line, "distortion_coefficients: expected [k1, k2, p1, p2] (or 5 with k3)");
    c.k1 = v[0];
    c.k2 = v[1];
    c.p1 = v[2];
    c.p2 = v[3];
    if (v.size() == 5) c.k3 = v[4];
  }
  line = yaml_list(lines, "resolution", v, path);
  if (line > 0) {
    // Bounded before the conversion to int (beyond INT_MAX it is undefined behaviour).
    if (v.size() != 2 || !(v[0] >= 1.0) || !(v[1] >= 1.0) || !(v[0] <= 1e6) || !(v[1] <= 1e6) || v[0] != std::floor(v[0]) ||
        v[1] != std::floor(v[1])) {
      throw ParseError(path, line, "resolution: expected [width, height] in whole pixels from 1 to 1000000");
    }
    c.width = static_cast<int>(v[0]);
    c.height = static_cast<int>(v[1]);
  }
  line = yaml_list(lines, "T_BS", v, path);
  if (line == 0) throw ParseError(path, 0, "missing T_BS (the camera's pose in the body frame)");
  if (v.size() != 16) throw ParseError(path, line, "T_BS data: expected 16 numbers (4 x 4, row-major), found " + std::to_string(v.size()));
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r) {
    for (int k = 0; k < 4; ++k) T(r, k) = v[static_cast<std::size_t>(4 * r + k)];
  }
  if (const Eigen::Matrix3d R = T.topLeftCorner<3, 3>(); (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3) {
    throw ParseError(path, line, "T_BS: the rotation block is not a rotation");
  }
  if (T_body_camera) *T_body_camera = core::SE3::from_matrix(T);
  if (std::string p; !c.is_valid(&p)) throw ParseError(path, 0, p);
  return c;
}

ImageSequence read_euroc_stereo(const std::string& folder) {
  fs::path dir(folder);
  std::error_code ec;
  if (fs::is_directory(dir / "mav0", ec)) dir /= "mav0";
  ImageSequence seq;
  seq.kind = SequenceKind::kStereo;
  seq.layout = "euroc";
  seq.folder = folder;
  seq.times_from_file = true;
  StereoRig rig;
  rig.left = read_euroc_camera((dir / "cam0" / "sensor.yaml").string(), &rig.T_body_left);
  rig.right = read_euroc_camera((dir / "cam1" / "sensor.yaml").string(), &rig.T_body_right);
  auto read_list = [&](const fs::path& csv) {
    std::vector<std::pair<core::Timestamp, std::string>> out;
    TextReader reader(csv.string());
    while (reader.next_line()) {
      if (is_blank_or_comment(reader.line())) continue;
      const std::vector<std::string_view> f = split_fields(reader.line(), ',');
      if (f.size() != 2) reader.fail("expected \"timestamp [ns],filename\", found " + std::to_string(f.size()) + " fields");
      const auto t = core::Timestamp::parse_nanoseconds(f[0]);
      if (!t) reader.fail("expected a timestamp in integer nanoseconds, found " + quote_token(f[0]));
      if (!out.empty() && !(out.back().first < *t)) reader.fail("timestamps must increase strictly");
      std::string name(f[1]);
      while (!name.empty() && (name.back() == ' ' || name.back() == '\r')) name.pop_back();
      while (!name.empty() && name.front() == ' ') name.erase(name.begin());
      if (name.empty()) reader.fail("expected an image file name after the timestamp, found none");
      out.emplace_back(*t, (csv.parent_path() / "data" / name).string());
    }
    if (out.empty()) throw ParseError(csv.string(), 0, "no images listed");
    return out;
  };
  const auto left = read_list(dir / "cam0" / "data.csv");
  const auto right = read_list(dir / "cam1" / "data.csv");
  std::size_t j = 0, unpaired = 0;
  for (const auto& [t, path] : left) {
    while (j < right.size() && right[j].first < t) {
      ++j;
      ++unpaired;
    }
    if (j < right.size() && right[j].first == t) {
      ImageFrame frame;
      frame.time = t;
      frame.image = path;
      frame.right_image = right[j].second;
      seq.frames.push_back(std::move(frame));
      ++j;
    } else {
      ++unpaired;
    }
  }
  unpaired += right.size() - j;
  if (seq.frames.empty()) throw ParseError((dir / "cam1" / "data.csv").string(), 0, "no cam1 stamp equals a cam0 stamp: the pair cannot be formed");
  if (unpaired > 0) seq.notes.push_back(std::to_string(unpaired) + " images have no partner with the same stamp and are skipped");
  seq.calibration = rig.left;
  seq.calibration_from_dataset = true;
  seq.rig = rig;
  const fs::path gt = dir / "state_groundtruth_estimate0" / "data.csv";
  if (fs::exists(gt, ec)) {
    seq.ground_truth = read_euroc(gt.string());
    seq.ground_truth_path = gt.string();
  }
  return seq;
}

}  // namespace cairn::io
