#pragma once
/// \file
/// Reads the frames of a bag's image sequence (vslam/bag_images.hpp) in order, streaming the
/// bag's image topics once in log-time order, as lidar3d::ScanReader streams a PointCloud2
/// topic. Only the images of frames not read yet are held: a bag may log frame k+1's colour image
/// before frame k's depth map, and a stereo driver may log the right image first. Images that
/// belong to no frame (unpaired, repeated stamps) are decoded from the bag and dropped.
/// Each image is made grey or 16-bit depth as vslam/image_message.hpp says, and must have the
/// calibration's size.

#include <cstddef>
#include <memory>

#include "cairn/io/image_sequence.hpp"
#include "cairn/vslam/bag_images.hpp"
#include "cairn/vslam/image_input.hpp"

namespace cairn::vslam {

class BagFrameReader final : public FrameSource {
 public:
  /// `kind`: images.sequence.kind, or kMonocular for the left / colour images alone. Opens the
  /// bag again (images.sequence.folder). `images` must outlive the reader. Throws io::ParseError.
  BagFrameReader(const BagImages& images, io::SequenceKind kind);
  ~BagFrameReader() override;
  BagFrameReader(const BagFrameReader&) = delete;
  BagFrameReader& operator=(const BagFrameReader&) = delete;

  /// The images of frame `frame_index`; frames are read in order, 0, 1, 2, ... (std::logic_error
  /// otherwise). Throws io::ParseError for an image that does not decode or has another size, or
  /// a bag that ends before the frame's images.
  FrameImages read(std::size_t frame_index) override;

 private:
  struct Stream;  // the bag, its decoder and message stream, the images held
  /// Reads one message, keeping its image when a frame not read yet needs it; false at the end.
  bool pull();

  const BagImages& images_;
  io::SequenceKind kind_;
  std::unique_ptr<Stream> stream_;
  std::size_t next_ = 0;
};

}  // namespace cairn::vslam
