#pragma once
/// \file
/// An image sequence on disk (io/image_sequence.hpp) made into what VisualSlam takes: an
/// unrectified stereo pair (EuRoC) rectified with Bouguet's method (vision::StereoRectifier), the
/// calibration checked against the first image before any work, and each frame's images decoded
/// (every one the size of the first), rectified and fed to the entry point of its kind.

#include <cstddef>
#include <optional>
#include <opencv2/core.hpp>
#include <string>

#include "cairn/core/time.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vslam/visual_slam.hpp"

namespace cairn::vslam {

/// For a pair that is not rectified (sequence.rig, EuRoC): the rectifier for the rig's image size
/// (the first image's when the rig gives none), and sequence.calibration becomes the rectified left
/// camera's, the camera tracked. Any other sequence: nullopt, and nothing changes.
std::optional<vision::StereoRectifier> rectify_calibration(io::ImageSequence& sequence);

/// A calibration that no real camera has (fx in other units, a baseline of 0.05 mm) would be
/// tracked "ok" while measuring nothing: throws io::ParseError(source, 0, "implausible
/// calibration: ...") when sequence.calibration is implausible (io::CameraCalibration::
/// implausibilities) for the first frame's image size, which is the calibration's width and
/// height or else the first image's. `stereo`: the baseline counts. Nothing for no frames.
void check_calibration_plausible(const io::ImageSequence& sequence, bool stereo, const std::string& source);

/// One frame's images, decoded (and rectified) for VisualSlam.
struct FrameImages {
  io::SequenceKind kind = io::SequenceKind::kMonocular;  ///< the VisualSlam entry point they are for
  cv::Mat gray;         ///< 8-bit grey: the (rectified) left, the colour or the only image
  cv::Mat right;        ///< stereo: the (rectified) right image
  cv::Mat depth;        ///< RGB-D: the 16-bit depth image
  double read_s = 0.0;  ///< decoding and rectifying them
};

/// Where a run's frames come from, one at a time: image files (FrameReader) or a bag's image
/// topics (vslam/bag_frame_reader.hpp).
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// The images of frame `frame_index`. Throws io::ParseError for an image that cannot be read.
  virtual FrameImages read(std::size_t frame_index) = 0;
};

/// Decodes a sequence's frames one at a time. Every image must have the size of the calibration
/// (when it gives one) or else of the first image (vision::read_gray_image throws otherwise).
class FrameReader final : public FrameSource {
 public:
  /// `kind`: what is tracked, the sequence's kind or kMonocular (the left or colour images only).
  /// `sequence` and `rectifier` (null for a rectified pair) must outlive the reader.
  FrameReader(const io::ImageSequence& sequence, io::SequenceKind kind, const vision::StereoRectifier* rectifier);
  /// The images of sequence.frames[frame_index].
  FrameImages read(std::size_t frame_index) override;

 private:
  const io::ImageSequence& sequence_;
  io::SequenceKind kind_;
  const vision::StereoRectifier* rectifier_;
  int width_, height_;  ///< of the last image read; 0 before the first without a calibrated size
};

/// add_monocular, add_stereo or add_rgbd, as images.kind says.
FrameResult add_frame(VisualSlam& slam, core::Timestamp time, const FrameImages& images);

}  // namespace cairn::vslam
