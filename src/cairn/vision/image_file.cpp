#include "cairn/vision/image_file.hpp"

// libpng and libjpeg report errors by longjmp (libpng's png_error, libjpeg's error_exit). C++ only
// allows a longjmp where a throw caught at the setjmp would run no non-trivial destructor
// ([csetjmp.syn]), so every libpng/libjpeg call that can fail runs inside one of the
// *_guarded functions below: each calls setjmp first, holds only trivially destructible locals,
// reaches the libraries' callbacks (which hold none either when they jump) and returns false
// after a jump. Everything owning memory (the cv::Mat, the row pointers, the libraries' structs
// through their guards) lives in the callers, which throw after a guarded function fails.

#include <algorithm>
#include <bit>
#include <csetjmp>
#include <cstdio>  // before jpeglib.h, which uses FILE
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <vector>

#include <jpeglib.h>
#include <jerror.h>  // after jpeglib.h: JERR_INPUT_EOF
#include <png.h>

namespace cairn::vision {
namespace {

constexpr std::size_t kMessageSize = 256;

std::string size_text(std::uint64_t width, std::uint64_t height) {
  return std::to_string(width) + " x " + std::to_string(height) + " pixels";
}

void check_pixel_count(std::uint64_t width, std::uint64_t height, const std::string& name) {
  if (width == 0 || height == 0) throw ImageFileError(name, "the image is empty (" + size_text(width, height) + ")");
  if (width * height > kMaxImagePixels || width > static_cast<std::uint64_t>(std::numeric_limits<int>::max()) ||
      height > static_cast<std::uint64_t>(std::numeric_limits<int>::max())) {
    throw ImageFileError(name, "the image declares " + size_text(width, height) + ", more than the " + std::to_string(kMaxImagePixels) +
                                   " pixels cairn decodes");
  }
}

// ---------------------------------------------------------------------------------------------
// EXIF orientation, as OpenCV 4.6's imread applies it for every mode but IMREAD_UNCHANGED
// (loadsave.cpp ApplyExifOrientation / ExifTransform; the tag is read as exif.cpp's ExifReader
// reads it: TIFF header "II" or "MM", 42, the first IFD's entries of 12 bytes, tag 0x0112 with
// its value as the 16-bit number at byte 8 of the entry).

int exif_orientation(const unsigned char* tiff, std::size_t size) {
  if (size < 8) return 0;
  const bool intel = tiff[0] == 'I' && tiff[1] == 'I';  // otherwise read as Motorola, as ExifReader does
  auto u16 = [&](std::size_t at) -> long {
    if (at + 1 >= size) return -1;
    return intel ? tiff[at] | (tiff[at + 1] << 8) : (tiff[at] << 8) | tiff[at + 1];
  };
  auto u32 = [&](std::size_t at) -> std::uint64_t {
    if (at + 3 >= size) return std::numeric_limits<std::uint64_t>::max();
    const std::uint64_t b0 = tiff[at], b1 = tiff[at + 1], b2 = tiff[at + 2], b3 = tiff[at + 3];
    return intel ? b0 | (b1 << 8) | (b2 << 16) | (b3 << 24) : (b0 << 24) | (b1 << 16) | (b2 << 8) | b3;
  };
  if (u16(2) != 0x2A) return 0;
  const std::uint64_t ifd = u32(4);
  if (ifd >= size) return 0;
  const long entries = u16(static_cast<std::size_t>(ifd));
  for (long i = 0; i < entries; ++i) {
    const std::uint64_t entry = ifd + 2 + 12 * static_cast<std::uint64_t>(i);
    if (entry >= size) return 0;  // ExifReader stops at the first read past the end
    const long tag = u16(static_cast<std::size_t>(entry));
    if (tag < 0) return 0;
    if (tag == 0x0112) return static_cast<int>(std::max(0L, u16(static_cast<std::size_t>(entry) + 8)));
  }
  return 0;
}

// loadsave.cpp ExifTransform: 1 = as stored, 2 = mirrored, 3 = rotated 180, 4 = flipped, 5-8
// transposed and then mirrored/rotated/flipped.
void apply_exif_orientation(int orientation, cv::Mat& image) {
  if (orientation >= 5 && orientation <= 8) cv::transpose(image, image);
  switch (orientation) {
    case 2: case 6: cv::flip(image, image, 1); break;
    case 3: case 7: cv::flip(image, image, -1); break;
    case 4: case 8: cv::flip(image, image, 0); break;
    default: break;
  }
}

// ---------------------------------------------------------------------------------------------
// PNG (OpenCV 4.6 grfmt_png.cpp PngDecoder::readHeader / readData, and PngEncoder::write).

const unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};

// Trivially destructible: the state libpng's callbacks see through png_get_error_ptr/io_ptr.
struct PngContext {
  const unsigned char* data = nullptr;
  std::size_t size = 0;
  std::size_t position = 0;
  std::string* output = nullptr;  // the encoder's bytes (only a pointer: not destroyed by a jump)
  bool truncated = false;
  char message[kMessageSize] = {};
};

[[noreturn]] void png_on_error(png_structp png, png_const_charp message) {
  auto* context = static_cast<PngContext*>(png_get_error_ptr(png));
  std::snprintf(context->message, kMessageSize, "%s", message);
  png_longjmp(png, 1);
}

// Warnings (a bad CRC in an ancillary chunk, ...) do not change the pixels; a library does not print.
void png_on_warning(png_structp, png_const_charp) {}

void png_read_from_memory(png_structp png, png_bytep out, png_size_t length) {
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  if (length > context->size - context->position) {
    context->truncated = true;
    png_error(png, "the data ends early (truncated file)");
  }
  std::memcpy(out, context->data + context->position, length);
  context->position += length;
}

struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bit_depth = 0, color_type = 0, num_trans = 0;
};

bool png_read_header_guarded(png_structp png, png_infop info, PngHeader* header) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  png_get_IHDR(png, info, &header->width, &header->height, &header->bit_depth, &header->color_type, nullptr, nullptr, nullptr);
  png_bytep trans = nullptr;
  png_color_16p trans_values = nullptr;
  png_get_tRNS(png, info, &trans, &header->num_trans, &trans_values);
  return true;
}

// The transformations of PngDecoder::readData, in its order; rows[y] receives row y of the result.
bool png_read_pixels_guarded(png_structp png, png_infop info, png_infop end_info, const PngHeader* header, int depth, int channels,
                             png_bytepp rows, std::size_t row_bytes) {
  if (setjmp(png_jmpbuf(png))) return false;
  const bool color = channels > 1;
  if (depth == CV_8U && header->bit_depth == 16) {
    png_set_strip_16(png);
  } else if constexpr (std::endian::native == std::endian::little) {
    png_set_swap(png);
  }
  if (channels < 4) {
    png_set_strip_alpha(png);
  } else {
    png_set_tRNS_to_alpha(png);
  }
  if (header->color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if ((header->color_type & PNG_COLOR_MASK_COLOR) == 0 && header->bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png);
  if ((header->color_type & PNG_COLOR_MASK_COLOR) && color) {
    png_set_bgr(png);
  } else if (color) {
    png_set_gray_to_rgb(png);
  } else {
    png_set_rgb_to_gray(png, 1, 0.299, 0.587);  // PNG_ERROR_ACTION_NONE, OpenCV's weights
  }
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  // The buffers were sized from the header: never let libpng write more than a row holds.
  if (png_get_rowbytes(png, info) != row_bytes) png_error(png, "unexpected row size after the conversions");
  png_read_image(png, rows);
  png_read_end(png, end_info);
  return true;
}

// OpenCV 4.6 reads the eXIf chunk from before the image data, else from after it.
int png_exif_orientation(png_structp png, png_infop info, png_infop end_info) {
  png_uint_32 size = 0;
  png_bytep exif = nullptr;
  if (png_get_valid(png, info, PNG_INFO_eXIf)) {
    png_get_eXIf_1(png, info, &size, &exif);
  } else if (png_get_valid(png, end_info, PNG_INFO_eXIf)) {
    png_get_eXIf_1(png, end_info, &size, &exif);
  }
  return exif != nullptr && size > 0 ? exif_orientation(exif, size) : 0;
}

class PngReadGuard {
 public:
  PngReadGuard(png_structp png, png_infop info, png_infop end_info) : png_(png), info_(info), end_info_(end_info) {}
  ~PngReadGuard() { png_destroy_read_struct(&png_, info_ == nullptr ? nullptr : &info_, end_info_ == nullptr ? nullptr : &end_info_); }
  PngReadGuard(const PngReadGuard&) = delete;
  PngReadGuard& operator=(const PngReadGuard&) = delete;

 private:
  png_structp png_;
  png_infop info_;
  png_infop end_info_;
};

std::string png_failure(const PngContext& context, const char* stage) {
  if (context.truncated) return std::string("truncated PNG: the data ends ") + stage;
  return std::string("invalid or unsupported PNG (") + stage + "): " + context.message;
}

cv::Mat decode_png(const unsigned char* data, std::size_t size, ImageMode mode, const std::string& name) {
  PngContext context;
  context.data = data;
  context.size = size;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &context, png_on_error, png_on_warning);
  if (png == nullptr) throw ImageFileError(name, "cannot start libpng (out of memory, or a libpng version mismatch)");
  png_infop info = png_create_info_struct(png);
  png_infop end_info = png_create_info_struct(png);
  const PngReadGuard guard(png, info, end_info);
  if (info == nullptr || end_info == nullptr) throw ImageFileError(name, "cannot start libpng (out of memory)");
  png_set_read_fn(png, &context, png_read_from_memory);

  PngHeader header;
  if (!png_read_header_guarded(png, info, &header)) throw ImageFileError(name, png_failure(context, "in the header"));
  check_pixel_count(header.width, header.height, name);
  if (header.bit_depth != 1 && header.bit_depth != 2 && header.bit_depth != 4 && header.bit_depth != 8 && header.bit_depth != 16) {
    throw ImageFileError(name, "unsupported PNG bit depth " + std::to_string(header.bit_depth));
  }

  // PngDecoder::readHeader's type, then imread's reduction to the wanted one (loadsave.cpp).
  int channels = 1;
  switch (header.color_type) {
    case PNG_COLOR_TYPE_RGB:
    case PNG_COLOR_TYPE_PALETTE: channels = header.num_trans > 0 ? 4 : 3; break;
    case PNG_COLOR_TYPE_GRAY_ALPHA:
    case PNG_COLOR_TYPE_RGB_ALPHA: channels = 4; break;
    default: channels = 1; break;
  }
  int depth = header.bit_depth == 16 ? CV_16U : CV_8U;
  if (mode == ImageMode::kGray8) {
    depth = CV_8U;
    channels = 1;
  }

  cv::Mat image(static_cast<int>(header.height), static_cast<int>(header.width), CV_MAKETYPE(depth, channels));
  std::vector<png_bytep> rows(header.height);
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = image.ptr(y);
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  if (!png_read_pixels_guarded(png, info, end_info, &header, depth, channels, rows.data(), row_bytes)) {
    throw ImageFileError(name, png_failure(context, "in the image data"));
  }
  if (mode != ImageMode::kUnchanged) apply_exif_orientation(png_exif_orientation(png, info, end_info), image);
  return image;
}

void png_write_to_string(png_structp png, png_bytep data, png_size_t length) {
  auto* context = static_cast<PngContext*>(png_get_io_ptr(png));
  bool ok = true;
  try {
    context->output->append(reinterpret_cast<const char*>(data), length);
  } catch (...) {  // no exception may cross libpng's C frames
    ok = false;
  }
  if (!ok) png_error(png, "out of memory");
}

void png_flush_nothing(png_structp) {}

class PngWriteGuard {
 public:
  PngWriteGuard(png_structp png, png_infop info) : png_(png), info_(info) {}
  ~PngWriteGuard() { png_destroy_write_struct(&png_, info_ == nullptr ? nullptr : &info_); }
  PngWriteGuard(const PngWriteGuard&) = delete;
  PngWriteGuard& operator=(const PngWriteGuard&) = delete;

 private:
  png_structp png_;
  png_infop info_;
};

// PngEncoder::write with no parameters: filter SUB, Z_BEST_SPEED (1), IMWRITE_PNG_STRATEGY_RLE (3),
// BGR stored as RGB, 16-bit samples swapped to big-endian.
bool png_write_guarded(png_structp png, png_infop info, png_uint_32 width, png_uint_32 height, int bit_depth, int color_type,
                       png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, 1);
  png_set_compression_strategy(png, 3);
  png_set_IHDR(png, info, width, height, bit_depth, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_set_bgr(png);
  if constexpr (std::endian::native == std::endian::little) png_set_swap(png);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

// ---------------------------------------------------------------------------------------------
// JPEG (OpenCV 4.6 grfmt_jpeg.cpp JpegDecoder::readHeader / readData).

// Trivially destructible; `error` first so that libjpeg's jpeg_error_mgr* is a JpegContext*.
struct JpegContext {
  jpeg_error_mgr error;
  std::jmp_buf jump;
  bool truncated = false;
  char message[JMSG_LENGTH_MAX] = {};
};

[[noreturn]] void jpeg_on_error(j_common_ptr cinfo) {
  auto* context = reinterpret_cast<JpegContext*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, context->message);
  std::longjmp(context->jump, 1);
}

// Warnings (corrupt data libjpeg can go past) do not stop OpenCV either; a library does not print.
void jpeg_on_output_message(j_common_ptr) {}

// jpeg_mem_src's fill_input_buffer pads a truncated file with an EOI marker and decodes the rest
// as grey; cairn refuses it. With the whole file in memory, being called means the data ran out.
boolean jpeg_fill_input_truncated(j_decompress_ptr cinfo) {
  auto* context = reinterpret_cast<JpegContext*>(cinfo->err);
  context->truncated = true;
  cinfo->err->msg_code = JERR_INPUT_EOF;
  (*cinfo->err->error_exit)(reinterpret_cast<j_common_ptr>(cinfo));
  return FALSE;
}

bool jpeg_read_header_guarded(j_decompress_ptr cinfo, JpegContext* context, const unsigned char* data, std::size_t size,
                              bool* created) {
  if (setjmp(context->jump)) return false;
  jpeg_CreateDecompress(cinfo, JPEG_LIB_VERSION, sizeof(jpeg_decompress_struct));
  *created = true;
  jpeg_mem_src(cinfo, data, static_cast<unsigned long>(size));
  cinfo->src->fill_input_buffer = jpeg_fill_input_truncated;
  jpeg_save_markers(cinfo, JPEG_APP0 + 1, 0xffff);  // APP1: EXIF
  jpeg_read_header(cinfo, TRUE);
  cinfo->scale_num = 1;
  cinfo->scale_denom = 1;
  jpeg_calc_output_dimensions(cinfo);
  return true;
}

// JpegDecoder::readData: straight into the rows as BGR or grey; CMYK through a row buffer and
// utils.cpp icvCvt_CMYK2BGR_8u_C4C3R / icvCvt_CMYK2Gray_8u_C4C1R.
bool jpeg_read_pixels_guarded(j_decompress_ptr cinfo, JpegContext* context, bool color, unsigned char* pixels, std::size_t step) {
  if (setjmp(context->jump)) return false;
  const bool cmyk = cinfo->num_components == 4;
  if (cmyk) {
    cinfo->out_color_space = JCS_CMYK;
    cinfo->out_color_components = 4;
  } else {
    cinfo->out_color_space = color ? JCS_EXT_BGR : JCS_GRAYSCALE;
    cinfo->out_color_components = color ? 3 : 1;
  }
  jpeg_start_decompress(cinfo);
  const JDIMENSION width = cinfo->output_width;
  if (cinfo->output_components != cinfo->out_color_components) {
    std::snprintf(context->message, sizeof(context->message), "unexpected output of %d components", cinfo->output_components);
    return false;
  }
  JSAMPARRAY buffer = cmyk ? (*cinfo->mem->alloc_sarray)(reinterpret_cast<j_common_ptr>(cinfo), JPOOL_IMAGE, width * 4, 1) : nullptr;
  for (JDIMENSION y = 0; y < cinfo->output_height; ++y) {
    unsigned char* row = pixels + y * step;
    JSAMPROW target = cmyk ? buffer[0] : row;
    if (jpeg_read_scanlines(cinfo, &target, 1) != 1) {
      std::snprintf(context->message, sizeof(context->message), "no data for row %u", y);
      return false;
    }
    if (!cmyk) continue;
    constexpr int kScale = 14;  // utils.cpp: cR, cG, cB in 14-bit fixed point
    constexpr int kR = static_cast<int>(0.299 * (1 << kScale) + 0.5), kG = static_cast<int>(0.587 * (1 << kScale) + 0.5);
    constexpr int kB = (1 << kScale) - kR - kG;
    for (JDIMENSION x = 0; x < width; ++x) {
      const unsigned char* p = buffer[0] + 4 * x;
      const int k = p[3];
      const int c = k - ((255 - p[0]) * k >> 8), m = k - ((255 - p[1]) * k >> 8), yellow = k - ((255 - p[2]) * k >> 8);
      if (color) {
        row[3 * x] = static_cast<unsigned char>(yellow);
        row[3 * x + 1] = static_cast<unsigned char>(m);
        row[3 * x + 2] = static_cast<unsigned char>(c);
      } else {
        row[x] = static_cast<unsigned char>((yellow * kB + m * kG + c * kR + (1 << (kScale - 1))) >> kScale);
      }
    }
  }
  jpeg_finish_decompress(cinfo);
  return true;
}

class JpegGuard {
 public:
  JpegGuard(jpeg_decompress_struct* cinfo, const bool* created) : cinfo_(cinfo), created_(created) {}
  ~JpegGuard() {
    if (*created_) jpeg_destroy_decompress(cinfo_);
  }
  JpegGuard(const JpegGuard&) = delete;
  JpegGuard& operator=(const JpegGuard&) = delete;

 private:
  jpeg_decompress_struct* cinfo_;
  const bool* created_;
};

std::string jpeg_failure(const JpegContext& context, const char* stage) {
  if (context.truncated) return std::string("truncated JPEG: the data ends ") + stage;
  return std::string("invalid or unsupported JPEG (") + stage + "): " + context.message;
}

// grfmt_jpeg.cpp: the first APP1 marker, its TIFF data 6 bytes in ("Exif\0\0").
int jpeg_exif_orientation(const jpeg_decompress_struct& cinfo) {
  for (jpeg_saved_marker_ptr marker = cinfo.marker_list; marker != nullptr; marker = marker->next) {
    if (marker->marker != JPEG_APP0 + 1) continue;
    return marker->data_length > 6 ? exif_orientation(marker->data + 6, marker->data_length - 6) : 0;
  }
  return 0;
}

cv::Mat decode_jpeg(const unsigned char* data, std::size_t size, ImageMode mode, const std::string& name) {
  jpeg_decompress_struct cinfo;
  std::memset(&cinfo, 0, sizeof(cinfo));
  JpegContext context;
  cinfo.err = jpeg_std_error(&context.error);
  context.error.error_exit = jpeg_on_error;
  context.error.output_message = jpeg_on_output_message;
  bool created = false;
  const JpegGuard guard(&cinfo, &created);
  if (!jpeg_read_header_guarded(&cinfo, &context, data, size, &created)) throw ImageFileError(name, jpeg_failure(context, "in the header"));
  check_pixel_count(cinfo.output_width, cinfo.output_height, name);
  const int orientation = jpeg_exif_orientation(cinfo);  // now: jpeg_finish_decompress drops the markers
  if (cinfo.num_components != 1 && cinfo.num_components != 3 && cinfo.num_components != 4) {
    throw ImageFileError(name, "unsupported JPEG with " + std::to_string(cinfo.num_components) + " components");
  }
  // JpegDecoder::readHeader: CV_8UC3 for more than one component; imread reduces as asked.
  const bool color = mode == ImageMode::kUnchanged && cinfo.num_components > 1;
  cv::Mat image(static_cast<int>(cinfo.output_height), static_cast<int>(cinfo.output_width), color ? CV_8UC3 : CV_8UC1);
  if (!jpeg_read_pixels_guarded(&cinfo, &context, color, image.data, image.step[0])) {
    throw ImageFileError(name, jpeg_failure(context, "in the image data"));
  }
  if (mode != ImageMode::kUnchanged) apply_exif_orientation(orientation, image);
  return image;
}

}  // namespace

ImageFileError::ImageFileError(std::string file, std::string detail)
    : std::runtime_error(file + ": " + detail), file_(std::move(file)), detail_(std::move(detail)) {}

cv::Mat decode_image(const unsigned char* data, std::size_t size, ImageMode mode, const std::string& name) {
  if (size == 0) throw ImageFileError(name, "empty file, not an image");
  if (size >= sizeof(kPngSignature) && std::memcmp(data, kPngSignature, sizeof(kPngSignature)) == 0) return decode_png(data, size, mode, name);
  if (size >= 3 && data[0] == 0xFF && data[1] == 0xD8 && data[2] == 0xFF) return decode_jpeg(data, size, mode, name);
  throw ImageFileError(name, "not a PNG or JPEG image (no PNG or JPEG signature at the start)");
}

cv::Mat read_image_file(const std::string& path, ImageMode mode) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw ImageFileError(path, "is a directory, expected an image file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ImageFileError(path, "cannot open the file");
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw ImageFileError(path, "cannot read the file");
  return decode_image(bytes.data(), bytes.size(), mode, path);
}

std::string encode_png(const cv::Mat& image) {
  if (image.empty()) throw std::invalid_argument("encode_png: the image is empty");
  const int type = image.type();
  if (type != CV_8UC1 && type != CV_8UC3 && type != CV_16UC1) {
    throw std::invalid_argument("encode_png: expected an 8-bit grey, 8-bit BGR or 16-bit grey image, found type " + std::to_string(type));
  }
  std::string bytes;
  PngContext context;
  context.output = &bytes;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &context, png_on_error, png_on_warning);
  if (png == nullptr) throw std::runtime_error("encode_png: cannot start libpng");
  png_infop info = png_create_info_struct(png);
  const PngWriteGuard guard(png, info);
  if (info == nullptr) throw std::runtime_error("encode_png: cannot start libpng (out of memory)");
  png_set_write_fn(png, &context, png_write_to_string, png_flush_nothing);
  // libpng only reads the rows, but takes them as non-const pointers.
  std::vector<png_bytep> rows(static_cast<std::size_t>(image.rows));
  for (int y = 0; y < image.rows; ++y) rows[static_cast<std::size_t>(y)] = const_cast<png_bytep>(image.ptr(y));
  const int bit_depth = image.depth() == CV_16U ? 16 : 8;
  const int color_type = image.channels() == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY;
  if (!png_write_guarded(png, info, static_cast<png_uint_32>(image.cols), static_cast<png_uint_32>(image.rows), bit_depth, color_type,
                         rows.data())) {
    throw std::runtime_error(std::string("encode_png: libpng failed: ") + context.message);
  }
  return bytes;
}

}  // namespace cairn::vision
