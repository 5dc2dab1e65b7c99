#pragma once
/// \file
/// Image messages of a bag (sensor_msgs/Image, sensor_msgs/CompressedImage) made into the images
/// VisualSlam takes (FrameImages of vslam/image_input.hpp): 8-bit grey to track, 16-bit depth.
///
/// Grey is what cairn reads from a PNG of the same pixels (vision/image_file.hpp, as
/// cv::imread(IMREAD_GRAYSCALE)), so a bag and a folder of the same images give the same run:
/// rgb8 / bgr8 / rgba8 / bgra8 as libpng's png_do_rgb_to_gray (pngrtran.c) computes it with the
/// weights OpenCV sets (0.299, 0.587: 15-bit fixed point 9797, 19234, 3737, truncated); mono16
/// keeps the high byte (png_set_strip_16).
/// Depth, REP 118: 16UC1 (and mono16) as stored, in the bag's units (millimetres unless told
/// otherwise); 32FC1 in metres (or `float_units_per_m` units per metre) stored as 16-bit
/// millimetres, kFloatDepthUnitsPerM, with NaN, infinite, non-positive and beyond-65.535 m values
/// as 0 (no depth), as a depth PNG holds them.
/// CompressedImage: PNG or JPEG bytes (told apart by their signatures, not the format string)
/// decoded by vision::decode_image; depth as a 16-bit PNG, or compressed_depth_image_transport's
/// "16UC1; compressedDepth png" (the PNG after its 12-byte ConfigHeader).
///
/// Errors are io::ParseError(file, 0, "<where>: ...") naming the encoding or format and what is
/// read instead; `where` names the message ("/camera/depth/image @ 1305031453.473352000 s").

#include <opencv2/core.hpp>
#include <string>
#include <string_view>
#include <variant>

#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/value.hpp"

namespace cairn::vslam {

/// The 16-bit units per metre 32FC1 depth is stored in (millimetres, as REP 118's 16UC1).
inline constexpr double kFloatDepthUnitsPerM = 1000.0;

/// True for the raw encodings decode_gray() reads: mono8, 8UC1, rgb8, bgr8, rgba8, bgra8, mono16.
bool is_gray_encoding(std::string_view encoding);
/// True for the raw encodings decode_depth() reads: 16UC1, mono16, 32FC1.
bool is_depth_encoding(std::string_view encoding);
/// True when a CompressedImage's format is compressed_depth_image_transport's ("...compressedDepth...").
bool is_compressed_depth_format(std::string_view format);

/// One decoded sensor_msgs/Image or sensor_msgs/CompressedImage.
struct ImageMessage {
  std::variant<bag::Image, bag::CompressedImage> image;

  const bag::Header& header() const;
  /// The raw image's encoding or the compressed image's format.
  const std::string& encoding() const;
  /// Its size: the raw image's fields; 0 x 0 for a compressed one (known once decoded).
  int width() const;
  int height() const;
};

/// An image message from its decoded value (bag::MessageDecoder::decode): a CompressedImage when
/// `compressed`, else an Image. Throws std::runtime_error when a field of the type is missing.
ImageMessage to_image_message(const bag::Value& message, bool compressed);

/// The 8-bit grey image of either kind.
cv::Mat decode_gray(const ImageMessage& message, const std::string& file, const std::string& where);
/// The 16-bit depth image of either kind (`float_units_per_m`: for 32FC1, see below).
cv::Mat decode_depth(const ImageMessage& message, double float_units_per_m, const std::string& file, const std::string& where);

/// The 8-bit grey image of a raw image (the pixels are copied).
cv::Mat decode_gray(const bag::Image& image, const std::string& file, const std::string& where);
/// The 16-bit depth image of a raw image: 16UC1 / mono16 unchanged (byte order made native);
/// 32FC1: metres = value / float_units_per_m, stored in kFloatDepthUnitsPerM units.
cv::Mat decode_depth(const bag::Image& image, double float_units_per_m, const std::string& file, const std::string& where);
/// The 8-bit grey image of PNG or JPEG bytes.
cv::Mat decode_gray(const bag::CompressedImage& image, const std::string& file, const std::string& where);
/// The 16-bit depth image of a 16-bit grey PNG (plain, or after compressedDepth's header).
cv::Mat decode_depth(const bag::CompressedImage& image, const std::string& file, const std::string& where);

}  // namespace cairn::vslam
