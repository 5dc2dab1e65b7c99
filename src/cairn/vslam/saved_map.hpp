#pragma once
/// \file
/// A visual map as `cairn vslam --save-map` saves it and `cairn vslam --localize-in` reuses it
/// (ORB-SLAM3's Atlas save / load, Campos et al., T-RO 2021, and its localisation mode): the
/// camera and the ORB settings the map was made with, the vocabulary's identity, the keyframes
/// (pose, keypoints with their stereo / depth measurements and descriptors, which map point each
/// keypoint observes) and the map points (position, representative descriptor, viewing direction
/// and scale-invariance distances, observations), and the covisibility graph (keyframe pairs and
/// the points they share). Only the main map segment is saved (docs/vslam.md, "Saving a map and
/// localising in it"). The file: map_file.hpp; byte by byte: docs/formats.md, "cairn visual map".
///
/// Frames: T_world_camera, world = the mapping run's first camera (x right, y down, z forward).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"

namespace cairn::vslam {

/// Which vocabulary the map's keyframes were indexed with. Localising needs the same one: bag-of-
/// words vectors of two vocabularies cannot be compared. `fingerprint` 0 and `words` 0: the map
/// was made without a vocabulary.
struct VocabularyIdentity {
  std::uint64_t fingerprint = 0;  ///< vision::Vocabulary::fingerprint()
  std::uint32_t words = 0;
  std::int32_t branching = 0, depth = 0;
  bool operator==(const VocabularyIdentity&) const = default;
};

struct SavedKeypoint {
  float x = 0.0f, y = 0.0f;  ///< level-0 pixels of the distorted image (cv::KeyPoint::pt)
  float size = 0.0f, angle = 0.0f, response = 0.0f;
  std::int32_t octave = 0;   ///< pyramid level, 0 .. orb.levels - 1
  double undistorted_x = 0.0, undistorted_y = 0.0;
  double u_right = -1.0;     ///< stereo: right-image x (or the virtual one from depth); < 0 none
  double depth = -1.0;       ///< metres; < 0 none
  std::int32_t map_point = -1;  ///< index into SavedVisualMap::points, or -1
  std::array<std::uint8_t, 32> descriptor{};
};

struct SavedKeyframe {
  std::int64_t time_ns = 0;  ///< the frame's timestamp, nanoseconds (core::Timestamp, exact)
  std::uint64_t frame = 0;  ///< the frame's index in the mapping run
  core::SE3 T_world_camera;
  std::vector<SavedKeypoint> keypoints;
};

struct SavedObservation {
  std::int32_t keyframe = 0;  ///< index into SavedVisualMap::keyframes
  std::int32_t keypoint = 0;  ///< index into that keyframe's keypoints
};

struct SavedMapPoint {
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< mean viewing direction, unit
  double min_distance = 0.0, max_distance = 0.0;      ///< scale-invariance distances (ORB-SLAM2), 0 <= min <= max
  std::array<std::uint8_t, 32> descriptor{};
  std::int32_t reference_keyframe = 0;
  std::int32_t visible = 1, found = 1;  ///< tracking statistics (found <= visible)
  std::vector<SavedObservation> observations;  ///< at least one
};

struct SavedCovisibility {
  std::int32_t a = 0, b = 0;  ///< keyframes, a < b
  std::int32_t shared = 0;    ///< map points both observe, >= 1
};

struct SavedVisualMap {
  io::SequenceKind kind = io::SequenceKind::kStereo;
  io::CameraCalibration camera;  ///< width and height set
  vision::OrbOptions orb;
  /// Points nearer than this many metres are "close" (VisualSlam's ThDepth in metres).
  double close_depth_m = 0.0;
  VocabularyIdentity vocabulary;
  std::vector<SavedKeyframe> keyframes;  ///< at least one; keyframe 0 holds the gauge
  std::vector<SavedMapPoint> points;
  std::vector<SavedCovisibility> covisibility;
  std::string configuration_json;  ///< the mapping run's options (cairn vslam's config), for the record
  std::string source;              ///< what was mapped (the input path), for the record
};

}  // namespace cairn::vslam
