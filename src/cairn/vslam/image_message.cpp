#include "cairn/vslam/image_message.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "cairn/io/parse_error.hpp"
#include "cairn/vision/image_file.hpp"

namespace cairn::vslam {
namespace {

constexpr std::array<std::string_view, 7> kGrayEncodings{"mono8", "8UC1", "rgb8", "bgr8", "rgba8", "bgra8", "mono16"};
constexpr std::array<std::string_view, 3> kDepthEncodings{"16UC1", "mono16", "32FC1"};

/// compressed_depth_image_transport's ConfigHeader (format enum, float depthParam[2]) before the PNG.
constexpr std::size_t kCompressedDepthHeaderBytes = 12;
constexpr std::array<unsigned char, 8> kPngSignature{0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

std::string list(const auto& names) {
  std::string out;
  for (const std::string_view name : names) out += (out.empty() ? "" : ", ") + std::string(name);
  return out;
}

/// Bytes per pixel of a raw encoding cairn reads (0 for any other).
std::size_t pixel_bytes(std::string_view encoding) {
  if (encoding == "mono8" || encoding == "8UC1") return 1;
  if (encoding == "mono16" || encoding == "16UC1") return 2;
  if (encoding == "rgb8" || encoding == "bgr8") return 3;
  if (encoding == "rgba8" || encoding == "bgra8" || encoding == "32FC1") return 4;
  return 0;
}

/// Refuses an image whose size, step or data cannot hold its pixels, before anything is read.
void check_layout(const bag::Image& image, std::size_t bytes_per_pixel, const std::string& file, const std::string& where) {
  const auto fail = [&](const std::string& detail) { throw io::ParseError(file, 0, where + ": " + detail); };
  if (image.width == 0 || image.height == 0) {
    fail("an empty image (" + std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels)");
  }
  if (std::uint64_t{image.width} * image.height > vision::kMaxImagePixels) {
    fail(std::to_string(image.width) + " x " + std::to_string(image.height) + " pixels is more than cairn decodes (2^28)");
  }
  const std::uint64_t row_bytes = std::uint64_t{image.width} * bytes_per_pixel;
  if (image.step < row_bytes) {
    fail("step " + std::to_string(image.step) + " is less than width x bytes per pixel = " + std::to_string(row_bytes) + " (" +
         image.encoding + ")");
  }
  const std::uint64_t needed = std::uint64_t{image.step} * image.height;
  if (image.data.size() < needed) {
    fail("the data holds " + std::to_string(image.data.size()) + " bytes, step x height = " + std::to_string(needed));
  }
}

/// Sample `index` (of `bytes` bytes) of row `row`, in the byte order the message declares.
template <typename T>
T sample(const unsigned char* row, std::size_t index, bool big_endian) {
  std::array<unsigned char, sizeof(T)> raw{};
  std::memcpy(raw.data(), row + index * sizeof(T), sizeof(T));
  if (big_endian != (std::endian::native == std::endian::big)) std::reverse(raw.begin(), raw.end());
  return std::bit_cast<T>(raw);
}

/// libpng's png_do_rgb_to_gray for 8-bit samples without gamma: 15-bit weights of 0.299 and
/// 0.587 (png_set_rgb_to_gray_fixed truncates 29900 * 32768 / 100000 and 58700 * 32768 / 100000),
/// blue the rest, the sum shifted down (truncated).
unsigned char gray_of(unsigned red, unsigned green, unsigned blue) {
  constexpr unsigned kRed = 9797, kGreen = 19234, kBlue = 32768 - kRed - kGreen;
  return static_cast<unsigned char>((kRed * red + kGreen * green + kBlue * blue) >> 15);
}

void gray_row(const bag::Image& image, const unsigned char* in, unsigned char* out) {
  const std::string& e = image.encoding;
  const std::size_t width = image.width;
  if (e == "mono8" || e == "8UC1") {
    std::memcpy(out, in, width);
  } else if (e == "mono16") {
    for (std::size_t x = 0; x < width; ++x) out[x] = static_cast<unsigned char>(sample<std::uint16_t>(in, x, image.is_bigendian) >> 8);
  } else {
    const std::size_t channels = pixel_bytes(e);
    const bool rgb = e == "rgb8" || e == "rgba8";
    for (std::size_t x = 0; x < width; ++x) {
      const unsigned char* p = in + x * channels;
      out[x] = rgb ? gray_of(p[0], p[1], p[2]) : gray_of(p[2], p[1], p[0]);
    }
  }
}

void depth_row(const bag::Image& image, double float_units_per_m, const unsigned char* in, std::uint16_t* out) {
  const std::size_t width = image.width;
  if (image.encoding != "32FC1") {
    for (std::size_t x = 0; x < width; ++x) out[x] = sample<std::uint16_t>(in, x, image.is_bigendian);
    return;
  }
  for (std::size_t x = 0; x < width; ++x) {
    const double metres = static_cast<double>(sample<float>(in, x, image.is_bigendian)) / float_units_per_m;
    const double units = std::round(metres * kFloatDepthUnitsPerM);
    // NaN and infinity (no return, REP 118), zero or negative, and beyond 16 bits: no depth.
    out[x] = std::isfinite(units) && units > 0.0 && units <= 65535.0 ? static_cast<std::uint16_t>(units) : std::uint16_t{0};
  }
}

const unsigned char* bytes_of(const std::string& data) { return reinterpret_cast<const unsigned char*>(data.data()); }

cv::Mat decode_bytes(const unsigned char* data, std::size_t size, vision::ImageMode mode, const std::string& format,
                     const std::string& file, const std::string& where) {
  try {
    return vision::decode_image(data, size, mode, where);
  } catch (const vision::ImageFileError& e) {
    throw io::ParseError(file, 0, where + ": CompressedImage of format '" + format + "': " + e.detail());
  }
}

bool starts_with_png(const std::string& data, std::size_t offset) {
  return data.size() >= offset + kPngSignature.size() &&
         std::memcmp(data.data() + offset, kPngSignature.data(), kPngSignature.size()) == 0;
}

}  // namespace

bool is_gray_encoding(std::string_view encoding) {
  return std::find(kGrayEncodings.begin(), kGrayEncodings.end(), encoding) != kGrayEncodings.end();
}

bool is_depth_encoding(std::string_view encoding) {
  return std::find(kDepthEncodings.begin(), kDepthEncodings.end(), encoding) != kDepthEncodings.end();
}

bool is_compressed_depth_format(std::string_view format) { return format.find("compressedDepth") != std::string_view::npos; }

cv::Mat decode_gray(const bag::Image& image, const std::string& file, const std::string& where) {
  if (!is_gray_encoding(image.encoding)) {
    throw io::ParseError(file, 0, where + ": image encoding '" + image.encoding + "' is not read as a grey image (" +
                                      list(kGrayEncodings) + " are" + (is_depth_encoding(image.encoding) ? "; is it a depth topic?" : "") + ")");
  }
  check_layout(image, pixel_bytes(image.encoding), file, where);
  cv::Mat gray(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC1);
  for (int y = 0; y < gray.rows; ++y) gray_row(image, bytes_of(image.data) + std::size_t{image.step} * y, gray.ptr<unsigned char>(y));
  return gray;
}

cv::Mat decode_depth(const bag::Image& image, double float_units_per_m, const std::string& file, const std::string& where) {
  if (!is_depth_encoding(image.encoding)) {
    throw io::ParseError(file, 0, where + ": image encoding '" + image.encoding + "' is not read as depth (" + list(kDepthEncodings) +
                                      " are: REP 118)");
  }
  check_layout(image, pixel_bytes(image.encoding), file, where);
  cv::Mat depth(static_cast<int>(image.height), static_cast<int>(image.width), CV_16UC1);
  for (int y = 0; y < depth.rows; ++y) {
    depth_row(image, float_units_per_m, bytes_of(image.data) + std::size_t{image.step} * y, depth.ptr<std::uint16_t>(y));
  }
  return depth;
}

cv::Mat decode_gray(const bag::CompressedImage& image, const std::string& file, const std::string& where) {
  if (is_compressed_depth_format(image.format)) {
    throw io::ParseError(file, 0, where + ": CompressedImage of format '" + image.format + "' is depth, not a grey or colour image");
  }
  return decode_bytes(bytes_of(image.data), image.data.size(), vision::ImageMode::kGray8, image.format, file, where);
}

cv::Mat decode_depth(const bag::CompressedImage& image, const std::string& file, const std::string& where) {
  std::size_t offset = 0;
  if (is_compressed_depth_format(image.format)) {
    if (image.format.starts_with("32FC1")) {
      throw io::ParseError(file, 0, where + ": CompressedImage of format '" + image.format +
                                        "': 32FC1 compressedDepth (quantised inverse depth) is not read; 16UC1 compressedDepth png is");
    }
    if (starts_with_png(image.data, kCompressedDepthHeaderBytes)) offset = kCompressedDepthHeaderBytes;
  }
  const cv::Mat depth =
      decode_bytes(bytes_of(image.data) + offset, image.data.size() - offset, vision::ImageMode::kUnchanged, image.format, file, where);
  if (depth.type() != CV_16UC1) {
    throw io::ParseError(file, 0, where + ": CompressedImage of format '" + image.format + "' holds " + std::to_string(depth.channels()) +
                                      " channel(s) of " + std::to_string(8 * depth.elemSize1()) +
                                      "-bit values; depth must be one channel of 16 bits");
  }
  return depth;
}

const bag::Header& ImageMessage::header() const {
  return std::visit([](const auto& m) -> const bag::Header& { return m.header; }, image);
}

const std::string& ImageMessage::encoding() const {
  if (const auto* raw = std::get_if<bag::Image>(&image)) return raw->encoding;
  return std::get<bag::CompressedImage>(image).format;
}

int ImageMessage::width() const {
  const auto* raw = std::get_if<bag::Image>(&image);
  return raw != nullptr ? static_cast<int>(std::min<std::uint32_t>(raw->width, 1u << 30)) : 0;
}

int ImageMessage::height() const {
  const auto* raw = std::get_if<bag::Image>(&image);
  return raw != nullptr ? static_cast<int>(std::min<std::uint32_t>(raw->height, 1u << 30)) : 0;
}

ImageMessage to_image_message(const bag::Value& message, bool compressed) {
  if (compressed) return {bag::to_compressed_image(message)};
  return {bag::to_image(message)};
}

cv::Mat decode_gray(const ImageMessage& message, const std::string& file, const std::string& where) {
  return std::visit([&](const auto& m) { return decode_gray(m, file, where); }, message.image);
}

cv::Mat decode_depth(const ImageMessage& message, double float_units_per_m, const std::string& file, const std::string& where) {
  if (const auto* raw = std::get_if<bag::Image>(&message.image)) return decode_depth(*raw, float_units_per_m, file, where);
  return decode_depth(std::get<bag::CompressedImage>(message.image), file, where);
}

}  // namespace cairn::vslam
