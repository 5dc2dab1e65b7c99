// Image-sequence folders: the real KITTI extract and TUM folder as they are, and broken copies of
// their text files, each refused with the file, the line and what was expected.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "cairn/io/image_sequence.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::io {
namespace {

namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("cairn_test_image_sequence_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

void write(const fs::path& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Expects a ParseError naming `file` (and `line` when > 0) whose text contains `what`.
template <typename F>
void expect_error(F&& f, const fs::path& file, std::size_t line, const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no error; expected " << what;
  } catch (const ParseError& e) {
    EXPECT_EQ(e.file(), file.string()) << e.what();
    if (line > 0) {
      EXPECT_EQ(e.line(), line) << e.what();
    }
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(ImageSequence, ReadsTheKittiExtract) {
  CAIRN_REQUIRE_DATA("visual/kitti_extract_seq2/calib.txt");
  const std::string folder = test::data_path("visual/kitti_extract_seq2").string();
  EXPECT_EQ(detect_image_layout(folder), "kitti");
  const ImageSequence seq = read_kitti_stereo(folder);
  EXPECT_EQ(seq.kind, SequenceKind::kStereo);
  ASSERT_EQ(seq.frames.size(), 51u);
  // The SOURCE.txt values: fx = fy = 718.856, cx 607.1928, cy 185.2157, baseline 386.1448 / fx.
  EXPECT_DOUBLE_EQ(seq.calibration.fx, 718.856);
  EXPECT_DOUBLE_EQ(seq.calibration.cy, 185.2157);
  EXPECT_NEAR(seq.calibration.baseline_m, 386.1448 / 718.856, 1e-12);
  EXPECT_FALSE(seq.times_from_file);
  ASSERT_FALSE(seq.notes.empty());
  EXPECT_NE(seq.notes.front().find("0.1 s apart"), std::string::npos);
  ASSERT_TRUE(seq.ground_truth.has_value());
  EXPECT_EQ(seq.ground_truth->size(), 51u);
  EXPECT_NE(seq.frames[50].image.find("image_l/000050.png"), std::string::npos);
  EXPECT_NE(seq.frames[50].right_image.find("image_r/000050.png"), std::string::npos);
}

TEST(ImageSequence, ReadsTheTumFolderThroughItsAssociations) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th/associations.txt");
  const std::string folder = test::data_path("visual/tum_fr1_desk_every4th").string();
  EXPECT_EQ(detect_image_layout(folder), "tum");
  const ImageSequence seq = read_tum_rgbd(folder);
  EXPECT_EQ(seq.kind, SequenceKind::kRgbd);
  EXPECT_EQ(seq.frames.size(), 149u);  // SOURCE.txt: 149 associated pairs
  ASSERT_TRUE(seq.ground_truth.has_value());
  EXPECT_EQ(seq.ground_truth->size(), 2335u);
  EXPECT_FALSE(seq.calibration_from_dataset);
}

TEST(ImageSequence, AssociatesRgbAndDepthListsAsTumsScriptDoes) {
  const fs::path dir = scratch("associate");
  write(dir / "rgb.txt", "# colour\n1.00 rgb/a.png\n1.10 rgb/b.png\n1.20 rgb/c.png\n");
  // b's nearest depth (1.115) is also c's nearest but nearer to b; c takes nothing within 0.02 s.
  write(dir / "depth.txt", "0.995 depth/a.png\n1.115 depth/b.png\n");
  const ImageSequence seq = read_tum_rgbd(dir.string());
  ASSERT_EQ(seq.frames.size(), 2u);
  EXPECT_NE(seq.frames[0].depth_image.find("depth/a.png"), std::string::npos);
  EXPECT_NE(seq.frames[1].image.find("rgb/b.png"), std::string::npos);
  ASSERT_EQ(seq.notes.size(), 1u);
  EXPECT_NE(seq.notes[0].find("1 colour images have no depth map"), std::string::npos);
  fs::remove_all(dir);
}

TEST(ImageSequence, BadFilesNameFileLineAndWhatWasExpected) {
  const fs::path dir = scratch("bad");
  fs::create_directories(dir / "image_0");
  fs::create_directories(dir / "image_1");
  write(dir / "image_0" / "000000.png", "x");
  write(dir / "image_1" / "000000.png", "x");
  write(dir / "image_0" / "000001.png", "x");
  const std::string p0 = "7 0 600 0 0 7 180 0 0 0 1 0\n";
  write(dir / "calib.txt", "P0: 7 0 600 0 0 7 180 0 0 0 1\nP1: 7 0 600 -3 0 7 180 0 0 0 1 0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "calib.txt", 1, "expected 12 numbers");
  write(dir / "calib.txt", "P0: " + p0 + "P1: 7 0 600 nan 0 7 180 0 0 0 1 0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "calib.txt", 2, "finite");
  write(dir / "calib.txt", "P0: " + p0 + "P1: 7 0 600 3 0 7 180 0 0 0 1 0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "calib.txt", 0, "must be negative");
  write(dir / "calib.txt", p0 + "7 0 600 -3.5 0 7 180 0 0 0 1 0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "image_1" / "000001.png", 0, "missing");
  write(dir / "image_1" / "000001.png", "x");
  EXPECT_NEAR(read_kitti_stereo(dir.string()).calibration.baseline_m, 0.5, 1e-12);
  write(dir / "times.txt", "0.0\n0.1\n0.2\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "times.txt", 0, "expected one time per frame");
  write(dir / "times.txt", "0.0\n0.0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "times.txt", 2, "increase strictly");
  fs::remove(dir / "times.txt");
  write(dir / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  expect_error([&] { read_kitti_stereo(dir.string()); }, dir / "poses.txt", 0, "expected one pose per frame");
  fs::remove_all(dir);

  const fs::path tum = scratch("bad_tum");
  write(tum / "rgb.txt", "1.0 rgb/a.png\nabc rgb/b.png\n");
  write(tum / "depth.txt", "1.0 depth/a.png\n");
  expect_error([&] { read_tum_rgbd(tum.string()); }, tum / "rgb.txt", 2, "expected a timestamp");
  write(tum / "rgb.txt", std::string("1.0 rgb/a.png\n\x01\x02\x03 binary\n"));
  EXPECT_THROW(read_tum_rgbd(tum.string()), ParseError);
  write(tum / "rgb.txt", "");
  expect_error([&] { read_tum_rgbd(tum.string()); }, tum / "rgb.txt", 0, "no images listed");
  write(tum / "associations.txt", "1.0 rgb/a.png 1.0\n");
  expect_error([&] { read_tum_rgbd(tum.string()); }, tum / "associations.txt", 1, "expected \"rgb_time rgb_file depth_time depth_file\"");
  expect_error([&] { detect_image_layout((tum / "rgb").string()); }, tum / "rgb", 0, "not a folder");
  const fs::path empty = scratch("empty");
  expect_error([&] { detect_image_layout(empty.string()); }, empty, 0, "not a known image sequence");
  fs::remove_all(tum);
  fs::remove_all(empty);
}

// A plain folder: images in natural order, monocular or left/ + right/, times from times.txt,
// from the file names, or assumed; other image formats named, not silently skipped.
TEST(ImageSequence, ReadsPlainFoldersInNaturalOrder) {
  const fs::path mono = scratch("plain_mono");
  for (const char* name : {"frame_10.png", "frame_9.png", "frame_100.jpg", "notes.txt"}) write(mono / name, "x");
  EXPECT_EQ(detect_image_layout(mono.string()), "folder");
  ImageSequence seq = read_image_folder(mono.string());
  EXPECT_EQ(seq.kind, SequenceKind::kMonocular);
  EXPECT_EQ(seq.layout, "folder");
  ASSERT_EQ(seq.frames.size(), 3U);
  EXPECT_EQ(fs::path(seq.frames[0].image).filename(), "frame_9.png");
  EXPECT_EQ(fs::path(seq.frames[1].image).filename(), "frame_10.png");
  EXPECT_EQ(fs::path(seq.frames[2].image).filename(), "frame_100.jpg");
  EXPECT_FALSE(seq.times_from_file);  // frame numbers are not times
  EXPECT_DOUBLE_EQ(seq.frames[2].time.seconds(), 0.2);
  EXPECT_FALSE(seq.calibration_from_dataset);

  // Nanosecond names (EuRoC's) and seconds with a decimal point (TUM's) are times.
  const fs::path stamped = scratch("plain_stamped");
  write(stamped / "1403636579763555584.png", "x");
  write(stamped / "1403636579813555456.png", "x");
  seq = read_image_folder(stamped.string());
  ASSERT_EQ(seq.frames.size(), 2U);
  EXPECT_TRUE(seq.times_from_file);
  EXPECT_EQ(seq.frames[1].time.nanoseconds() - seq.frames[0].time.nanoseconds(), 49999872);
  const fs::path seconds = scratch("plain_seconds");
  write(seconds / "1305031102.175304.png", "x");
  write(seconds / "1305031102.211214.png", "x");
  seq = read_image_folder(seconds.string());
  EXPECT_TRUE(seq.times_from_file);
  EXPECT_NEAR(seq.frames[1].time.seconds() - seq.frames[0].time.seconds(), 0.03591, 1e-6);
  // times.txt wins, and must have one time per frame.
  write(seconds / "times.txt", "0.5\n0.25\n");
  expect_error([&] { read_image_folder(seconds.string()); }, seconds / "times.txt", 2, "times must increase strictly");
  write(seconds / "times.txt", "0.5\n");
  expect_error([&] { read_image_folder(seconds.string()); }, seconds / "times.txt", 0, "expected one time per frame");

  // Stereo: left/ and right/ paired by name.
  const fs::path stereo = scratch("plain_stereo");
  fs::create_directories(stereo / "left");
  fs::create_directories(stereo / "right");
  for (const char* name : {"2.png", "10.png"}) {
    write(stereo / "left" / name, "x");
    write(stereo / "right" / name, "x");
  }
  write(stereo / "right" / "11.png", "x");
  EXPECT_EQ(detect_image_layout(stereo.string()), "folder");
  seq = read_image_folder(stereo.string());
  EXPECT_EQ(seq.kind, SequenceKind::kStereo);
  ASSERT_EQ(seq.frames.size(), 2U);
  EXPECT_EQ(fs::path(seq.frames[0].image).filename(), "2.png");
  EXPECT_EQ(seq.frames[1].right_image, (stereo / "right" / "10.png").string());
  ASSERT_FALSE(seq.notes.empty());
  write(stereo / "left" / "12.png", "x");
  expect_error([&] { read_image_folder(stereo.string()); }, stereo / "right" / "12.png", 0, "every left image needs its right image");

  // Formats cairn does not decode are named.
  const fs::path pgm = scratch("plain_pgm");
  write(pgm / "a.pgm", "P5");
  write(pgm / "b.pgm", "P5");
  expect_error([&] { read_image_folder(pgm.string()); }, pgm, 0, "holds 2 .pgm images, which cairn does not read");
  for (const fs::path& dir : {mono, stamped, seconds, stereo, pgm}) fs::remove_all(dir);
}

}  // namespace
}  // namespace cairn::io
