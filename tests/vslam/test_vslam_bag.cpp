// `cairn vslam BAG` (issue 37): a bag's images are read as cairn reads the same images from files,
// so a run on a bag gives the folder run's trajectory to the last digit; topics and calibration
// come from the bag; what cannot be read is named. The bags are made at test time by
// tests/bag/fixtures/make_all.sh, an independent writer (python3-rosbag): $CAIRN_BAG_FIXTURES,
// ctest fixture bag_fixtures (frames20/: 20 frames of TUM fr1_desk and KITTI).

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/core/time.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vision/image_file.hpp"
#include "cairn/vslam/bag_frame_reader.hpp"
#include "cairn/vslam/bag_images.hpp"
#include "cairn/vslam/bag_topics.hpp"
#include "cairn/vslam/camera_info_calibration.hpp"
#include "cairn/vslam/image_message.hpp"
#include "cairn/vslam/stamp_pairing.hpp"
#include "cli/cli_runner.hpp"
#include "test_data.hpp"

namespace cairn::vslam {
namespace {

namespace fs = std::filesystem;
using test::slurp;

constexpr const char* kTum = "visual/tum_fr1_desk_every4th";
constexpr const char* kKitti = "visual/kitti_extract_seq2";

fs::path fixtures() {
  const char* dir = std::getenv("CAIRN_BAG_FIXTURES");
  return dir != nullptr ? dir : "";
}

#define REQUIRE_FIXTURE(name)                                                                                   \
  do {                                                                                                          \
    if (!fs::exists(fixtures() / (name))) {                                                                     \
      GTEST_SKIP() << "fixture " << (fixtures() / (name)) << " not made (tests/bag/fixtures/make_all.sh)"; \
    }                                                                                                           \
  } while (false)

fs::path scratch() { return test::scratch_folder("vslam_bag"); }
std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }
test::CliResult run(const std::string& args) { return test::run_command(CAIRN_BINARY, args, scratch() / "stderr.txt"); }

bool same_pixels(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && (a.empty() || cv::countNonZero(a.reshape(1) != b.reshape(1)) == 0);
}

std::string parse_error_of(const auto& call) {
  try {
    call();
  } catch (const io::ParseError& e) {
    return e.what();
  }
  return "no io::ParseError";
}

/// The first `n` colour PNGs of TUM fr1_desk, in name (= time) order.
std::vector<fs::path> tum_colour_pngs(std::size_t n) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(test::data_path(std::string(kTum) + "/rgb"))) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  files.resize(std::min(n, files.size()));
  return files;
}

cv::Mat decode_file(const fs::path& path, vision::ImageMode mode) { return vision::read_image_file(path.string(), mode); }

// ---------------------------------------------------------------------------------------------
// Image messages (vslam/image_message.hpp)

/// A raw image message of a BGR picture in `encoding` (rgb8, bgr8, rgba8, bgra8), rows padded.
bag::Image colour_message(const cv::Mat& bgr, const std::string& encoding, std::uint32_t padding) {
  const std::size_t channels = encoding.size() == 5 ? 4 : 3;
  bag::Image image;
  image.width = static_cast<std::uint32_t>(bgr.cols);
  image.height = static_cast<std::uint32_t>(bgr.rows);
  image.encoding = encoding;
  image.step = static_cast<std::uint32_t>(channels * image.width + padding);
  image.data.assign(std::size_t{image.step} * image.height, '\x7f');
  const bool rgb = encoding.starts_with("rgb");
  for (int y = 0; y < bgr.rows; ++y) {
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      char* out = image.data.data() + std::size_t{image.step} * y + channels * x;
      out[0] = static_cast<char>(rgb ? p[2] : p[0]);
      out[1] = static_cast<char>(p[1]);
      out[2] = static_cast<char>(rgb ? p[0] : p[2]);
    }
  }
  return image;
}

// The grey a bag's rgb8 / bgr8 / rgba8 / bgra8 image becomes is the grey libpng (as cv::imread)
// makes of the PNG of the same pixels: TUM's colour PNGs and the fixture's rgb8 copies of them.
TEST(BagImageMessage, ColourIsMadeGreyAsThePngDecoderMakesIt) {
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/rgb");
  for (const fs::path& png : tum_colour_pngs(3)) {
    const cv::Mat bgr = decode_file(png, vision::ImageMode::kUnchanged);
    const cv::Mat gray = decode_file(png, vision::ImageMode::kGray8);
    ASSERT_EQ(bgr.type(), CV_8UC3) << png;
    for (const char* encoding : {"rgb8", "bgr8", "rgba8", "bgra8"}) {
      EXPECT_TRUE(same_pixels(decode_gray(colour_message(bgr, encoding, 5), "x.bag", "/image"), gray)) << png << " " << encoding;
    }
  }
}

TEST(BagImageMessage, GreyAndDepthEncodings) {
  bag::Image mono16;
  mono16.width = 2;
  mono16.height = 1;
  mono16.encoding = "mono16";
  mono16.step = 4;
  mono16.data = std::string("\x34\x12\xff\x00", 4);  // little-endian 0x1234, 0x00ff
  const cv::Mat gray = decode_gray(mono16, "x.bag", "/ir");
  EXPECT_EQ(gray.at<unsigned char>(0, 0), 0x12);  // the high byte, as png_set_strip_16
  EXPECT_EQ(gray.at<unsigned char>(0, 1), 0x00);

  bag::Image depth = mono16;
  depth.encoding = "16UC1";
  depth.is_bigendian = true;
  const cv::Mat big = decode_depth(depth, 1.0, "x.bag", "/depth");
  EXPECT_EQ(big.at<std::uint16_t>(0, 0), 0x3412);
  EXPECT_EQ(big.at<std::uint16_t>(0, 1), 0xff00);

  const std::vector<float> metres{1.2345f, std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), -1.0f, 0.0f,
                                  70.0f, 0.0004f};
  bag::Image floats;
  floats.width = static_cast<std::uint32_t>(metres.size());
  floats.height = 1;
  floats.encoding = "32FC1";
  floats.step = static_cast<std::uint32_t>(4 * metres.size());
  floats.data.resize(floats.step);
  std::memcpy(floats.data.data(), metres.data(), floats.step);
  floats.is_bigendian = std::endian::native == std::endian::big;
  const cv::Mat millimetres = decode_depth(floats, 1.0, "x.bag", "/depth");
  ASSERT_EQ(millimetres.type(), CV_16UC1);
  // 1.2345 m -> 1235 mm (kFloatDepthUnitsPerM); NaN, inf, negative, 0, beyond 65.535 m and below
  // half a millimetre: no depth.
  const std::vector<std::uint16_t> expected{1235, 0, 0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < expected.size(); ++i) EXPECT_EQ(millimetres.at<std::uint16_t>(0, static_cast<int>(i)), expected[i]) << i;
  // Floats in millimetres (--depth-scale 1000).
  EXPECT_EQ(decode_depth(floats, 1000.0, "x.bag", "/depth").at<std::uint16_t>(0, 0), 1);
}

TEST(BagImageMessage, WhatCannotBeReadIsNamed) {
  bag::Image image;
  image.width = 4;
  image.height = 2;
  image.step = 4;
  image.encoding = "bayer_rggb8";
  image.data.assign(8, '\0');
  std::string error = parse_error_of([&] { decode_gray(image, "x.bag", "/camera/image_raw @ 1 s"); });
  EXPECT_NE(error.find("x.bag: /camera/image_raw @ 1 s: image encoding 'bayer_rggb8' is not read as a grey image (mono8, 8UC1, rgb8"),
            std::string::npos)
      << error;
  image.encoding = "32FC1";
  error = parse_error_of([&] { decode_gray(image, "x.bag", "/depth"); });
  EXPECT_NE(error.find("is it a depth topic?"), std::string::npos) << error;
  image.encoding = "yuv422";
  error = parse_error_of([&] { decode_depth(image, 1.0, "x.bag", "/depth"); });
  EXPECT_NE(error.find("'yuv422' is not read as depth (16UC1, mono16, 32FC1 are"), std::string::npos) << error;
  image.encoding = "mono8";
  image.data.resize(7);
  error = parse_error_of([&] { decode_gray(image, "x.bag", "/image"); });
  EXPECT_NE(error.find("the data holds 7 bytes, step x height = 8"), std::string::npos) << error;
  image.encoding = "rgb8";
  error = parse_error_of([&] { decode_gray(image, "x.bag", "/image"); });
  EXPECT_NE(error.find("step 4 is less than width x bytes per pixel = 12"), std::string::npos) << error;
  image.height = 0;
  error = parse_error_of([&] { decode_gray(image, "x.bag", "/image"); });
  EXPECT_NE(error.find("an empty image (4 x 0 pixels)"), std::string::npos) << error;
}

TEST(BagImageMessage, CompressedImagesAreDecodedByCairnsDecoders) {
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/depth");
  const fs::path colour = tum_colour_pngs(1).front();
  bag::CompressedImage png;
  png.format = "png";
  png.data = slurp(colour);
  EXPECT_TRUE(same_pixels(decode_gray(png, "x.bag", "/c"), decode_file(colour, vision::ImageMode::kGray8)));

  fs::path depth_png;
  for (const auto& entry : fs::directory_iterator(test::data_path(std::string(kTum) + "/depth"))) depth_png = entry.path();
  const cv::Mat depth = vision::read_depth_image(depth_png.string());
  bag::CompressedImage depth_message;
  depth_message.format = "16UC1; png compressed 16UC1";
  depth_message.data = slurp(depth_png);
  EXPECT_TRUE(same_pixels(decode_depth(depth_message, "x.bag", "/d"), depth));
  // compressed_depth_image_transport: a 12-byte ConfigHeader before the PNG.
  depth_message.format = "16UC1; compressedDepth png";
  depth_message.data = std::string(12, '\0') + slurp(depth_png);
  EXPECT_TRUE(same_pixels(decode_depth(depth_message, "x.bag", "/d"), depth));
  std::string error = parse_error_of([&] { decode_gray(depth_message, "x.bag", "/d"); });
  EXPECT_NE(error.find("is depth, not a grey or colour image"), std::string::npos) << error;
  depth_message.format = "32FC1; compressedDepth";
  error = parse_error_of([&] { decode_depth(depth_message, "x.bag", "/d"); });
  EXPECT_NE(error.find("32FC1 compressedDepth (quantised inverse depth) is not read"), std::string::npos) << error;
  // A colour PNG is not depth; bytes that are neither PNG nor JPEG say which format was claimed.
  error = parse_error_of([&] { decode_depth(png, "x.bag", "/c"); });
  EXPECT_NE(error.find("holds 3 channel(s) of 8-bit values; depth must be one channel of 16 bits"), std::string::npos) << error;
  png.format = "tiff";
  png.data = "II*\0 not an image";
  error = parse_error_of([&] { decode_gray(png, "x.bag", "/c"); });
  EXPECT_NE(error.find("x.bag: /c: CompressedImage of format 'tiff': "), std::string::npos) << error;
}

// ---------------------------------------------------------------------------------------------
// Frames from stamps (vslam/stamp_pairing.hpp)

TEST(BagStampPairing, StereoPairsByEqualStamps) {
  const std::vector<StampPair> pairs = pair_equal_stamps({30, 10, 20, 20, 50}, {20, 10, 40, 30});
  EXPECT_EQ(pairs, (std::vector<StampPair>{{1, 1}, {2, 0}, {0, 3}}));  // by stamp; the repeated 20 pairs once
}

TEST(BagStampPairing, ColourAndDepthAssociateAsTumsAssociatePy) {
  // Closest first, each used once, ordered by the colour stamp.
  EXPECT_EQ(associate_stamps({100, 0, 200}, {95, 6, 300}, 20), (std::vector<StampPair>{{1, 1}, {0, 0}}));
  // 10 is closer to 6 than 0 is: 0 goes without.
  EXPECT_EQ(associate_stamps({0, 10}, {6}, 20), (std::vector<StampPair>{{1, 0}}));
  // |difference| < max_difference, strictly (associate.py).
  EXPECT_TRUE(associate_stamps({0}, {20}, 20).empty());
  EXPECT_EQ(associate_stamps({0}, {19}, 20).size(), 1u);
  EXPECT_EQ(associate_stamps({40}, {21}, 20).size(), 1u);
}

// ---------------------------------------------------------------------------------------------
// CameraInfo (vslam/camera_info_calibration.hpp) and topics (vslam/bag_topics.hpp)

bag::CameraInfo kitti_info(const std::array<double, 12>& P) {
  bag::CameraInfo info;
  info.width = 1241;
  info.height = 376;
  info.distortion_model = "plumb_bob";
  info.D = {0, 0, 0, 0, 0};
  info.K = {P[0], P[1], P[2], P[4], P[5], P[6], P[8], P[9], P[10]};
  info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  info.P = P;
  return info;
}

TEST(BagCameraInfo, RectifiedStereoGivesKittisCalibration) {
  CAIRN_REQUIRE_DATA(std::string(kKitti) + "/calib.txt");
  const io::CameraCalibration kitti = io::read_kitti_calibration(test::data_path(std::string(kKitti) + "/calib.txt").string());
  const bag::CameraInfo left = kitti_info({718.856, 0, 607.1928, 0, 0, 718.856, 185.2157, 0, 0, 0, 1, 0});
  const bag::CameraInfo right = kitti_info({718.856, 0, 607.1928, -386.1448, 0, 718.856, 185.2157, 0, 0, 0, 1, 0});
  const io::CameraCalibration c = camera_from_stereo_camera_infos(left, right, "/l/image_raw", "/r/image_raw", "x.bag", "/l/ci", "/r/ci");
  EXPECT_EQ(c.fx, kitti.fx);
  EXPECT_EQ(c.fy, kitti.fy);
  EXPECT_EQ(c.cx, kitti.cx);
  EXPECT_EQ(c.cy, kitti.cy);
  EXPECT_EQ(c.baseline_m, kitti.baseline_m);  // to the last bit
  EXPECT_FALSE(c.has_distortion());

  bag::CameraInfo turned = right;
  turned.R = {0.9999, -0.0141, 0, 0.0141, 0.9999, 0, 0, 0, 1};
  std::string error = parse_error_of([&] { camera_from_stereo_camera_infos(left, turned, "/l/image_raw", "/r/image_raw", "x.bag", "/l/ci", "/r/ci"); });
  EXPECT_NE(error.find("the images are not rectified"), std::string::npos) << error;
  EXPECT_NE(error.find("--image-topic /l/image_raw"), std::string::npos) << error;
  // image_proc's image_rect topics are rectified whatever R says: P describes them.
  EXPECT_EQ(camera_from_stereo_camera_infos(left, turned, "/l/image_rect", "/r/image_rect", "x.bag", "/l/ci", "/r/ci").baseline_m, kitti.baseline_m);
  bag::CameraInfo other = right;
  other.P[2] = 600.0;
  error = parse_error_of([&] { camera_from_stereo_camera_infos(left, other, "/l/image_raw", "/r/image_raw", "x.bag", "/l/ci", "/r/ci"); });
  EXPECT_NE(error.find("the two P differ in fx, fy, cx or cy"), std::string::npos) << error;
  error = parse_error_of([&] { camera_from_stereo_camera_infos(right, left, "/l/image_raw", "/r/image_raw", "x.bag", "/l/ci", "/r/ci"); });
  EXPECT_NE(error.find("expected P[3] = -fx * baseline < 0"), std::string::npos) << error;
}

TEST(BagCameraInfo, MonocularCameraFromKAndD) {
  bag::CameraInfo info = kitti_info({525, 0, 319.5, 0, 0, 525, 239.5, 0, 0, 0, 1, 0});
  info.K = {517.3, 0, 318.6, 0, 516.5, 255.3, 0, 0, 1};
  info.D = {0.2624, -0.9531, -0.0054, 0.0026, 1.1633};
  io::CameraCalibration c = camera_from_camera_info(info, "/camera/rgb/image_color", "x.bag", "/camera/rgb/camera_info");
  EXPECT_EQ(c.fx, 517.3);
  EXPECT_EQ(c.fy, 516.5);
  EXPECT_EQ(c.cx, 318.6);
  EXPECT_EQ(c.cy, 255.3);
  EXPECT_EQ(c.k1, 0.2624);
  EXPECT_EQ(c.p1, -0.0054);
  EXPECT_EQ(c.k3, 1.1633);
  // A rectified topic: P's camera, no distortion.
  c = camera_from_camera_info(info, "/camera/rgb/image_rect_color", "x.bag", "/camera/rgb/camera_info");
  EXPECT_EQ(c.fx, 525.0);
  EXPECT_FALSE(c.has_distortion());
  info.distortion_model = "rational_polynomial";
  info.D = {0.1, 0.01, 0, 0, 0.001, 0, 0, 0};
  EXPECT_EQ(camera_from_camera_info(info, "/image", "x.bag", "/camera_info").k3, 0.001);
  info.D[5] = 0.2;
  std::string error = parse_error_of([&] { camera_from_camera_info(info, "/image", "x.bag", "/camera_info"); });
  EXPECT_NE(error.find("distortion model 'rational_polynomial' with 8 coefficients is not undistorted by cairn"), std::string::npos) << error;
  info.D.assign(5, 0.0);
  info.K = {};
  error = parse_error_of([&] { camera_from_camera_info(info, "/image", "x.bag", "/camera_info"); });
  EXPECT_NE(error.find("CameraInfo on /camera_info: K has fx 0, fy 0: not a calibrated camera"), std::string::npos) << error;
}

TEST(BagTopics, CameraInfoBesideTheImagesAndFlagCombinations) {
  EXPECT_EQ(sibling_camera_info_topic("/camera/rgb/image_color"), "/camera/rgb/camera_info");
  EXPECT_EQ(sibling_camera_info_topic("/camera/rgb/image_color/compressed"), "/camera/rgb/camera_info");
  EXPECT_EQ(sibling_camera_info_topic("/camera/depth/image_raw/compressedDepth"), "/camera/depth/camera_info");
  EXPECT_EQ(sibling_camera_info_topic("image"), "camera_info");
  EXPECT_TRUE(is_rectified_topic("/stereo/left/image_rect"));
  EXPECT_TRUE(is_rectified_topic("/camera/rgb/image_rect_color/compressed"));
  EXPECT_FALSE(is_rectified_topic("/camera/rgb/image_raw"));
  EXPECT_FALSE(is_rectified_topic("/image_rectangle_finder/image"));
  EXPECT_FALSE(is_rectified_topic("/camera/image_rectangles"));
  EXPECT_TRUE(is_rectified_topic("image_rect"));

  std::string why;
  EXPECT_TRUE(BagTopicRequest{}.is_valid(&why));
  EXPECT_TRUE((BagTopicRequest{"/l", "/r", "", "", "", ""}.is_valid(&why)));
  EXPECT_TRUE((BagTopicRequest{"", "", "/rgb", "/depth", "/rgb/info", ""}.is_valid(&why)));
  EXPECT_FALSE((BagTopicRequest{"/l", "", "/rgb", "", "", ""}.is_valid(&why)));
  EXPECT_NE(why.find("--left-topic and --right-topic go together"), std::string::npos) << why;
  EXPECT_NE(why.find("exclude each other"), std::string::npos) << why;
  EXPECT_FALSE((BagTopicRequest{"", "", "", "/depth", "", ""}.is_valid(&why)));
  EXPECT_NE(why.find("--depth-topic needs --image-topic"), std::string::npos) << why;
}

// ---------------------------------------------------------------------------------------------
// The bag's frames (vslam/bag_images.hpp, bag_frame_reader.hpp), against the image files they
// were made from

/// The first `n` lines of TUM fr1_desk's associations.txt: rgb stamp, rgb file, depth stamp, depth file.
std::vector<std::vector<std::string>> tum_associations(std::size_t n) {
  std::ifstream in(test::data_path(std::string(kTum) + "/associations.txt"));
  std::vector<std::vector<std::string>> rows;
  for (std::string line; rows.size() < n && std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<std::string> row(4);
    fields >> row[0] >> row[1] >> row[2] >> row[3];
    rows.push_back(row);
  }
  return rows;
}

TEST(BagImages, TumRgbdFramesAreTheFilesImages) {
  REQUIRE_FIXTURE("tum_rgbd.bag");
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/associations.txt");
  const std::string bag = (fixtures() / "tum_rgbd.bag").string();
  BagImages images = read_bag_images(bag, {});
  EXPECT_EQ(images.sequence.kind, io::SequenceKind::kRgbd);
  EXPECT_EQ(images.sequence.layout, "bag");
  EXPECT_EQ(images.sequence.calibration.depth_units_per_m, 1000.0);  // REP 118 when not told
  EXPECT_EQ(images.sequence.calibration.fx, 517.3);
  EXPECT_EQ(images.sequence.calibration.width, 640);
  EXPECT_EQ(images.calibration_source, "CameraInfo /camera/rgb/camera_info");
  BagImageOptions options;
  options.depth_units_per_m = 5000.0;
  images = read_bag_images(bag, options);
  EXPECT_EQ(images.sequence.calibration.depth_units_per_m, 5000.0);
  const auto rows = tum_associations(images.sequence.frames.size());
  ASSERT_EQ(rows.size(), 3u);
  BagFrameReader reader(images, io::SequenceKind::kRgbd);
  const fs::path tum = test::data_path(kTum);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_EQ(images.sequence.frames[k].time, *core::Timestamp::parse_seconds(rows[k][0])) << k;
    EXPECT_EQ(images.partner_stamps_ns[k], core::Timestamp::parse_seconds(rows[k][2])->nanoseconds()) << k;
    const FrameImages frame = reader.read(k);
    EXPECT_TRUE(same_pixels(frame.gray, vision::read_gray_image((tum / rows[k][1]).string()))) << k;
    EXPECT_TRUE(same_pixels(frame.depth, vision::read_depth_image((tum / rows[k][3]).string()))) << k;
  }
  EXPECT_THROW(reader.read(0), std::logic_error);
}

TEST(BagImages, CompressedColourFramesAreTheFilesImages) {
  REQUIRE_FIXTURE("tum_rgb_compressed.bag");
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/associations.txt");
  const std::string bag = (fixtures() / "tum_rgb_compressed.bag").string();
  // No CameraInfo in this bag: refused, naming the topic looked for and the flags, unless the
  // calibration is given.
  const std::string error = parse_error_of([&] { read_bag_images(bag, {}); });
  EXPECT_NE(error.find("no CameraInfo topic /camera/rgb/camera_info (looked for beside /camera/rgb/image_color/compressed): name the "
                       "CameraInfo topic with --camera-info-topic, or give the calibration with --calib FILE"),
            std::string::npos)
      << error;
  BagImageOptions options;
  options.calibration_given = true;
  const BagImages images = read_bag_images(bag, options);
  EXPECT_EQ(images.sequence.kind, io::SequenceKind::kMonocular);
  const auto rows = tum_associations(images.sequence.frames.size());
  BagFrameReader reader(images, io::SequenceKind::kMonocular);
  for (std::size_t k = 0; k < rows.size(); ++k) {
    EXPECT_TRUE(same_pixels(reader.read(k).gray, vision::read_gray_image((test::data_path(kTum) / rows[k][1]).string()))) << k;
  }
}

// ---------------------------------------------------------------------------------------------
// `cairn vslam BAG` against `cairn vslam FOLDER` on the same images

/// The TUM calibration the fixture's CameraInfo holds, as a --calib file (and RGB-D's depth scale
/// and virtual baseline as a bag run sets them).
fs::path tum_calibration_yaml() {
  const fs::path path = scratch() / "tum_bag_camera.yaml";
  std::ofstream yaml(path);
  yaml.precision(17);
  yaml << "fx: 517.3\nfy: 516.5\ncx: 318.6\ncy: 255.3\nk1: 0.2624\nk2: -0.9531\np1: -0.0054\np2: 0.0026\nk3: 1.1633\n"
       << "width: 640\nheight: 480\ndepth_units_per_m: 5000\nvirtual_baseline_m: " << kRgbdBaselineTimesFxPx / 517.3 << "\n";
  return path;
}

/// A TUM folder of the first `n` frames of fr1_desk: their associations.txt lines, rgb/ and depth/
/// linked to the shared data.
fs::path tum_folder(std::size_t n) {
  const fs::path folder = scratch() / ("tum_first_" + std::to_string(n));
  fs::remove_all(folder);
  fs::create_directories(folder);
  fs::create_directory_symlink(test::data_path(std::string(kTum) + "/rgb"), folder / "rgb");
  fs::create_directory_symlink(test::data_path(std::string(kTum) + "/depth"), folder / "depth");
  std::ofstream list(folder / "associations.txt");
  for (const auto& row : tum_associations(n)) list << row[0] << ' ' << row[1] << ' ' << row[2] << ' ' << row[3] << '\n';
  return folder;
}

nlohmann::json report_of(const fs::path& out) { return nlohmann::json::parse(slurp(out / "report.json")); }

fs::path fresh(const std::string& name) {
  const fs::path out = scratch() / name;
  fs::remove_all(out);
  return out;
}

TEST(VslamBagCli, TumRgbdBagRunsAsTheFolderOfItsImages) {
  REQUIRE_FIXTURE("frames20/tum_rgbd.bag");
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/associations.txt");
  const fs::path bag_out = fresh("tum_bag"), folder_out = fresh("tum_folder");
  // No topic flag: one colour and one 16UC1 topic make RGB-D; TUM's values are 5000 per metre.
  test::CliResult r = run("vslam " + quoted(fixtures() / "frames20/tum_rgbd.bag") + " --depth-scale 5000 -q --out " + quoted(bag_out));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run("vslam " + quoted(tum_folder(20)) + " --calib " + quoted(tum_calibration_yaml()) + " -q --out " + quoted(folder_out));
  ASSERT_EQ(r.status, 0) << r.err;
  for (const char* file : {"trajectory.tum", "keyframes.tum", "trajectory.kitti", "map_points.ply"}) {
    EXPECT_EQ(slurp(bag_out / file), slurp(folder_out / file)) << file;
  }
  const nlohmann::json report = report_of(bag_out);
  const nlohmann::json& input = report["input"];
  EXPECT_EQ(input["layout"], "bag");
  EXPECT_EQ(input["kind"], "rgbd");
  EXPECT_EQ(input["bag"], (fixtures() / "frames20/tum_rgbd.bag").string());
  EXPECT_EQ(input["topics"]["image"], "/camera/rgb/image_color");
  EXPECT_EQ(input["topics"]["depth"], "/camera/depth/image");
  EXPECT_EQ(input["topics"]["camera_info"], "/camera/rgb/camera_info");
  EXPECT_EQ(input["calibration"]["source"], "CameraInfo /camera/rgb/camera_info");
  EXPECT_EQ(input["calibration"]["depth_units_per_m"], 5000.0);
  EXPECT_EQ(input["frames_processed"], 20);
  EXPECT_EQ(report["summary"]["ok"], 20) << report["summary"].dump();
}

TEST(VslamBagCli, KittiStereoBagRunsAsTheKittiFolder) {
  REQUIRE_FIXTURE("frames20/kitti_stereo.bag");
  CAIRN_REQUIRE_DATA(std::string(kKitti) + "/calib.txt");
  const fs::path bag_out = fresh("kitti_bag"), folder_out = fresh("kitti_folder");
  // The KITTI layout's setting of 2000 features is not a bag's (1000): given.
  test::CliResult r = run("vslam " + quoted(fixtures() / "frames20/kitti_stereo.bag") + " --features 2000 -q --out " + quoted(bag_out));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run("vslam " + quoted(test::data_path(kKitti)) + " --max-frames 20 -q --out " + quoted(folder_out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(bag_out / "trajectory.kitti"), slurp(folder_out / "trajectory.kitti"));
  EXPECT_EQ(slurp(bag_out / "map_points.ply"), slurp(folder_out / "map_points.ply"));
  // The same poses; the bag's stamps are 1e9 s after the folder's (times.txt-less: 0.1 s apart from 0).
  std::istringstream bag_lines(slurp(bag_out / "trajectory.tum")), folder_lines(slurp(folder_out / "trajectory.tum"));
  std::size_t poses = 0;
  for (std::string b, f; std::getline(bag_lines, b) && std::getline(folder_lines, f);) {
    if (b.starts_with("#")) continue;
    const std::size_t bs = b.find(' '), fs_ = f.find(' ');
    EXPECT_EQ(b.substr(bs), f.substr(fs_));
    EXPECT_EQ(core::Timestamp::parse_seconds(b.substr(0, bs))->nanoseconds() - core::Timestamp::parse_seconds(f.substr(0, fs_))->nanoseconds(),
              std::int64_t{1'000'000'000} * 1'000'000'000);
    ++poses;
  }
  EXPECT_EQ(poses, 20u);
  const nlohmann::json input = report_of(bag_out)["input"];
  EXPECT_EQ(input["kind"], "stereo");
  EXPECT_EQ(input["topics"]["left"], "/stereo/left/image_raw");
  EXPECT_EQ(input["topics"]["right"], "/stereo/right/image_raw");
  EXPECT_EQ(input["topics"]["right_camera_info"], "/stereo/right/camera_info");
  EXPECT_EQ(input["calibration"]["baseline_m"], report_of(folder_out)["input"]["calibration"]["baseline_m"]);
}

TEST(VslamBagCli, CompressedColourBagRunsAsAMonocularFolder) {
  REQUIRE_FIXTURE("frames20/tum_rgb_compressed.bag");
  CAIRN_REQUIRE_DATA(std::string(kTum) + "/associations.txt");
  const fs::path bag_out = fresh("mono_bag"), folder_out = fresh("mono_folder");
  const fs::path bag = fixtures() / "frames20/tum_rgb_compressed.bag";
  // The bag has no CameraInfo: refused before any work, naming the topic looked for and the flags.
  test::CliResult r = run("vslam " + quoted(bag) + " --out " + quoted(bag_out));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no CameraInfo topic /camera/rgb/camera_info"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--camera-info-topic"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(bag_out));
  r = run("vslam " + quoted(bag) + " --calib " + quoted(tum_calibration_yaml()) + " -q --out " + quoted(bag_out));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run("vslam " + quoted(tum_folder(20)) + " --mono --calib " + quoted(tum_calibration_yaml()) + " -q --out " + quoted(folder_out));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(bag_out / "trajectory.tum"), slurp(folder_out / "trajectory.tum"));
  EXPECT_EQ(slurp(bag_out / "trajectory.kitti"), slurp(folder_out / "trajectory.kitti"));
  const nlohmann::json report = report_of(bag_out);
  EXPECT_EQ(report["input"]["kind"], "monocular");
  EXPECT_GT(report["summary"]["ok"].get<int>(), 5) << report["summary"].dump();  // initialised and tracked: a comparison of substance
}

TEST(VslamBagCli, NamedTopicsAndTheirErrors) {
  REQUIRE_FIXTURE("kitti_stereo.bag");
  REQUIRE_FIXTURE("tum_rgbd.bag");
  const fs::path stereo = fixtures() / "kitti_stereo.bag", rgbd = fixtures() / "tum_rgbd.bag";
  const fs::path chosen = fresh("chosen"), named = fresh("named");
  test::CliResult r = run("vslam " + quoted(stereo) + " -q --out " + quoted(chosen));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run("vslam " + quoted(stereo) + " --left-topic /stereo/left/image_raw --right-topic /stereo/right/image_raw" +
          " --camera-info-topic /stereo/left/camera_info -q --out " + quoted(named));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(slurp(named / "trajectory.tum"), slurp(chosen / "trajectory.tum"));

  const fs::path none = fresh("none");
  r = run("vslam " + quoted(rgbd) + " --image-topic /camera/rgb/image_colour --out " + quoted(none));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no topic '/camera/rgb/image_colour'; the bag has:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/camera/depth/image (sensor_msgs/Image)"), std::string::npos) << r.err;
  r = run("vslam " + quoted(rgbd) + " --image-topic /camera/depth/image --out " + quoted(none));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("image encoding '16UC1' is not read as a grey image"), std::string::npos) << r.err;
  r = run("vslam " + quoted(rgbd) + " --image-topic /camera/rgb/camera_info --out " + quoted(none));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("the topic has type sensor_msgs/CameraInfo"), std::string::npos) << r.err;
  r = run("vslam " + quoted(rgbd) + " --camera-info-topic /camera/info --out " + quoted(none));
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("no topic '/camera/info'"), std::string::npos) << r.err;
  // Usage errors (exit status 2): flags that do not go together, or with a folder.
  r = run("vslam " + quoted(stereo) + " --left-topic /stereo/left/image_raw --out " + quoted(none));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--left-topic and --right-topic go together"), std::string::npos) << r.err;
  CAIRN_REQUIRE_DATA(std::string(kKitti) + "/calib.txt");
  r = run("vslam " + quoted(test::data_path(kKitti)) + " --image-topic /camera/image --out " + quoted(none));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--image-topic goes with a bag input"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(none));
}

}  // namespace
}  // namespace cairn::vslam
