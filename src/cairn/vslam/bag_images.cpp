#include "cairn/vslam/bag_images.hpp"

#include <algorithm>
#include <cstdio>
#include <optional>
#include <set>
#include <stdexcept>

#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/core/time.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vslam/camera_info_calibration.hpp"
#include "cairn/vslam/image_message.hpp"

namespace cairn::vslam {
namespace {

/// REP 118: 16UC1 depth is in millimetres.
constexpr double kRep118UnitsPerM = 1000.0;

/// What the pass found on one image topic.
struct TopicScan {
  std::string name;
  bool depth = false;                ///< read as depth (RGB-D's partner)
  std::vector<std::int64_t> stamps;  ///< header stamps, in log-time order
  std::string encoding;              ///< of the first message (raw encoding or compressed format)
  int width = 0, height = 0;         ///< of the first image
};

/// One camera's CameraInfo topic and its first message.
struct CameraInfoScan {
  std::string name;
  std::optional<std::size_t> topic;  ///< index into Bag::topics() when it exists
  std::optional<bag::CameraInfo> first;
  std::string missing;  ///< why there is none
};

struct Scan {
  TopicScan image, partner;
  CameraInfoScan info, right_info;
};

/// "0.02" for 20,000,000 ns.
std::string seconds_text(std::int64_t ns) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", static_cast<double>(ns) * 1e-9);
  return text;
}

std::string at_stamp(const std::string& topic, std::int64_t stamp_ns) {
  return topic + " @ " + core::Timestamp::from_nanoseconds(stamp_ns).to_seconds_string() + " s";
}

/// The CameraInfo topic `name`: named by `flag` (then it must exist: bag::choose_topic lists the
/// topics), or looked for beside `image_topic` (then its absence is said in `missing`).
CameraInfoScan find_camera_info(const bag::Bag& bag, const std::string& name, bool named, const std::string& image_topic,
                                const char* flag) {
  CameraInfoScan scan;
  scan.name = name;
  if (named) {
    scan.topic = bag::choose_topic(bag, name, {{"sensor_msgs/CameraInfo"}, "camera info", flag});
    return scan;
  }
  for (const std::size_t t : bag::topics_of_type(bag, {"sensor_msgs/CameraInfo"})) {
    if (bag.topics()[t].name == name) scan.topic = t;
  }
  if (!scan.topic) scan.missing = "no CameraInfo topic " + name + " (looked for beside " + image_topic + ")";
  return scan;
}

Scan prepare_scan(const bag::Bag& bag, const BagImageTopics& chosen) {
  Scan scan;
  scan.image.name = bag.topics()[chosen.image].name;
  if (chosen.partner) {
    scan.partner.name = bag.topics()[*chosen.partner].name;
    scan.partner.depth = chosen.kind == io::SequenceKind::kRgbd;
  }
  scan.info = find_camera_info(bag, chosen.camera_info_topic, chosen.camera_info_named, scan.image.name, "--camera-info-topic");
  if (chosen.kind == io::SequenceKind::kStereo) {
    scan.right_info = find_camera_info(bag, chosen.right_camera_info_topic, chosen.right_camera_info_named, scan.partner.name,
                                       "--right-camera-info-topic");
  }
  return scan;
}

bag::CameraInfo decode_camera_info(const bag::Bag& bag, bag::MessageDecoder& decoder, const bag::BagMessage& message) {
  try {
    return bag::to_camera_info(decoder.decode(message));
  } catch (const io::ParseError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw io::ParseError(bag.path(), 0, "topic " + bag.topics()[message.topic].name + " message at " +
                                            std::to_string(message.message.log_time_ns) + " ns: " + e.what());
  }
}

/// Records an image's stamp; the first image of the topic is decoded (its encoding or format
/// checked, a compressed image's size found), the others must have its encoding.
void scan_image(TopicScan& scan, const ImageMessage& message, const std::string& file) {
  const std::string where = at_stamp(scan.name, message.header().stamp_ns);
  if (scan.stamps.empty()) {
    scan.encoding = message.encoding();
    const cv::Mat image = scan.depth ? decode_depth(message, 1.0, file, where) : decode_gray(message, file, where);
    scan.width = image.cols;
    scan.height = image.rows;
  } else if (message.encoding() != scan.encoding) {
    throw io::ParseError(file, 0, where + ": encoding '" + message.encoding() + "' differs from the topic's first image's ('" +
                                      scan.encoding + "')");
  }
  scan.stamps.push_back(message.header().stamp_ns);
}

void check_decodable(bag::MessageDecoder& decoder, const bag::Bag& bag, const std::vector<std::size_t>& topics) {
  for (const std::size_t t : topics) {
    if (std::string why; !decoder.can_decode(t, &why)) {
      throw io::ParseError(bag.path(), 0, "topic " + bag.topics()[t].name + " (" + bag.topics()[t].type + ") cannot be decoded: " + why);
    }
  }
}

/// The one pass over the chosen topics: every image's stamp, each camera's first CameraInfo.
void scan_bag(bag::Bag& bag, bag::MessageDecoder& decoder, const BagImageTopics& chosen, Scan& scan) {
  std::vector<std::size_t> topics{chosen.image};
  if (chosen.partner) topics.push_back(*chosen.partner);
  for (const CameraInfoScan* info : {&scan.info, &scan.right_info}) {
    if (info->topic && std::find(topics.begin(), topics.end(), *info->topic) == topics.end()) topics.push_back(*info->topic);
  }
  check_decodable(decoder, bag, topics);
  const std::unique_ptr<bag::BagStream> stream = bag.read(topics);
  for (bag::BagMessage message; stream->next(&message);) {
    bool camera_info = false;
    for (CameraInfoScan* info : {&scan.info, &scan.right_info}) {
      if (!info->topic || message.topic != *info->topic) continue;
      camera_info = true;
      if (!info->first) info->first = decode_camera_info(bag, decoder, message);
    }
    if (camera_info) continue;
    TopicScan& image = message.topic == chosen.image ? scan.image : scan.partner;
    scan_image(image, decode_image_message(bag, decoder, message), bag.path());
  }
  if (scan.image.stamps.empty()) throw io::ParseError(bag.path(), 0, "topic " + scan.image.name + " has no message");
  if (chosen.partner && scan.partner.stamps.empty()) throw io::ParseError(bag.path(), 0, "topic " + scan.partner.name + " has no message");
}

/// A topic's stamps without repeats (the first of each kept, in order), and how many repeated.
std::vector<std::int64_t> unique_stamps(const TopicScan& scan, std::vector<std::string>& notes) {
  std::vector<std::int64_t> unique;
  std::set<std::int64_t> seen;
  for (const std::int64_t stamp : scan.stamps) {
    if (seen.insert(stamp).second) unique.push_back(stamp);
  }
  if (const std::size_t repeats = scan.stamps.size() - unique.size(); repeats > 0) {
    notes.push_back(std::to_string(repeats) + " images on " + scan.name + " repeat a stamp already seen on it: skipped");
  }
  return unique;
}

void append_frame(BagImages& out, std::int64_t image_ns, std::optional<std::int64_t> partner_ns) {
  io::ImageFrame frame;
  frame.time = core::Timestamp::from_nanoseconds(image_ns);
  frame.image = at_stamp(out.image_topic, image_ns);
  if (partner_ns) {
    (out.sequence.kind == io::SequenceKind::kStereo ? frame.right_image : frame.depth_image) = at_stamp(out.partner_topic, *partner_ns);
    out.partner_stamps_ns.push_back(*partner_ns);
  }
  out.sequence.frames.push_back(std::move(frame));
}

void note_unpaired(std::size_t count, const std::string& text, std::vector<std::string>& notes) {
  if (count > 0) notes.push_back(std::to_string(count) + " " + text);
}

/// The frames: every image (monocular), or the pairs (stereo: equal stamps; RGB-D: associate.py).
void make_frames(const Scan& scan, std::int64_t max_depth_offset_ns, const std::string& file, BagImages& out) {
  std::vector<std::string>& notes = out.sequence.notes;
  std::vector<std::int64_t> images = unique_stamps(scan.image, notes);
  if (out.sequence.kind == io::SequenceKind::kMonocular) {
    std::sort(images.begin(), images.end());
    for (const std::int64_t stamp : images) append_frame(out, stamp, std::nullopt);
    return;
  }
  const std::vector<std::int64_t> partners = unique_stamps(scan.partner, notes);
  const bool stereo = out.sequence.kind == io::SequenceKind::kStereo;
  const std::vector<StampPair> pairs = stereo ? pair_equal_stamps(images, partners) : associate_stamps(images, partners, max_depth_offset_ns);
  for (const StampPair& pair : pairs) append_frame(out, images[pair.first], partners[pair.second]);
  const std::string within = seconds_text(max_depth_offset_ns) + " s";
  note_unpaired(images.size() - pairs.size(), stereo ? "left images have no right image of the same stamp: skipped"
                                                     : "colour images have no depth image within " + within + ": skipped", notes);
  note_unpaired(partners.size() - pairs.size(), stereo ? "right images have no left image of the same stamp: skipped"
                                                       : "depth images are not paired with a colour image: unused", notes);
  if (pairs.empty()) {
    throw io::ParseError(file, 0, "no image on " + scan.image.name + " has a partner on " + scan.partner.name +
                                      (stereo ? " with the same header stamp" : " stamped within " + within));
  }
}

/// A CameraInfo that is not there (the topic, or a message on it) and what to do about it.
std::string missing_camera_info(const CameraInfoScan& info, bool stereo) {
  return (info.missing.empty() ? "no message on the CameraInfo topic " + info.name : info.missing) +
         ": name the CameraInfo topic with --camera-info-topic" + (stereo ? " and --right-camera-info-topic" : "") +
         ", or give the calibration with --calib FILE (or --camera)";
}

/// The camera of the CameraInfo(s); a problem (not an error yet) when there is none to use.
std::string camera_from_infos(const Scan& scan, io::SequenceKind kind, const std::string& file, io::CameraCalibration& c) {
  const bool stereo = kind == io::SequenceKind::kStereo;
  for (const CameraInfoScan* info : {&scan.info, &scan.right_info}) {
    if (info == &scan.right_info && !stereo) continue;
    if (!info->first) return missing_camera_info(*info, stereo);
  }
  const bag::CameraInfo& info = *scan.info.first;
  if (info.width != 0 && (info.width != static_cast<std::uint32_t>(scan.image.width) || info.height != static_cast<std::uint32_t>(scan.image.height))) {
    return "the CameraInfo on " + scan.info.name + " is for " + std::to_string(info.width) + " x " + std::to_string(info.height) +
           " images, those on " + scan.image.name + " are " + std::to_string(scan.image.width) + " x " + std::to_string(scan.image.height) +
           " (binning and regions of interest are not read): give the calibration with --calib FILE";
  }
  try {
    c = stereo ? camera_from_stereo_camera_infos(info, *scan.right_info.first, scan.image.name, scan.partner.name, file, scan.info.name,
                                                 scan.right_info.name)
               : camera_from_camera_info(info, scan.image.name, file, scan.info.name);
  } catch (const io::ParseError& e) {
    return e.detail();
  }
  return "";
}

/// RGB-D: the depth scale of the 16-bit images the reader makes, and the virtual baseline.
void set_depth_scale(const Scan& scan, const BagImageOptions& options, const std::string& file, BagImages& out) {
  io::CameraCalibration& c = out.sequence.calibration;
  if (scan.partner.width != scan.image.width || scan.partner.height != scan.image.height) {
    throw io::ParseError(file, 0, "the depth images on " + scan.partner.name + " are " + std::to_string(scan.partner.width) + " x " +
                                      std::to_string(scan.partner.height) + ", the colour images on " + scan.image.name + " " +
                                      std::to_string(scan.image.width) + " x " + std::to_string(scan.image.height) +
                                      ": the depth must be registered to the colour camera (a depth_registered topic)");
  }
  const double given = options.depth_units_per_m > 0.0 ? options.depth_units_per_m : 0.0;
  if (scan.partner.encoding == "32FC1") {
    c.depth_units_per_m = kFloatDepthUnitsPerM;
    out.float_depth_units_per_m = given > 0.0 ? given : 1.0;
  } else {
    c.depth_units_per_m = given > 0.0 ? given : kRep118UnitsPerM;
  }
  if (c.fx > 0.0) c.virtual_baseline_m = kRgbdBaselineTimesFxPx / c.fx;
}

void set_calibration(const Scan& scan, const BagImageOptions& options, const std::string& file, BagImages& out) {
  const io::SequenceKind kind = out.sequence.kind;
  io::CameraCalibration c;
  if (const std::string problem = camera_from_infos(scan, kind, file, c); !problem.empty()) {
    if (!options.calibration_given) throw io::ParseError(file, 0, problem);
    out.sequence.notes.push_back("CameraInfo not used (the calibration is given): " + problem.substr(0, problem.find(": name the")));
    c = io::CameraCalibration{};
  } else {
    out.sequence.calibration_from_dataset = true;
    out.calibration_source = "CameraInfo " + scan.info.name + (kind == io::SequenceKind::kStereo ? ", " + scan.right_info.name : "");
  }
  c.width = scan.image.width;
  c.height = scan.image.height;
  out.sequence.calibration = c;
  if (kind == io::SequenceKind::kRgbd) set_depth_scale(scan, options, file, out);
}

/// The topics read, for report.json and a note ("bag topics: left /stereo/left/image_raw (mono8), ...").
void describe_topics(const Scan& scan, BagImages& out) {
  const io::SequenceKind kind = out.sequence.kind;
  const bool stereo = kind == io::SequenceKind::kStereo;
  out.topics.emplace_back(stereo ? "left" : "image", scan.image.name);
  if (kind != io::SequenceKind::kMonocular) out.topics.emplace_back(stereo ? "right" : "depth", scan.partner.name);
  if (scan.info.first) out.topics.emplace_back("camera_info", scan.info.name);
  if (stereo && scan.right_info.first) out.topics.emplace_back("right_camera_info", scan.right_info.name);
  std::string text;
  for (const auto& [role, topic] : out.topics) {
    std::string encoding;
    if (topic == scan.image.name) encoding = " (" + scan.image.encoding + ")";
    if (topic == scan.partner.name) encoding = " (" + scan.partner.encoding + ")";
    text += (text.empty() ? "bag topics: " : ", ") + role + " " + topic + encoding;
  }
  text += "; images " + std::to_string(scan.image.width) + " x " + std::to_string(scan.image.height) + " pixels";
  out.sequence.notes.insert(out.sequence.notes.begin(), text);
}

}  // namespace

ImageMessage decode_image_message(const bag::Bag& bag, bag::MessageDecoder& decoder, const bag::BagMessage& message) {
  try {
    return to_image_message(decoder.decode(message), decoder.type(message.topic) == "sensor_msgs/CompressedImage");
  } catch (const io::ParseError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw io::ParseError(bag.path(), 0, "topic " + bag.topics()[message.topic].name + " message at " +
                                            std::to_string(message.message.log_time_ns) + " ns: " + e.what());
  }
}

BagImages read_bag_images(const std::string& path, const BagImageOptions& options) {
  bag::Bag bag = bag::Bag::open(path);
  bag::MessageDecoder decoder(bag);
  const BagImageTopics chosen = choose_image_topics(bag, decoder, options.topics);
  Scan scan = prepare_scan(bag, chosen);
  scan_bag(bag, decoder, chosen, scan);

  BagImages out;
  out.sequence.kind = chosen.kind;
  out.sequence.layout = "bag";
  out.sequence.folder = path;
  out.sequence.times_from_file = true;  // the header stamps
  out.sequence.notes = chosen.notes;
  out.image_topic = scan.image.name;
  out.partner_topic = scan.partner.name;
  make_frames(scan, options.max_depth_offset_ns, path, out);
  set_calibration(scan, options, path, out);
  describe_topics(scan, out);
  return out;
}

}  // namespace cairn::vslam
