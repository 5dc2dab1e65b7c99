// The PNG/JPEG reader and PNG writer (vision/image_file.hpp) against OpenCV 4.6's imgcodecs, which
// they replace: every kind of PNG (grey 1/2/4/8/16-bit, grey + alpha, RGB 8/16, RGBA, palettes
// with and without transparency, tRNS, interlaced, gAMA, EXIF orientation) and JPEG (grey,
// colour, progressive, CMYK, EXIF orientation) written here, and a sample of the real PNGs under
// the data root, must decode bit-identically to cv::imread / cv::imdecode with IMREAD_GRAYSCALE and
// IMREAD_UNCHANGED. Hostile files (truncated, random, empty, missing, huge declared size) give an
// ImageFileError naming the file. This test alone links opencv_imgcodecs.

#include <gtest/gtest.h>
#include <jpeglib.h>
#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "cairn/vision/image_file.hpp"
#include "test_data.hpp"

namespace cairn::vision {
namespace {

namespace fs = std::filesystem;

fs::path scratch() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / "cairn_test_image_file";
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

fs::path write_file(const std::string& name, const std::string& bytes) {
  const fs::path path = scratch() / name;
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

cv::Mat opencv_decode(const std::string& bytes, int flags) {
  const std::vector<uchar> buffer(bytes.begin(), bytes.end());
  return cv::imdecode(buffer, flags);
}

cv::Mat cairn_decode(const std::string& bytes, ImageMode mode) {
  return decode_image(reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(), mode, "test bytes");
}

// Same type, same size, same bytes in every row.
::testing::AssertionResult identical(const cv::Mat& ours, const cv::Mat& opencv) {
  if (opencv.empty()) return ::testing::AssertionFailure() << "OpenCV could not decode it";
  if (ours.type() != opencv.type()) return ::testing::AssertionFailure() << "type " << ours.type() << ", OpenCV " << opencv.type();
  if (ours.size() != opencv.size()) return ::testing::AssertionFailure() << "size " << ours.size() << ", OpenCV " << opencv.size();
  const std::size_t row_bytes = static_cast<std::size_t>(ours.cols) * ours.elemSize();
  for (int y = 0; y < ours.rows; ++y) {
    if (std::memcmp(ours.ptr(y), opencv.ptr(y), row_bytes) != 0) return ::testing::AssertionFailure() << "row " << y << " differs";
  }
  return ::testing::AssertionSuccess();
}

// Both modes, from memory and from a file, against imdecode and imread.
void expect_as_opencv(const std::string& bytes, const std::string& label) {
  const fs::path path = write_file("kind.img", bytes);
  for (const auto& [mode, flags] : {std::pair{ImageMode::kGray8, cv::IMREAD_GRAYSCALE}, std::pair{ImageMode::kUnchanged, cv::IMREAD_UNCHANGED}}) {
    const std::string what = label + (mode == ImageMode::kGray8 ? ", grayscale" : ", unchanged");
    EXPECT_TRUE(identical(cairn_decode(bytes, mode), opencv_decode(bytes, flags))) << what << " (memory)";
    EXPECT_TRUE(identical(read_image_file(path.string(), mode), cv::imread(path.string(), flags))) << what << " (file)";
  }
}

// ---------------------------------------------------------------------------------------------
// Writing test PNGs of every kind with libpng's classic API. Like the reader, the function that
// calls setjmp holds nothing that needs a destructor.

struct PngSpec {
  int width = 37, height = 23;  // odd, so that packed 1/2/4-bit rows end inside a byte
  int bit_depth = 8;
  int color_type = PNG_COLOR_TYPE_GRAY;
  bool interlaced = false;
  int palette_size = 0;        // PLTE entries (palette images)
  int transparent_entries = 0;  // tRNS alpha entries of a palette
  bool trns_color = false;      // tRNS single transparent colour (grey / RGB)
  bool gamma = false;           // a gAMA chunk (OpenCV asks for no gamma correction)
  std::string exif;             // eXIf chunk contents (TIFF data)
};

struct PngOut {
  std::string* bytes;
};

void png_test_write(png_structp png, png_bytep data, png_size_t length) {
  static_cast<PngOut*>(png_get_io_ptr(png))->bytes->append(reinterpret_cast<const char*>(data), length);
}
void png_test_flush(png_structp) {}

bool png_test_write_guarded(png_structp png, png_infop info, const PngSpec* spec, const png_color* palette, const png_byte* alpha,
                            const png_color_16* trans, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_IHDR(png, info, static_cast<png_uint_32>(spec->width), static_cast<png_uint_32>(spec->height), spec->bit_depth, spec->color_type,
               spec->interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (spec->palette_size > 0) png_set_PLTE(png, info, palette, spec->palette_size);
  if (spec->transparent_entries > 0) png_set_tRNS(png, info, alpha, spec->transparent_entries, nullptr);
  if (spec->trns_color) png_set_tRNS(png, info, nullptr, 1, trans);
  if (spec->gamma) png_set_gAMA(png, info, 1.0 / 2.2);
  if (!spec->exif.empty()) {
    png_set_eXIf_1(png, info, static_cast<png_uint_32>(spec->exif.size()),
                   const_cast<png_bytep>(reinterpret_cast<const png_byte*>(spec->exif.data())));
  }
  png_write_info(png, info);
  if (spec->interlaced) png_set_interlace_handling(png);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

// A PNG of random samples (in the file's own layout: packed, 16-bit big-endian).
std::string make_png(const PngSpec& spec, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const int channels = spec.color_type == PNG_COLOR_TYPE_GRAY || spec.color_type == PNG_COLOR_TYPE_PALETTE ? 1
                       : spec.color_type == PNG_COLOR_TYPE_GRAY_ALPHA                                       ? 2
                       : spec.color_type == PNG_COLOR_TYPE_RGB                                              ? 3
                                                                                                            : 4;
  const std::size_t row_bytes = (static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(channels * spec.bit_depth) + 7) / 8;
  std::vector<png_byte> pixels(row_bytes * static_cast<std::size_t>(spec.height));
  for (auto& b : pixels) b = static_cast<png_byte>(rng() & 0xFF);
  if (spec.trns_color) {  // make the transparent colour occur: the first pixels of each row are 0
    for (int y = 0; y < spec.height; ++y) std::fill_n(pixels.begin() + static_cast<std::ptrdiff_t>(row_bytes) * y, std::min<std::size_t>(row_bytes, 6), 0);
  }
  std::vector<png_color> palette(256);
  for (auto& c : palette) c = {static_cast<png_byte>(rng() & 0xFF), static_cast<png_byte>(rng() & 0xFF), static_cast<png_byte>(rng() & 0xFF)};
  std::vector<png_byte> alpha(256);
  for (auto& a : alpha) a = static_cast<png_byte>(rng() & 0xFF);
  png_color_16 trans{};  // the transparent colour: 0
  std::vector<png_bytep> rows(static_cast<std::size_t>(spec.height));
  for (std::size_t y = 0; y < rows.size(); ++y) rows[y] = pixels.data() + y * row_bytes;

  std::string bytes;
  PngOut out{&bytes};
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_set_write_fn(png, &out, png_test_write, png_test_flush);
  const bool ok = png_test_write_guarded(png, info, &spec, palette.data(), alpha.data(), &trans, rows.data());
  png_destroy_write_struct(&png, &info);
  EXPECT_TRUE(ok) << "libpng could not write the test PNG";
  return bytes;
}

// TIFF data with one IFD entry: Orientation (0x0112), SHORT, 1 value.
std::string exif_orientation_tiff(int orientation, bool intel) {
  const unsigned char o = static_cast<unsigned char>(orientation);
  if (intel) return std::string("II\x2A\0\x08\0\0\0\x01\0\x12\x01\x03\0\x01\0\0\0", 18) + std::string(1, static_cast<char>(o)) + std::string("\0\0\0\0\0\0\0", 7);
  return std::string("MM\0\x2A\0\0\0\x08\0\x01\x01\x12\0\x03\0\0\0\x01\0", 19) + std::string(1, static_cast<char>(o)) + std::string("\0\0\0\0\0\0", 6);
}

TEST(ImageFile, EveryKindOfPngDecodesAsOpenCvDecodesIt) {
  struct Case {
    const char* label;
    PngSpec spec;
  };
  std::vector<Case> cases;
  for (int depth : {1, 2, 4, 8, 16}) {
    PngSpec s;
    s.bit_depth = depth;
    cases.push_back({"grey", s});
    s.trns_color = true;
    cases.push_back({"grey + tRNS", s});
  }
  for (int depth : {8, 16}) {
    PngSpec s;
    s.bit_depth = depth;
    s.color_type = PNG_COLOR_TYPE_GRAY_ALPHA;
    cases.push_back({"grey + alpha", s});
    s.color_type = PNG_COLOR_TYPE_RGB;
    cases.push_back({"RGB", s});
    s.trns_color = true;
    cases.push_back({"RGB + tRNS", s});
    s.trns_color = false;
    s.color_type = PNG_COLOR_TYPE_RGB_ALPHA;
    cases.push_back({"RGBA", s});
  }
  for (int depth : {1, 2, 4, 8}) {
    PngSpec s;
    s.bit_depth = depth;
    s.color_type = PNG_COLOR_TYPE_PALETTE;
    s.palette_size = 1 << depth;
    cases.push_back({"palette", s});
    s.transparent_entries = std::max(1, s.palette_size / 2);
    cases.push_back({"palette + tRNS", s});
  }
  const std::size_t plain = cases.size();
  for (std::size_t i = 0; i < plain; ++i) {  // every kind again, Adam7-interlaced
    Case c = cases[i];
    c.spec.interlaced = true;
    c.spec.width = 13;  // narrower than 8 px in some passes' columns
    cases.push_back(c);
  }
  {
    PngSpec s;
    s.color_type = PNG_COLOR_TYPE_RGB;
    s.gamma = true;
    cases.push_back({"RGB + gAMA", s});
    s.width = 1;
    s.height = 1;
    cases.push_back({"RGB 1 x 1", s});
  }
  std::uint32_t seed = 1;
  for (const Case& c : cases) {
    const std::string label = std::string(c.label) + " " + std::to_string(c.spec.bit_depth) + "-bit" + (c.spec.interlaced ? " interlaced" : "");
    SCOPED_TRACE(label);
    expect_as_opencv(make_png(c.spec, seed++), label);
  }
}

TEST(ImageFile, PngExifOrientationIsAppliedAsOpenCvAppliesIt) {
  for (int orientation = 1; orientation <= 8; ++orientation) {
    for (bool intel : {true, false}) {
      PngSpec s;
      s.color_type = orientation % 2 == 0 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY;
      s.exif = exif_orientation_tiff(orientation, intel);
      expect_as_opencv(make_png(s, 100u + static_cast<std::uint32_t>(orientation)),
                       "PNG orientation " + std::to_string(orientation) + (intel ? " II" : " MM"));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// JPEGs: cv::imencode for grey and colour (baseline and progressive); libjpeg for CMYK.

cv::Mat smooth_random_image(int rows, int cols, int type, std::uint32_t seed) {
  cv::Mat noise(rows / 4 + 1, cols / 4 + 1, type);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 256);
  cv::Mat image;
  cv::resize(noise, image, cv::Size(cols, rows), 0, 0, cv::INTER_LINEAR);
  return image;
}

std::string opencv_encode(const std::string& ext, const cv::Mat& image, const std::vector<int>& params = {}) {
  std::vector<uchar> bytes;
  EXPECT_TRUE(cv::imencode(ext, image, bytes, params));
  return std::string(bytes.begin(), bytes.end());
}

struct JpegTestError {
  jpeg_error_mgr error;
  std::jmp_buf jump;
};

[[noreturn]] void jpeg_test_error_exit(j_common_ptr cinfo) { std::longjmp(reinterpret_cast<JpegTestError*>(cinfo->err)->jump, 1); }

bool cmyk_jpeg_guarded(jpeg_compress_struct* cinfo, JpegTestError* error, const unsigned char* pixels, int width, int height,
                       unsigned char** out, unsigned long* out_size) {
  if (setjmp(error->jump)) return false;
  jpeg_CreateCompress(cinfo, JPEG_LIB_VERSION, sizeof(jpeg_compress_struct));
  jpeg_mem_dest(cinfo, out, out_size);
  cinfo->image_width = static_cast<JDIMENSION>(width);
  cinfo->image_height = static_cast<JDIMENSION>(height);
  cinfo->input_components = 4;
  cinfo->in_color_space = JCS_CMYK;
  jpeg_set_defaults(cinfo);
  jpeg_start_compress(cinfo, TRUE);
  for (int y = 0; y < height; ++y) {
    JSAMPROW row = const_cast<JSAMPROW>(pixels + static_cast<std::size_t>(y) * static_cast<std::size_t>(width) * 4);
    jpeg_write_scanlines(cinfo, &row, 1);
  }
  jpeg_finish_compress(cinfo);
  return true;
}

std::string make_cmyk_jpeg(int width, int height) {
  const cv::Mat pixels = smooth_random_image(height, width, CV_8UC4, 7);
  jpeg_compress_struct cinfo;
  std::memset(&cinfo, 0, sizeof(cinfo));
  JpegTestError error;
  cinfo.err = jpeg_std_error(&error.error);
  error.error.error_exit = jpeg_test_error_exit;
  unsigned char* out = nullptr;
  unsigned long out_size = 0;
  const bool ok = cmyk_jpeg_guarded(&cinfo, &error, pixels.data, width, height, &out, &out_size);
  jpeg_destroy_compress(&cinfo);
  std::string bytes = ok ? std::string(reinterpret_cast<const char*>(out), out_size) : std::string();
  std::free(out);
  EXPECT_TRUE(ok) << "libjpeg could not write the CMYK test JPEG";
  return bytes;
}

// The JPEG with an APP1 "Exif" segment inserted after SOI.
std::string with_exif(const std::string& jpeg, const std::string& tiff) {
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  const std::size_t length = payload.size() + 2;
  std::string segment = "\xFF\xE1";
  segment += static_cast<char>(length >> 8);
  segment += static_cast<char>(length & 0xFF);
  return jpeg.substr(0, 2) + segment + payload + jpeg.substr(2);
}

TEST(ImageFile, JpegsDecodeAsOpenCvDecodesThem) {
  const cv::Mat gray = smooth_random_image(61, 83, CV_8UC1, 1);
  const cv::Mat color = smooth_random_image(61, 83, CV_8UC3, 2);
  expect_as_opencv(opencv_encode(".jpg", gray), "grey JPEG");
  expect_as_opencv(opencv_encode(".jpg", color), "colour JPEG (4:2:0)");
  expect_as_opencv(opencv_encode(".jpg", color, {cv::IMWRITE_JPEG_QUALITY, 100}), "colour JPEG quality 100");
  expect_as_opencv(opencv_encode(".jpg", color, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}), "progressive colour JPEG");
  expect_as_opencv(opencv_encode(".jpg", gray, {cv::IMWRITE_JPEG_OPTIMIZE, 1}), "grey JPEG, optimised Huffman tables");
  expect_as_opencv(make_cmyk_jpeg(45, 29), "CMYK JPEG");
  for (int orientation = 1; orientation <= 8; ++orientation) {
    expect_as_opencv(with_exif(opencv_encode(".jpg", color), exif_orientation_tiff(orientation, orientation % 2 == 0)),
                     "JPEG orientation " + std::to_string(orientation));
  }
}

// ---------------------------------------------------------------------------------------------

TEST(ImageFile, WrittenPngsAreOpenCvsBytesAndReadBack) {
  const cv::Mat gray = smooth_random_image(47, 71, CV_8UC1, 3);
  const cv::Mat bgr = smooth_random_image(47, 71, CV_8UC3, 4);
  cv::Mat depth(47, 71, CV_16UC1);
  cv::RNG(5).fill(depth, cv::RNG::UNIFORM, 0, 65536);
  for (const cv::Mat& image : {gray, bgr, depth}) {
    const std::string ours = encode_png(image);
    EXPECT_EQ(ours, opencv_encode(".png", image)) << "type " << image.type();
    EXPECT_TRUE(identical(cairn_decode(ours, ImageMode::kUnchanged), image)) << "type " << image.type();
  }
  // A view into a bigger image (rows not contiguous) is written as the view.
  const cv::Mat view = bgr(cv::Rect(5, 3, 20, 11));
  EXPECT_TRUE(identical(cairn_decode(encode_png(view), ImageMode::kUnchanged), view.clone()));
  EXPECT_THROW(encode_png(cv::Mat()), std::invalid_argument);
  EXPECT_THROW(encode_png(cv::Mat(4, 4, CV_32FC1, cv::Scalar(0))), std::invalid_argument);
}

TEST(ImageFile, RealPngsUnderTheDataRootDecodeAsOpenCvDecodesThem) {
  const fs::path root = test::data_root();
  if (!fs::is_directory(root / "visual")) GTEST_SKIP() << "benchmark data not found: " << root / "visual" << " (set CAIRN_DATA_ROOT)";
  std::vector<fs::path> pngs;
  for (const auto& entry : fs::recursive_directory_iterator(root / "visual")) {
    if (entry.is_regular_file() && entry.path().extension() == ".png") pngs.push_back(entry.path());
  }
  if (pngs.empty()) GTEST_SKIP() << "no PNG under " << root / "visual";
  std::sort(pngs.begin(), pngs.end());
  // Every 25th file keeps this to a few seconds; the first and last always.
  std::vector<fs::path> sample;
  for (std::size_t i = 0; i < pngs.size(); i += 25) sample.push_back(pngs[i]);
  if (sample.back() != pngs.back()) sample.push_back(pngs.back());
  for (const fs::path& path : sample) {
    EXPECT_TRUE(identical(read_image_file(path.string(), ImageMode::kGray8), cv::imread(path.string(), cv::IMREAD_GRAYSCALE))) << path;
    EXPECT_TRUE(identical(read_image_file(path.string(), ImageMode::kUnchanged), cv::imread(path.string(), cv::IMREAD_UNCHANGED))) << path;
  }
  std::cout << "[ compared ] " << sample.size() << " of " << pngs.size() << " PNGs under " << (root / "visual").string() << "\n";
}

// ---------------------------------------------------------------------------------------------
// Hostile files: an ImageFileError naming the file, saying what is wrong; never a crash.

template <typename F>
void expect_error(F&& f, const std::string& file, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no error for " << file << " (expected: " << what << ")";
  } catch (const ImageFileError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(std::string(e.what()).rfind(file + ": ", 0), 0u) << e.what();
    EXPECT_NE(e.detail().find(what), std::string::npos) << "expected \"" << what << "\" in: " << e.what();
  }
}

void expect_file_error(const std::string& name, const std::string& bytes, const std::string& what) {
  const fs::path path = write_file(name, bytes);
  for (ImageMode mode : {ImageMode::kGray8, ImageMode::kUnchanged}) expect_error([&] { read_image_file(path.string(), mode); }, path.string(), what);
}

std::uint32_t crc32(const std::string& bytes) {  // PNG's CRC (ISO 3309), bit by bit
  std::uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char b : bytes) {
    crc ^= b;
    for (int k = 0; k < 8; ++k) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return crc ^ 0xFFFFFFFFu;
}

std::string big_endian(std::uint32_t v) {
  return {static_cast<char>(v >> 24), static_cast<char>((v >> 16) & 0xFF), static_cast<char>((v >> 8) & 0xFF), static_cast<char>(v & 0xFF)};
}

std::string png_chunk(const std::string& type, const std::string& data) {
  return big_endian(static_cast<std::uint32_t>(data.size())) + type + data + big_endian(crc32(type + data));
}

TEST(ImageFile, HostileFilesGiveClearErrorsNamingTheFile) {
  const cv::Mat image = smooth_random_image(40, 60, CV_8UC1, 9);
  const std::string png = encode_png(image);
  for (std::size_t cut : {std::size_t{9}, std::size_t{20}, std::size_t{33}, png.size() / 2, png.size() - 1}) {
    expect_file_error("cut_" + std::to_string(cut) + ".png", png.substr(0, cut), "truncated PNG");
  }
  const std::string jpeg = opencv_encode(".jpg", image);
  expect_file_error("cut_header.jpg", jpeg.substr(0, 100), "truncated JPEG");
  expect_file_error("cut_half.jpg", jpeg.substr(0, jpeg.size() / 2), "truncated JPEG");

  std::mt19937 rng(42);
  std::string noise(4096, '\0');
  for (char& c : noise) c = static_cast<char>(rng() & 0xFF);
  expect_file_error("random.png", noise, "not a PNG or JPEG");
  // Random bytes behind a valid signature reach the decoders' own checks.
  expect_file_error("random_behind_png_signature.png", png.substr(0, 8) + noise, "PNG");
  expect_file_error("random_behind_jpeg_signature.jpg", jpeg.substr(0, 3) + noise, "JPEG");
  std::string flipped = png;  // a damaged byte in the compressed data: bad CRC of a critical chunk
  flipped[png.size() / 2] = static_cast<char>(flipped[png.size() / 2] ^ 0x55);
  expect_file_error("flipped.png", flipped, "invalid or unsupported PNG");
  expect_file_error("empty.png", "", "empty file");
  expect_file_error("text.png", "this is not a PNG\n", "not a PNG or JPEG");
  expect_error([] { read_image_file((scratch() / "missing.png").string(), ImageMode::kGray8); }, (scratch() / "missing.png").string(),
               "cannot open");
  expect_error([] { read_image_file(scratch().string(), ImageMode::kGray8); }, scratch().string(), "is a directory, expected an image file");

  // Declared sizes over 2^28 pixels are refused before any allocation (60000 x 60000 grey 8-bit:
  // 3.6 GB; within libpng's own limit of 1e6 per side).
  std::string ihdr = big_endian(60000) + big_endian(60000) + std::string("\x08\x00\x00\x00\x00", 5);
  const std::string huge = png.substr(0, 8) + png_chunk("IHDR", ihdr) + png_chunk("IDAT", std::string("\x78\x01", 2)) + png_chunk("IEND", "");
  expect_file_error("huge.png", huge, "more than the 268435456 pixels");
  std::string huge_jpeg = jpeg;  // SOF0: FF C0, length (2), precision (1), height (2), width (2)
  const std::size_t sof = huge_jpeg.find("\xFF\xC0");
  ASSERT_NE(sof, std::string::npos);
  for (std::size_t k : {5u, 6u, 7u, 8u}) huge_jpeg[sof + k] = static_cast<char>(k % 2 == 1 ? 0xFD : 0xE8);  // 65000 x 65000
  expect_file_error("huge.jpg", huge_jpeg, "more than the 268435456 pixels");
  // The same from memory, with the caller's name for the bytes.
  expect_error([&] { decode_image(reinterpret_cast<const unsigned char*>(huge.data()), huge.size(), ImageMode::kUnchanged, "frame 7"); },
               "frame 7", "60000 x 60000 pixels");
}

}  // namespace
}  // namespace cairn::vision
