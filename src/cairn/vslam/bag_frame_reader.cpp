#include "cairn/vslam/bag_frame_reader.hpp"

#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/core/time.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::vslam {
namespace {

/// One image topic as the reader follows it: which frame each stamp belongs to, the images held.
struct TopicImages {
  std::size_t topic = 0;  ///< index into Bag::topics()
  std::unordered_map<std::int64_t, std::size_t> frame_of_stamp;
  std::map<std::size_t, cv::Mat> held;  ///< by frame
};

}  // namespace

struct BagFrameReader::Stream {
  explicit Stream(const std::string& path) : bag(bag::Bag::open(path)), decoder(bag) {}

  bag::Bag bag;
  bag::MessageDecoder decoder;  // refers to `bag`: a Stream never moves (held by unique_ptr)
  std::unique_ptr<bag::BagStream> messages;
  TopicImages image;
  std::optional<TopicImages> partner;  ///< right or depth images; none when monocular
};

BagFrameReader::BagFrameReader(const BagImages& images, io::SequenceKind kind)
    : images_(images), kind_(kind), stream_(std::make_unique<Stream>(images.sequence.folder)) {
  Stream& s = *stream_;
  const std::vector<io::ImageFrame>& frames = images.sequence.frames;
  s.image.topic = s.bag.topic_index(images.image_topic);
  for (std::size_t k = 0; k < frames.size(); ++k) s.image.frame_of_stamp.emplace(frames[k].time.nanoseconds(), k);
  std::vector<std::size_t> topics{s.image.topic};
  if (kind_ != io::SequenceKind::kMonocular) {
    s.partner.emplace();
    s.partner->topic = s.bag.topic_index(images.partner_topic);
    for (std::size_t k = 0; k < images.partner_stamps_ns.size(); ++k) s.partner->frame_of_stamp.emplace(images.partner_stamps_ns[k], k);
    topics.push_back(s.partner->topic);
  }
  s.messages = s.bag.read(topics);
}

BagFrameReader::~BagFrameReader() = default;

bool BagFrameReader::pull() {
  Stream& s = *stream_;
  bag::BagMessage message;
  if (!s.messages->next(&message)) return false;
  TopicImages& topic = message.topic == s.image.topic ? s.image : *s.partner;
  const ImageMessage decoded = decode_image_message(s.bag, s.decoder, message);
  const std::int64_t stamp_ns = decoded.header().stamp_ns;
  const auto frame = topic.frame_of_stamp.find(stamp_ns);
  // Unpaired, a frame already read, or a repeat of a stamp held: not needed.
  if (frame == topic.frame_of_stamp.end() || frame->second < next_ || topic.held.contains(frame->second)) return true;
  const std::string& name = s.bag.topics()[topic.topic].name;
  const std::string where = name + " @ " + core::Timestamp::from_nanoseconds(stamp_ns).to_seconds_string() + " s";
  const std::string& file = images_.sequence.folder;
  const bool depth = &topic != &s.image && kind_ == io::SequenceKind::kRgbd;
  cv::Mat image = depth ? decode_depth(decoded, images_.float_depth_units_per_m, file, where) : decode_gray(decoded, file, where);
  const io::CameraCalibration& c = images_.sequence.calibration;
  if (c.width > 0 && (image.cols != c.width || image.rows != c.height)) {
    throw io::ParseError(file, 0, where + ": the image is " + std::to_string(image.cols) + " x " + std::to_string(image.rows) +
                                      " pixels, expected " + std::to_string(c.width) + " x " + std::to_string(c.height) +
                                      " as the calibration and the first image");
  }
  topic.held.emplace(frame->second, std::move(image));
  return true;
}

FrameImages BagFrameReader::read(std::size_t frame_index) {
  if (frame_index != next_) throw std::logic_error("BagFrameReader: a bag's frames are read in order");
  const auto read_start = core::Clock::now();
  Stream& s = *stream_;
  const io::ImageFrame& frame = images_.sequence.frames.at(frame_index);
  while (!s.image.held.contains(frame_index) || (s.partner && !s.partner->held.contains(frame_index))) {
    if (!pull()) {
      throw io::ParseError(images_.sequence.folder, 0, "the bag ended before the images of frame " + std::to_string(frame_index) + " (" +
                                                           frame.image + (s.partner ? " and its partner" : "") + ")");
    }
  }
  FrameImages images;
  images.kind = kind_;
  images.gray = std::move(s.image.held.at(frame_index));
  s.image.held.erase(frame_index);
  if (s.partner) {
    (kind_ == io::SequenceKind::kStereo ? images.right : images.depth) = std::move(s.partner->held.at(frame_index));
    s.partner->held.erase(frame_index);
  }
  ++next_;
  images.read_s = core::seconds_since(read_start);
  return images;
}

}  // namespace cairn::vslam
