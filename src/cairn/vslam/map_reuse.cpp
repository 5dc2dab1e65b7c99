// Map reuse (ORB-SLAM3's Atlas save / load and ORB-SLAM2's localisation mode, Mur-Artal & Tardos,
// T-RO 2017, Sec. III-F "Localization Mode"; System::ActivateLocalizationMode): the main map
// segment exported as a SavedVisualMap, and a VisualSlam built from one that only tracks (no
// keyframe, no point, no loop, no new segment; relocalisation by bag of words when lost).

#include <cstring>
#include <stdexcept>

#include "cairn/core/problems.hpp"
#include "cairn/vslam/saved_map.hpp"
#include "cairn/vslam/slam_state.hpp"

namespace cairn::vslam {

namespace {

std::array<std::uint8_t, 32> descriptor_bytes(const unsigned char* row) {
  std::array<std::uint8_t, 32> d{};
  std::memcpy(d.data(), row, 32);
  return d;
}

VocabularyIdentity identity_of(const vision::Vocabulary* vocabulary) {
  VocabularyIdentity id;
  if (!vocabulary) return id;
  id.fingerprint = vocabulary->fingerprint();
  id.words = static_cast<std::uint32_t>(vocabulary->words());
  id.branching = vocabulary->branching();
  id.depth = vocabulary->depth();
  return id;
}

std::string describe(const VocabularyIdentity& id) {
  if (id.words == 0) return "none";
  char buffer[128];
  std::snprintf(buffer, sizeof buffer, "k=%d L=%d, %u words, fingerprint %016llx", id.branching, id.depth, id.words,
                static_cast<unsigned long long>(id.fingerprint));
  return buffer;
}

bool near(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max(1.0, std::max(std::abs(a), std::abs(b))); }

}  // namespace

namespace {

SavedKeypoint saved_keypoint(const FrameData& f, std::size_t i) {
  SavedKeypoint kp;
  kp.x = f.keypoints[i].pt.x;
  kp.y = f.keypoints[i].pt.y;
  kp.size = f.keypoints[i].size;
  kp.angle = f.keypoints[i].angle;
  kp.response = f.keypoints[i].response;
  kp.octave = f.keypoints[i].octave;
  kp.undistorted_x = f.undistorted[i].x();
  kp.undistorted_y = f.undistorted[i].y();
  kp.u_right = f.u_right[i];
  kp.depth = f.depth[i];
  kp.descriptor = descriptor_bytes(f.descriptors.ptr(static_cast<int>(i)));
  return kp;
}

// A point as saved, without its observations (added as its keypoints are met).
SavedMapPoint saved_point(const MapPoint& mp) {
  SavedMapPoint p;
  p.p_world = mp.p_world;
  p.normal = mp.normal;
  p.min_distance = mp.min_distance;
  p.max_distance = mp.max_distance;
  p.descriptor = descriptor_bytes(mp.descriptor.ptr(0));
  p.visible = std::max(1, mp.visible);
  p.found = std::clamp(mp.found, 0, p.visible);
  p.reference_keyframe = -1;
  return p;
}

// Keyframe pairs and the saved points both observe (ORB-SLAM2's covisibility weights).
std::vector<SavedCovisibility> covisibility_of(const std::vector<SavedMapPoint>& points) {
  std::map<std::pair<int, int>, int> shared;
  for (const SavedMapPoint& p : points) {
    for (std::size_t a = 0; a < p.observations.size(); ++a) {
      for (std::size_t b = a + 1; b < p.observations.size(); ++b) {
        const int ka = p.observations[a].keyframe, kb = p.observations[b].keyframe;
        ++shared[{std::min(ka, kb), std::max(ka, kb)}];
      }
    }
  }
  std::vector<SavedCovisibility> edges;
  for (const auto& [pair, n] : shared) edges.push_back({pair.first, pair.second, n});
  return edges;
}

}  // namespace

// The main segment's good keyframes, renumbered in order, then their keypoints and points
// (export_keyframe_observations), then the covisibility those observations give.
SavedVisualMap VisualSlam::Impl::export_main_segment() const {
  SavedVisualMap map;
  map.kind = kind;
  map.camera = camera;
  map.camera.width = width;
  map.camera.height = height;
  map.orb = options.orb;
  map.close_depth_m = close_depth_m;
  map.vocabulary = identity_of(options.vocabulary.get());
  if (keyframes.empty()) return map;
  const int main = segment_of(0);
  std::vector<int> keyframe_index(keyframes.size(), -1);
  for (const KeyFrame& kf : keyframes) {
    if (kf.bad || segment_of(kf.id) != main) continue;
    keyframe_index[static_cast<std::size_t>(kf.id)] = static_cast<int>(map.keyframes.size());
    SavedKeyframe saved;
    saved.time_ns = kf.frame.time.nanoseconds();
    saved.frame = kf.frame.index;
    saved.T_world_camera = kf.frame.T_world_camera;
    map.keyframes.push_back(std::move(saved));
  }
  std::unordered_map<int, int> point_index;
  for (const KeyFrame& kf : keyframes) {
    if (const int k = keyframe_index[static_cast<std::size_t>(kf.id)]; k >= 0) export_keyframe_observations(kf, k, map, point_index);
  }
  map.covisibility = covisibility_of(map.points);
  return map;
}

// Keyframe `kf` (saved as index k): every keypoint, and its map point taken from the keyframe
// (what tracking's local map uses) when that point is good and observes it back, so that the
// saved observations and keypoints agree by construction. `point_index`: Impl point id -> saved.
void VisualSlam::Impl::export_keyframe_observations(const KeyFrame& kf, int k, SavedVisualMap& map, std::unordered_map<int, int>& point_index) const {
  const FrameData& f = kf.frame;
  SavedKeyframe& saved = map.keyframes[static_cast<std::size_t>(k)];
  saved.keypoints.reserve(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    saved.keypoints.push_back(saved_keypoint(f, i));
    const int id = f.map_point[i];
    if (id < 0) continue;
    const MapPoint& mp = points[static_cast<std::size_t>(id)];
    const auto seen = mp.observations.find(kf.id);
    if (mp.bad || seen == mp.observations.end() || seen->second != static_cast<int>(i)) continue;
    const auto [it, inserted] = point_index.try_emplace(id, static_cast<int>(map.points.size()));
    if (inserted) map.points.push_back(saved_point(mp));
    SavedMapPoint& p = map.points[static_cast<std::size_t>(it->second)];
    p.observations.push_back({k, static_cast<std::int32_t>(i)});
    if (kf.id == mp.reference_keyframe || p.reference_keyframe < 0) p.reference_keyframe = k;
    saved.keypoints.back().map_point = it->second;
  }
}

namespace {

// A saved keyframe's frame: its keypoints, measurements, descriptors and map points as tracking
// holds them (the grid is built by the caller, which knows the image size).
FrameData frame_from_saved(const SavedKeyframe& saved) {
  FrameData f;
  f.index = saved.frame;
  f.time = core::Timestamp::from_nanoseconds(saved.time_ns);
  f.T_world_camera = saved.T_world_camera;
  const std::size_t n = saved.keypoints.size();
  f.keypoints.resize(n);
  f.undistorted.resize(n);
  f.u_right.resize(n);
  f.depth.resize(n);
  f.map_point.resize(n);
  f.outlier.assign(n, 0);
  f.descriptors.create(static_cast<int>(n), 32, CV_8U);
  for (std::size_t i = 0; i < n; ++i) {
    const SavedKeypoint& kp = saved.keypoints[i];
    f.keypoints[i] = cv::KeyPoint(kp.x, kp.y, kp.size, kp.angle, kp.response, kp.octave);
    f.undistorted[i] = Eigen::Vector2d(kp.undistorted_x, kp.undistorted_y);
    f.u_right[i] = kp.u_right;
    f.depth[i] = kp.depth;
    f.map_point[i] = kp.map_point;
    std::memcpy(f.descriptors.ptr(static_cast<int>(i)), kp.descriptor.data(), 32);
  }
  return f;
}

MapPoint point_from_saved(const SavedMapPoint& saved, int keyframes) {
  MapPoint mp;
  mp.p_world = saved.p_world;
  mp.normal = saved.normal;
  mp.min_distance = saved.min_distance;
  mp.max_distance = saved.max_distance;
  mp.descriptor = cv::Mat(1, 32, CV_8U);
  std::memcpy(mp.descriptor.ptr(0), saved.descriptor.data(), 32);
  mp.first_keyframe = keyframes;
  for (const SavedObservation& o : saved.observations) {
    mp.observations[o.keyframe] = o.keypoint;
    mp.first_keyframe = std::min(mp.first_keyframe, static_cast<int>(o.keyframe));
  }
  mp.reference_keyframe = saved.reference_keyframe;
  mp.visible = saved.visible;
  mp.found = saved.found;
  return mp;
}

}  // namespace

// The saved keyframes and points as the tracker's own, one segment (keyframe 0 its anchor), the
// keyframes' words in the place-recognition database, and the tracker lost: the first frame
// relocalises (bag of words, PnP, the local map, the uniqueness test) as after any loss.
void VisualSlam::Impl::import_map(const SavedVisualMap& map) {
  set_image_size(map.camera.width, map.camera.height);
  keyframes.reserve(map.keyframes.size());
  for (std::size_t k = 0; k < map.keyframes.size(); ++k) {
    KeyFrame kf;
    kf.id = static_cast<int>(k);
    kf.segment = 0;
    kf.starts_segment = k == 0;
    kf.frame = frame_from_saved(map.keyframes[k]);
    build_grid(kf.frame);
    if (options.vocabulary) {
      kf.bow = options.vocabulary->transform(kf.frame.descriptors, nullptr, &kf.nodes, bow_levels_up());
      database.add(static_cast<std::uint32_t>(k), kf.bow);
    }
    keyframes.push_back(std::move(kf));
  }
  points.reserve(map.points.size());
  for (const SavedMapPoint& saved : map.points) points.push_back(point_from_saved(saved, static_cast<int>(map.keyframes.size())));
  lost = true;
  reference_keyframe = -1;
}

std::string map_incompatibility(const SavedVisualMap& map, const io::CameraCalibration& camera, io::SequenceKind kind,
                                const vision::Vocabulary* vocabulary) {
  core::Problems problems;
  if (map.kind != kind) {
    problems.add("the map was made from " + std::string(io::to_string(map.kind)) + " images, these are " + std::string(io::to_string(kind)));
  }
  const io::CameraCalibration& m = map.camera;
  const bool same_camera = near(m.fx, camera.fx) && near(m.fy, camera.fy) && near(m.cx, camera.cx) && near(m.cy, camera.cy) && near(m.k1, camera.k1) &&
                           near(m.k2, camera.k2) && near(m.p1, camera.p1) && near(m.p2, camera.p2) && near(m.k3, camera.k3) &&
                           (kind != io::SequenceKind::kStereo || near(m.baseline_m, camera.baseline_m)) &&
                           (kind != io::SequenceKind::kRgbd || near(m.depth_units_per_m, camera.depth_units_per_m));
  if (!same_camera) {
    char buffer[256];
    std::snprintf(buffer, sizeof buffer, "the map's camera (fx %.6g fy %.6g cx %.6g cy %.6g) is not this calibration (fx %.6g fy %.6g cx %.6g cy %.6g, or its distortion, baseline or depth scale differ)",
                  m.fx, m.fy, m.cx, m.cy, camera.fx, camera.fy, camera.cx, camera.cy);
    problems.add(buffer);
  }
  if (camera.width > 0 && camera.height > 0 && (camera.width != m.width || camera.height != m.height)) {
    problems.add("the map's images are " + std::to_string(m.width) + " x " + std::to_string(m.height) + ", these " + std::to_string(camera.width) +
                 " x " + std::to_string(camera.height));
  }
  if (map.vocabulary.words > 0 && !vocabulary) {
    problems.add("the map was indexed with a vocabulary (" + describe(map.vocabulary) + "): give one (--vocabulary) to relocalise in it");
  }
  std::string why;
  problems.report(&why);
  return why;
}

std::string vocabulary_mismatch(const SavedVisualMap& map, const vision::Vocabulary* vocabulary) {
  const VocabularyIdentity given = identity_of(vocabulary);
  if (map.vocabulary.words == 0 || given.words == 0 || given == map.vocabulary) return "";
  return "the map was indexed with another vocabulary (" + describe(map.vocabulary) + ") than the one given (" + describe(given) +
         "): the keyframes' words are recomputed with the one given";
}

SavedVisualMap VisualSlam::saved_map(std::string configuration_json, std::string source) const {
  impl_->join_local_mapping(nullptr);
  SavedVisualMap map = impl_->export_main_segment();
  if (map.keyframes.empty()) throw std::logic_error("VisualSlam::saved_map: no keyframe yet: nothing to save");
  map.configuration_json = std::move(configuration_json);
  map.source = std::move(source);
  return map;
}

namespace {
// The options a localisation runs with: the caller's, but the map's ORB settings (its keypoints'
// levels and descriptors must mean the same), and nothing that adds to the map.
VisualSlamOptions localisation_options(const SavedVisualMap& map, VisualSlamOptions options) {
  options.orb = map.orb;
  options.loop_closure = false;
  options.new_map_after_lost_frames = 0;
  options.merge_recent_keyframes_of_new_map = 0;
  return options;
}
}  // namespace

VisualSlam::VisualSlam(const SavedVisualMap& map, const VisualSlamOptions& options) : options_(localisation_options(map, options)) {
  if (std::string p; !options_.is_valid(&p)) throw std::invalid_argument("visual SLAM options: " + p);
  if (map.keyframes.empty()) throw std::invalid_argument("the saved map has no keyframe");
  if (const std::string p = map_incompatibility(map, map.camera, map.kind, options_.vocabulary.get()); !p.empty()) {
    throw std::invalid_argument("cannot localise in this map: " + p);
  }
  impl_ = std::make_unique<Impl>(map.camera, map.kind, options_);
  impl_->summary = &summary_;
  impl_->localization_only = true;
  impl_->close_depth_m = map.close_depth_m;
  impl_->import_map(map);
}

bool VisualSlam::localization_only() const { return impl_->localization_only; }

}  // namespace cairn::vslam
