#pragma once
/// \file
/// Which image topics of a bag `cairn vslam BAG` tracks, and so how. Image topics are
/// sensor_msgs/Image or sensor_msgs/CompressedImage.
///
/// * --left-topic and --right-topic: stereo (a rectified pair);
/// * --image-topic with --depth-topic: RGB-D; --image-topic alone: monocular;
/// * no topic flag: the bag's image topics decide. A depth topic is one whose first message has
///   encoding 16UC1 or 32FC1 (REP 118) or a compressedDepth format, or whose name contains
///   "depth"; the others are colour or grey. Two colour/grey topics, one named ...left... and the
///   other ...right...: stereo; one colour/grey topic and one depth topic: RGB-D; exactly one
///   image topic: monocular; anything else is refused, listing the image topics and the flags.
///
/// Each camera's calibration is its sensor_msgs/CameraInfo: --camera-info-topic (and
/// --right-camera-info-topic for the right camera), else the topic beside the image topic, as
/// image_transport and camera_info_manager lay them out (/camera/rgb/image_color ->
/// /camera/rgb/camera_info).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/io/image_sequence.hpp"

namespace cairn::vslam {

/// The topics a user named (empty: chosen as above).
struct BagTopicRequest {
  std::string left_topic;               ///< stereo, with right_topic
  std::string right_topic;
  std::string image_topic;              ///< RGB-D with depth_topic; alone, monocular
  std::string depth_topic;
  std::string camera_info_topic;        ///< the left or colour camera's CameraInfo; "" = beside its images
  std::string right_camera_info_topic;  ///< the right camera's; "" = beside its images

  /// False when the topics named do not make one of the three inputs ("--left-topic needs
  /// --right-topic"), with every problem in *why, "; "-separated.
  bool is_valid(std::string* why) const;
};

/// The topics chosen.
struct BagImageTopics {
  io::SequenceKind kind = io::SequenceKind::kMonocular;
  std::size_t image = 0;               ///< index into Bag::topics(): the left, colour or only images
  std::optional<std::size_t> partner;  ///< the right (stereo) or depth (RGB-D) images
  std::string camera_info_topic;       ///< where the left / colour camera's CameraInfo is looked for
  std::string right_camera_info_topic; ///< stereo: the right camera's
  bool camera_info_named = false;      ///< given by a flag (then it must exist)
  bool right_camera_info_named = false;
  /// Image topics left out ("depth topic /camera/depth/image is not used: stereo is tracked").
  std::vector<std::string> notes;
};

/// Chooses the topics as above; without topic flags, reads the first message of each image topic
/// to tell depth from colour. Throws io::ParseError naming the bag: a named topic that does not
/// exist (listing the bag's topics, bag::choose_topic) or is not an image topic; a bag without
/// image topics; image topics from which no choice follows (listing each with its encoding, and
/// the flags). Precondition: request.is_valid().
BagImageTopics choose_image_topics(bag::Bag& bag, bag::MessageDecoder& decoder, const BagTopicRequest& request);

/// The CameraInfo topic beside an image topic: "camera_info" in place of the last name, after a
/// "/compressed" or "/compressedDepth" transport suffix is dropped ("/camera/rgb/image_color" and
/// "/camera/rgb/image_color/compressed" -> "/camera/rgb/camera_info").
std::string sibling_camera_info_topic(const std::string& image_topic);

}  // namespace cairn::vslam
