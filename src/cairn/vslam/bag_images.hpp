#pragma once
/// \file
/// `cairn vslam BAG`: the images of a bag (anything bag::Bag opens: a ROS 1 .bag, an MCAP file, a
/// rosbag2 folder) as the image sequence a run takes, its frames paired and its camera calibrated
/// from the bag alone.
///
/// * Topics: vslam/bag_topics.hpp (flags, or the bag's image topics) decides stereo, RGB-D or
///   monocular.
/// * Frames: one per left / colour image, at its header stamp; stereo pairs by equal stamps,
///   colour and depth as TUM's associate.py (vslam/stamp_pairing.hpp). Images without a partner,
///   and repeats of a stamp already seen on their topic, are skipped and counted in the notes.
/// * Camera: the CameraInfo of each camera (vslam/camera_info_calibration.hpp), sized as the
///   first image. Depth units per metre (REP 118): 16UC1 is millimetres (1000), 32FC1 metres,
///   unless the caller says otherwise (the TUM RGB-D files keep 5000 per metre). The virtual
///   baseline of an RGB-D camera is ORB-SLAM2's bf = 40 pixels over fx (TUM1.yaml).
///
/// This pass decodes every image message of the chosen topics once, keeping only its stamp (and
/// the first one's size): the images themselves are read by BagFrameReader
/// (vslam/bag_frame_reader.hpp), which streams the bag again.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vslam/bag_topics.hpp"
#include "cairn/vslam/image_message.hpp"
#include "cairn/vslam/stamp_pairing.hpp"

namespace cairn::vslam {

/// ORB-SLAM2's bf for RGB-D cameras (TUM1.yaml, as io::tum_calibration_preset): the virtual
/// baseline is this over fx, in metres.
inline constexpr double kRgbdBaselineTimesFxPx = 40.0;

struct BagImageOptions {
  BagTopicRequest topics;
  /// Units per metre of the depth values as stored: for 16UC1, REP 118's millimetres (1000); for
  /// 32FC1, REP 118's metres (1). 0 = REP 118's.
  double depth_units_per_m = 0.0;
  /// RGB-D: a colour image and a depth image stamped closer than this are one frame, ns.
  std::int64_t max_depth_offset_ns = kMaxDepthOffsetNs;
  /// The calibration comes from elsewhere (cairn vslam --calib, --camera): a CameraInfo that is
  /// missing or cannot be used is then a note, not an error.
  bool calibration_given = false;
};

struct BagImages {
  /// layout "bag", folder = the bag's path, the kind chosen; frames at the left / colour image's
  /// header stamp, labelled "<topic> @ <stamp> s"; the calibration from the CameraInfo (size and
  /// depth scale set even without one); notes: topics, skipped images, unused CameraInfo.
  io::ImageSequence sequence;
  std::string image_topic;    ///< left, colour or only images
  std::string partner_topic;  ///< right (stereo) or depth (RGB-D) images; "" for monocular
  /// Stereo, RGB-D: the stamp of each frame's right or depth image.
  std::vector<std::int64_t> partner_stamps_ns;
  /// 32FC1 depth: its values per metre (converted to 16-bit at kFloatDepthUnitsPerM, which is
  /// then sequence.calibration.depth_units_per_m).
  double float_depth_units_per_m = 1.0;
  /// Each topic read and what it is ("left", "right", "image", "depth", "camera_info",
  /// "right_camera_info"), for report.json.
  std::vector<std::pair<std::string, std::string>> topics;
  /// "CameraInfo <topic>[, <topic>]" when the calibration came from the bag, else "".
  std::string calibration_source;
};

/// Opens the bag at `path` and reads the sequence of its image topics (above). Throws
/// io::ParseError naming the bag: topics as vslam/bag_topics.hpp says; an image encoding or
/// format cairn does not decode (named, with those it does); a missing CameraInfo (naming the
/// topic looked for and --camera-info-topic) unless options.calibration_given; depth images of
/// another size than the colour ones; no frame left after pairing.
/// Precondition: options.topics.is_valid().
BagImages read_bag_images(const std::string& path, const BagImageOptions& options);

/// A message of an image topic, decoded. Throws io::ParseError naming the bag, the topic and the
/// message's log time when it does not decode or lacks a field of its type.
ImageMessage decode_image_message(const bag::Bag& bag, bag::MessageDecoder& decoder, const bag::BagMessage& message);

}  // namespace cairn::vslam
