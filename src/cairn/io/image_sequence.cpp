#include "cairn/io/image_sequence.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;

}  // namespace

bool is_image_file_name(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".bmp" ||
         ext == ".tif" || ext == ".tiff";
}

std::vector<std::string> image_files_in(const std::string& folder) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.is_regular_file(ec) && is_image_file_name(entry.path().string())) names.push_back(entry.path().string());
  }
  if (ec) throw ParseError(folder, 0, "cannot list the folder: " + ec.message());
  if (names.empty()) throw ParseError(folder, 0, "no images (.png, .jpg, .pgm, ...) in the folder");
  std::sort(names.begin(), names.end());
  return names;
}

std::string CameraCalibration::problems() const {
  std::string out;
  auto add = [&](const std::string& p) { out += (out.empty() ? "" : "; ") + p; };
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
  throw ParseError(folder, 0,
                   "not a known image sequence: expected calib.txt with image_0/ and image_1/ (or image_l/ and image_r/) "
                   "(KITTI odometry stereo), or rgb.txt / associations.txt (TUM RGB-D)");
}

CameraCalibration read_kitti_calibration(const std::string& path) {
  TextReader reader(path);
  std::vector<std::vector<double>> rows;
  std::vector<std::string> labels;
  std::optional<std::vector<double>> p0, p1;
  std::size_t unlabelled = 0;
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
    if (label == "P0" || (label.empty() && unlabelled == 0)) p0 = values;
    else p1 = values;
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
  if (!(c.baseline_m > 0.0)) {
    throw ParseError(path, 0, "P1[0,3] - P0[0,3] must be negative (camera 1 right of camera 0), found a baseline of " +
                                  std::to_string(c.baseline_m) + " m");
  }
  return c;
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
  const fs::path times = dir / "times.txt";
  std::vector<core::Timestamp> stamps;
  if (fs::exists(times, ec)) {
    TextReader reader(times.string());
    while (reader.next_line()) {
      if (is_blank_or_comment(reader.line())) continue;
      const auto tokens = split_whitespace(reader.line());
      if (tokens.size() != 1) reader.fail("expected one time in seconds per line");
      const double t = parse_double(reader, tokens[0], "a time in seconds");
      if (!stamps.empty() && !(t > stamps.back().seconds())) reader.fail("times must increase strictly");
      stamps.push_back(core::Timestamp::from_seconds(t));
    }
    if (stamps.size() != names.size()) {
      throw ParseError(times.string(), 0, "expected one time per frame: " + std::to_string(names.size()) + " frames, " +
                                              std::to_string(stamps.size()) + " times");
    }
    seq.times_from_file = true;
  } else {
    for (std::size_t k = 0; k < names.size(); ++k) stamps.push_back(core::Timestamp::from_nanoseconds(static_cast<std::int64_t>(k) * 100'000'000));
    seq.notes.push_back("no times.txt: frames taken as 0.1 s apart (KITTI's 10 Hz)");
  }
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

}  // namespace cairn::io
