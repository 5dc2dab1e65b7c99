#pragma once
/// \file
/// PNG and JPEG files in and out without OpenCV's imgcodecs: libpng and libjpeg(-turbo) directly,
/// with the settings of OpenCV 4.6's decoders (modules/imgcodecs/src/grfmt_png.cpp,
/// grfmt_jpeg.cpp, loadsave.cpp), so that the pixels are bit-identical to cv::imread's. Linking
/// libopencv_imgcodecs costs ~65 ms at every start of `cairn` (it pulls in GDAL, GDCM, Poppler,
/// HDF5, OpenEXR, libheif...: ~130 shared libraries), and cairn reads only PNG (and JPEG).

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

namespace cairn::vision {

/// What to decode into; the two cv::imread flags cairn uses.
enum class ImageMode {
  kGray8,      ///< cv::IMREAD_GRAYSCALE: CV_8UC1 (colour converted, 16-bit reduced to 8, alpha dropped)
  kUnchanged,  ///< cv::IMREAD_UNCHANGED: the file's depth (CV_8U or CV_16U) and channels (1, BGR, BGRA)
};

/// Largest image decoded, in pixels; a larger declared size is refused before any allocation.
inline constexpr std::uint64_t kMaxImagePixels = std::uint64_t{1} << 28;

/// A file (or buffer) that is not a decodable PNG or JPEG. what() is "<file>: <detail>".
class ImageFileError : public std::runtime_error {
 public:
  ImageFileError(std::string file, std::string detail);
  const std::string& file() const { return file_; }
  /// The message without the "<file>: " prefix.
  const std::string& detail() const { return detail_; }

 private:
  std::string file_;
  std::string detail_;
};

/// Decodes a PNG or JPEG file (told apart by their signatures) as cv::imread(path, mode) does.
/// Throws ImageFileError naming the file when it is missing, empty, neither PNG nor JPEG,
/// truncated, corrupt, of a kind not supported (a 12-bit JPEG), or over kMaxImagePixels.
/// kGray8 applies an EXIF orientation (JPEG APP1, PNG eXIf) as imread does; kUnchanged does not.
/// Differences from cv::imread: a JPEG whose data ends early is an error (libjpeg would pad it
/// with grey and only warn); larger images are refused (OpenCV: 2^30 pixels); and the EXIF
/// orientation entry is found even behind an entry OpenCV's ExifReader gives up on (a text tag
/// pointing past the end of the EXIF data).
cv::Mat read_image_file(const std::string& path, ImageMode mode);

/// Decodes PNG or JPEG bytes; `name` stands for the file in errors.
cv::Mat decode_image(const unsigned char* data, std::size_t size, ImageMode mode, const std::string& name = "<memory>");

/// PNG bytes of an 8-bit grey, 8-bit BGR (as cv::imencode takes it; stored as RGB) or 16-bit grey
/// image, written with cv::imencode(".png")'s default settings (filter SUB, zlib level 1, RLE
/// strategy), so the bytes equal OpenCV 4.6's. Throws std::invalid_argument for other types or an
/// empty image.
std::string encode_png(const cv::Mat& image);

}  // namespace cairn::vision
