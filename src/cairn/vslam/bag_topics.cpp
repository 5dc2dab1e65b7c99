#include "cairn/vslam/bag_topics.hpp"

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vslam/image_message.hpp"

namespace cairn::vslam {
namespace {

const std::vector<std::string> kImageTypes{"sensor_msgs/Image", "sensor_msgs/CompressedImage"};

/// An image topic as the automatic choice sees it.
struct Candidate {
  std::size_t topic = 0;
  std::string name;
  std::string encoding;  ///< of its first message: Image encoding or CompressedImage format ("" unknown)
  bool depth = false;
};

bool name_contains(const std::string& name, const char* word) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return lower.find(word) != std::string::npos;
}

/// The encoding (Image) or format (CompressedImage) of a topic's first message; "" when it has
/// none or it cannot be decoded (the run then says why when it reads the topic).
std::string first_encoding(bag::Bag& bag, bag::MessageDecoder& decoder, std::size_t topic) {
  if (!decoder.can_decode(topic)) return "";
  const std::unique_ptr<bag::BagStream> stream = bag.read({topic});
  bag::BagMessage message;
  if (!stream->next(&message)) return "";
  try {
    return to_image_message(decoder.decode(message), decoder.type(topic) == "sensor_msgs/CompressedImage").encoding();
  } catch (const std::runtime_error&) {  // io::ParseError too: a damaged message is reported when it is read
    return "";
  }
}

std::vector<Candidate> image_candidates(bag::Bag& bag, bag::MessageDecoder& decoder) {
  std::vector<Candidate> candidates;
  for (const std::size_t t : bag::topics_of_type(bag, kImageTypes)) {
    Candidate c{t, bag.topics()[t].name, first_encoding(bag, decoder, t), false};
    c.depth = c.encoding == "16UC1" || c.encoding == "32FC1" || is_compressed_depth_format(c.encoding) || name_contains(c.name, "depth");
    candidates.push_back(std::move(c));
  }
  return candidates;
}

[[noreturn]] void refuse_ambiguous(const bag::Bag& bag, const std::vector<Candidate>& candidates) {
  std::string listing;
  for (const Candidate& c : candidates) {
    listing += "\n  " + c.name + " (" + bag.topics()[c.topic].type + (c.encoding.empty() ? "" : ", " + c.encoding) +
               (c.depth ? ", depth" : "") + ")";
  }
  throw io::ParseError(bag.path(), 0, "cannot tell which images to track from the bag's " + std::to_string(candidates.size()) +
                                          " image topics:" + listing +
                                          "\nname them: --left-topic and --right-topic (rectified stereo), --image-topic and "
                                          "--depth-topic (RGB-D), or --image-topic alone (monocular)");
}

void note_unused(const std::vector<Candidate>& candidates, const char* what, BagImageTopics& out) {
  for (const Candidate& c : candidates) {
    if (c.topic == out.image || (out.partner && c.topic == *out.partner)) continue;
    out.notes.push_back((c.depth ? "depth topic " : "image topic ") + c.name + " is not used: " + what + " is tracked");
  }
}

/// The choice without topic flags (file comment).
BagImageTopics choose_automatically(bag::Bag& bag, bag::MessageDecoder& decoder) {
  const std::vector<Candidate> candidates = image_candidates(bag, decoder);
  if (candidates.empty()) bag::choose_topic(bag, "", {kImageTypes, "image", "--image-topic"});  // throws, listing the bag's topics
  std::vector<const Candidate*> visual, depth, left, right;
  for (const Candidate& c : candidates) {
    (c.depth ? depth : visual).push_back(&c);
    if (!c.depth && name_contains(c.name, "left")) left.push_back(&c);
    if (!c.depth && name_contains(c.name, "right")) right.push_back(&c);
  }
  BagImageTopics out;
  if (visual.size() == 2 && left.size() == 1 && right.size() == 1 && left.front() != right.front()) {
    out.kind = io::SequenceKind::kStereo;
    out.image = left.front()->topic;
    out.partner = right.front()->topic;
    note_unused(candidates, "stereo", out);
  } else if (visual.size() == 1 && depth.size() == 1) {
    out.kind = io::SequenceKind::kRgbd;
    out.image = visual.front()->topic;
    out.partner = depth.front()->topic;
  } else if (candidates.size() == 1 && visual.size() == 1) {
    out.kind = io::SequenceKind::kMonocular;
    out.image = visual.front()->topic;
  } else {
    refuse_ambiguous(bag, candidates);
  }
  return out;
}

BagImageTopics choose_named(bag::Bag& bag, const BagTopicRequest& request) {
  BagImageTopics out;
  if (!request.left_topic.empty()) {
    out.kind = io::SequenceKind::kStereo;
    out.image = bag::choose_topic(bag, request.left_topic, {kImageTypes, "left image", "--left-topic"});
    out.partner = bag::choose_topic(bag, request.right_topic, {kImageTypes, "right image", "--right-topic"});
  } else {
    out.image = bag::choose_topic(bag, request.image_topic, {kImageTypes, "image", "--image-topic"});
    out.kind = io::SequenceKind::kMonocular;
    if (!request.depth_topic.empty()) {
      out.kind = io::SequenceKind::kRgbd;
      out.partner = bag::choose_topic(bag, request.depth_topic, {kImageTypes, "depth image", "--depth-topic"});
    }
  }
  return out;
}

}  // namespace

bool BagTopicRequest::is_valid(std::string* why) const {
  core::Problems problems;
  const bool stereo = !left_topic.empty() || !right_topic.empty();
  if (left_topic.empty() != right_topic.empty()) problems.add("--left-topic and --right-topic go together (a stereo pair)");
  if (stereo && (!image_topic.empty() || !depth_topic.empty())) {
    problems.add("--left-topic / --right-topic (stereo) and --image-topic / --depth-topic (RGB-D or monocular) exclude each other");
  }
  if (!depth_topic.empty() && image_topic.empty()) problems.add("--depth-topic needs --image-topic (the colour images its depth goes with)");
  if (!right_camera_info_topic.empty() && !image_topic.empty()) problems.add("--right-camera-info-topic goes with stereo, not --image-topic");
  if (!left_topic.empty() && left_topic == right_topic) problems.add("--left-topic and --right-topic name the same topic");
  if (!image_topic.empty() && image_topic == depth_topic) problems.add("--image-topic and --depth-topic name the same topic");
  return problems.report(why);
}

std::string sibling_camera_info_topic(const std::string& image_topic) {
  std::string topic = image_topic;
  for (const std::string suffix : {"/compressed", "/compressedDepth"}) {
    if (topic.ends_with(suffix)) topic.resize(topic.size() - suffix.size());
  }
  const std::size_t slash = topic.rfind('/');
  return (slash == std::string::npos ? std::string() : topic.substr(0, slash + 1)) + "camera_info";
}

BagImageTopics choose_image_topics(bag::Bag& bag, bag::MessageDecoder& decoder, const BagTopicRequest& request) {
  const bool named = !request.left_topic.empty() || !request.image_topic.empty();
  BagImageTopics out = named ? choose_named(bag, request) : choose_automatically(bag, decoder);
  out.camera_info_named = !request.camera_info_topic.empty();
  out.camera_info_topic = out.camera_info_named ? request.camera_info_topic : sibling_camera_info_topic(bag.topics()[out.image].name);
  if (out.kind == io::SequenceKind::kStereo) {
    out.right_camera_info_named = !request.right_camera_info_topic.empty();
    out.right_camera_info_topic =
        out.right_camera_info_named ? request.right_camera_info_topic : sibling_camera_info_topic(bag.topics()[*out.partner].name);
  }
  return out;
}

}  // namespace cairn::vslam
