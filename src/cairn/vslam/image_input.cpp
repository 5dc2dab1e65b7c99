#include "cairn/vslam/image_input.hpp"

#include <chrono>

#include "cairn/core/timer.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::vslam {

std::optional<vision::StereoRectifier> rectify_calibration(io::ImageSequence& sequence) {
  std::optional<vision::StereoRectifier> rectifier;
  if (!sequence.rig) return rectifier;
  int w = sequence.rig->left.width, h = sequence.rig->left.height;
  if (w <= 0 || h <= 0) {
    const cv::Mat first = vision::read_gray_image(sequence.frames.front().image);
    w = first.cols;
    h = first.rows;
  }
  rectifier.emplace(*sequence.rig, w, h);
  sequence.calibration = rectifier->rectified();
  return rectifier;
}

void check_calibration_plausible(const io::ImageSequence& sequence, bool stereo, const std::string& source) {
  if (sequence.frames.empty()) return;
  int first_width = sequence.calibration.width, first_height = sequence.calibration.height;
  if (first_width == 0 || first_height == 0) {
    const cv::Mat first = vision::read_gray_image(sequence.frames[0].image);
    first_width = first.cols;
    first_height = first.rows;
  }
  if (const std::string implausible = sequence.calibration.implausibilities(first_width, first_height, stereo); !implausible.empty()) {
    throw io::ParseError(source, 0, "implausible calibration: " + implausible);
  }
}

FrameReader::FrameReader(const io::ImageSequence& sequence, io::SequenceKind kind, const vision::StereoRectifier* rectifier)
    : sequence_(sequence),
      kind_(kind),
      rectifier_(rectifier),
      width_(sequence.calibration.width),
      height_(sequence.calibration.height) {}

FrameImages FrameReader::read(std::size_t frame_index) {
  const io::ImageFrame& frame = sequence_.frames[frame_index];
  const auto read_start = core::Clock::now();
  FrameImages images;
  images.gray = vision::read_gray_image(frame.image, width_, height_);
  width_ = images.gray.cols;
  height_ = images.gray.rows;
  if (kind_ == io::SequenceKind::kMonocular) {
    images.kind = io::SequenceKind::kMonocular;
    if (rectifier_) {
      cv::Mat unused, rectified;
      rectifier_->rectify(images.gray, images.gray, rectified, unused);
      images.gray = rectified;
    }
  } else if (sequence_.kind == io::SequenceKind::kStereo) {
    images.kind = io::SequenceKind::kStereo;
    images.right = vision::read_gray_image(frame.right_image, width_, height_);
    if (rectifier_) {
      cv::Mat left_rectified, right_rectified;
      rectifier_->rectify(images.gray, images.right, left_rectified, right_rectified);
      images.gray = left_rectified;
      images.right = right_rectified;
    }
  } else {
    images.kind = io::SequenceKind::kRgbd;
    images.depth = vision::read_depth_image(frame.depth_image, width_, height_);
  }
  images.read_s = core::seconds_since(read_start);
  return images;
}

FrameResult add_frame(VisualSlam& slam, core::Timestamp time, const FrameImages& images) {
  switch (images.kind) {
    case io::SequenceKind::kMonocular:
      return slam.add_monocular(time, images.gray);
    case io::SequenceKind::kStereo:
      return slam.add_stereo(time, images.gray, images.right);
    case io::SequenceKind::kRgbd:
      break;
  }
  return slam.add_rgbd(time, images.gray, images.depth);
}

}  // namespace cairn::vslam
