// The point-cloud readers (io/point_cloud.hpp): synthetic PCD (ascii, binary, binary_compressed),
// PLY (ascii, binary) and KITTI .bin files written to a temporary folder, compressed files,
// every kind of bad input with its error, the KITTI ring/time recovery, and the real scans of
// ../shared/data/lidar3d with the facts their SOURCE.txt states.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "cairn/io/compressed_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "../test_data.hpp"

namespace cairn::io {
namespace {

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

/// LZF with literal runs only (1..32 bytes, each behind a control byte L-1): valid LZF that any
/// decoder must accept, written independently of the reader.
std::string lzf_literals(const std::string& data) {
  std::string out;
  for (std::size_t i = 0; i < data.size(); i += 32) {
    const std::size_t n = std::min<std::size_t>(32, data.size() - i);
    out += static_cast<char>(n - 1);
    out.append(data, i, n);
  }
  return out;
}

std::string pcd_header(const std::string& fields, const std::string& sizes, const std::string& types,
                       const std::string& counts, std::size_t points, const std::string& data) {
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " + fields + "\nSIZE " + sizes +
                       "\nTYPE " + types + "\n";
  if (!counts.empty()) header += "COUNT " + counts + "\n";
  header += "WIDTH " + std::to_string(points) + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " +
            std::to_string(points) + "\nDATA " + data + "\n";
  return header;
}

/// A PCD header of float x y z (12 bytes per point).
std::string xyz_header(std::size_t points, const std::string& data) {
  return pcd_header("x y z", "4 4 4", "F F F", "1 1 1", points, data);
}

std::string xyz_records(const std::vector<std::array<float, 3>>& points) {
  std::string out;
  for (const auto& p : points) {
    for (const float v : p) put(out, v);
  }
  return out;
}

// small.pcd (an ascii PCD: 2 points x y z intensity = (1.5, -2, 0.25, 7), (3, 4, 5, 255))
// compressed with `xz -9` (XZ Utils 5.4.1).
const unsigned char kSmallPcdXz[] = {
    0xfd, 0x37, 0x7a, 0x58, 0x5a, 0x00, 0x00, 0x04, 0xe6, 0xd6, 0xb4, 0x46, 0x02, 0x00, 0x21, 0x01, 0x1c, 0x00, 0x00,
    0x00, 0x10, 0xcf, 0x58, 0xcc, 0xe0, 0x00, 0xca, 0x00, 0xa9, 0x5d, 0x00, 0x11, 0x88, 0x02, 0x21, 0xf2, 0x47, 0x16,
    0x49, 0xa8, 0x72, 0x97, 0xc0, 0x16, 0x90, 0xb7, 0x2e, 0x09, 0x73, 0xb9, 0x20, 0x03, 0x1a, 0x32, 0x2b, 0x89, 0xd8,
    0xf2, 0xea, 0xfd, 0x7e, 0xd1, 0x8e, 0x4e, 0x03, 0x07, 0x42, 0x31, 0x77, 0xb1, 0x20, 0xea, 0x7c, 0xd1, 0x9f, 0xe9,
    0xed, 0x78, 0xe0, 0x59, 0xa5, 0x38, 0xe3, 0xeb, 0xb6, 0x25, 0x66, 0xcd, 0x84, 0xd9, 0x69, 0xc5, 0xac, 0x38, 0xfb,
    0x14, 0xe1, 0xb0, 0xc6, 0x48, 0xbc, 0x1f, 0xf4, 0x63, 0x03, 0xab, 0xbc, 0x0d, 0x88, 0x10, 0xa6, 0xb9, 0x61, 0x2c,
    0x4d, 0xed, 0x40, 0x21, 0x7e, 0xbd, 0xe4, 0x9b, 0xca, 0x27, 0xe4, 0x1e, 0x6f, 0x1f, 0xba, 0xce, 0x64, 0x98, 0xd0,
    0x31, 0xd1, 0x93, 0x1f, 0x0f, 0x3d, 0x39, 0xe4, 0x46, 0xbb, 0x59, 0x60, 0x78, 0xbe, 0x03, 0x2c, 0x2f, 0x28, 0x14,
    0xfd, 0xcf, 0x03, 0x14, 0x57, 0x75, 0xb7, 0x7f, 0xbf, 0x00, 0x32, 0x1d, 0x33, 0x1c, 0xfe, 0xd0, 0x77, 0xdc, 0xe5,
    0x63, 0xd0, 0x59, 0xd9, 0xd2, 0x68, 0x01, 0x2e, 0x01, 0x74, 0x28, 0x59, 0x95, 0x58, 0x54, 0x5e, 0x13, 0xb5, 0x71,
    0x6f, 0x69, 0x37, 0x5c, 0x2f, 0xef, 0xb6, 0x90, 0x45, 0x6c, 0x00, 0x00, 0x00, 0x00, 0x12, 0x03, 0xb1, 0xc2, 0xe2,
    0x63, 0x5f, 0xce, 0x00, 0x01, 0xc5, 0x01, 0xcb, 0x01, 0x00, 0x00, 0x5a, 0x71, 0x9e, 0x1f, 0xb1, 0xc4, 0x67, 0xfb,
    0x02, 0x00, 0x00, 0x00, 0x00, 0x04, 0x59, 0x5a};

// A 2-point KITTI scan, float32 (1.5, -2, 0.25, 0.5), (3, 4, 5, 0.75), compressed with `gzip -9n`.
const unsigned char kSmallBinGz[] = {0x1f, 0x8b, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x03, 0x63, 0x60,
                                     0x38, 0x60, 0xcf, 0xc0, 0xc0, 0x70, 0x80, 0x81, 0xa1, 0xc1, 0x0e, 0x48,
                                     0x03, 0xd9, 0x0e, 0x0e, 0x40, 0x36, 0x10, 0x2f, 0x00, 0x62, 0x07, 0x7b,
                                     0x00, 0xb7, 0x1d, 0xf0, 0x56, 0x20, 0x00, 0x00, 0x00};

class PointCloudTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::temp_directory_path() /
           ("cairn_test_point_cloud_" + std::to_string(::getpid()) + "_" + info->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }

  std::string write(const std::string& name, const std::string& bytes) const {
    const std::string path = (dir_ / name).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    return path;
  }
  std::string write(const std::string& name, const unsigned char* bytes, std::size_t size) const {
    return write(name, std::string(reinterpret_cast<const char*>(bytes), size));
  }

  std::filesystem::path dir_;
};

/// Reads `path` expecting a ParseError at `line` whose message holds every one of `parts`.
void expect_error(const std::string& path, std::size_t line, const std::vector<std::string>& parts) {
  try {
    const PointCloud cloud = read_point_cloud(path);
    ADD_FAILURE() << path << ": expected an error, read " << cloud.size() << " points";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.file(), path);
    for (const std::string& part : parts)
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << "'" << part << "' not in: " << e.what();
  }
}

// --- PCD ----------------------------------------------------------------------------------------

TEST_F(PointCloudTest, PcdAsciiReadsEveryAttributeSkipsOtherFieldsAndDropsNaNPoints) {
  const std::string path = write("a.pcd", pcd_header("x y z intensity ring time normal _", "4 4 4 4 2 4 4 1",
                                                     "F F F F U F F U", "1 1 1 1 1 1 3 2", 3, "ascii") +
                                              "1.5 -2 0.25 7 3 0.05 0 0 1 0 0\n"
                                              "nan nan nan 0 0 0 0 0 1 0 0\r\n"
                                              "\n"
                                              "-10 20.5 -1.75 255 63 0.099 1 0 0 9 9\n");
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(report.dropped_non_finite, 1u);
  EXPECT_EQ(report.trailing_bytes, 0u);
  EXPECT_EQ(report.format, "pcd ascii");
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.5F, -2.0F, 0.25F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(-10.0F, 20.5F, -1.75F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{7.0F, 255.0F}));
  EXPECT_EQ(cloud.ring, (std::vector<std::uint16_t>{3, 63}));
  EXPECT_EQ(cloud.time_s, (std::vector<float>{0.05F, 0.099F}));
}

TEST_F(PointCloudTest, PcdWithoutCountLineAndWithFieldINamesTheIntensity) {
  const std::string path = write("no_count.pcd",
                                 "VERSION .7\nFIELDS x y z i\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 1\nHEIGHT 1\n"
                                 "POINTS 1\nDATA ascii\n1 2 3 0.5");
  const PointCloud cloud = read_point_cloud(path);
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.0F, 2.0F, 3.0F));
  EXPECT_EQ(cloud.intensity, std::vector<float>{0.5F});
  EXPECT_TRUE(cloud.ring.empty());
  EXPECT_TRUE(cloud.time_s.empty());
}

TEST_F(PointCloudTest, PcdBinaryReadsEveryScalarTypeAndOusterNanosecondTimes) {
  // x F8, y F4, z I2, intensity U1, t U4 (Ouster: nanoseconds), 3 padding bytes, ring I1.
  std::string data;
  put(data, 1.25);
  put(data, -3.5F);
  put(data, std::int16_t{-2});
  put(data, std::uint8_t{200});
  put(data, std::uint32_t{50'000'000});
  data += "abc";
  put(data, std::int8_t{5});
  put(data, 1000.0);
  put(data, 0.125F);
  put(data, std::int16_t{7});
  put(data, std::uint8_t{0});
  put(data, std::uint32_t{99'000'000});
  data += "def";
  put(data, std::int8_t{127});
  const std::string path = write(
      "b.pcd",
      pcd_header("x y z intensity t _ ring", "8 4 2 1 4 1 1", "F F I U U U I", "1 1 1 1 1 3 1", 2, "binary") + data);
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  EXPECT_EQ(report.format, "pcd binary");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.25F, -3.5F, -2.0F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(1000.0F, 0.125F, 7.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{200.0F, 0.0F}));
  ASSERT_EQ(cloud.time_s.size(), 2u);
  EXPECT_FLOAT_EQ(cloud.time_s[0], 0.05F);
  EXPECT_FLOAT_EQ(cloud.time_s[1], 0.099F);
  EXPECT_EQ(cloud.ring, (std::vector<std::uint16_t>{5, 127}));
}

TEST_F(PointCloudTest, PcdBinaryIgnoresAndCountsPaddingAfterThePoints) {
  // PCL's writer pads binary files; the KITTI key frames carry 3,922 zero bytes.
  const std::string records = xyz_records({{1, 2, 3}, {4, 5, 6}, {7, 8, 9}});
  const std::string path = write("padded.pcd", xyz_header(3, "binary") + records + std::string(3922, '\0'));
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(report.trailing_bytes, 3922u);
  EXPECT_EQ(cloud.points[2], Eigen::Vector3f(7.0F, 8.0F, 9.0F));
}

TEST_F(PointCloudTest, PcdBinaryDropsAndCountsNonFinitePointsKeepingTheOrder) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const std::string path = write(
      "nan.pcd", xyz_header(5, "binary") + xyz_records({{1, 1, 1}, {nan, 2, 2}, {3, 3, 3}, {4, 4, -inf}, {5, 5, 5}}));
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  EXPECT_EQ(report.dropped_non_finite, 2u);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.points[0].x(), 1.0F);
  EXPECT_EQ(cloud.points[1].x(), 3.0F);
  EXPECT_EQ(cloud.points[2].x(), 5.0F);
}

TEST_F(PointCloudTest, PcdBinaryTruncatedOrWithHugeCountsIsRefusedBeforeAllocating) {
  const std::string records = xyz_records({{1, 2, 3}, {4, 5, 6}});
  expect_error(write("short.pcd", xyz_header(2, "binary") + records.substr(0, 23)), 0,
               {"truncated", "2 points of 12 bytes", "only 23 bytes"});
  expect_error(write("huge.pcd", xyz_header(1'000'000'000'000'000, "binary") + records), 0,
               {"truncated", "1000000000000000 points"});
  expect_error(write("nodata.pcd", xyz_header(1, "binary").substr(0, xyz_header(1, "binary").size() - 1)), 0,
               {"truncated", "only 0 bytes"});
}

TEST_F(PointCloudTest, PcdBinaryCompressedReadsColumnsFromLiteralLzf) {
  // Fields are stored column by column: x0 x1 x2, y0 y1 y2, z0.., intensity0..
  std::string columns;
  for (const float v : {1.0F, 2.0F, 3.0F, -1.0F, -2.0F, -3.0F, 0.5F, 0.25F, 0.125F, 10.0F, 20.0F, 30.0F})
    put(columns, v);
  const std::string compressed = lzf_literals(columns);
  std::string block;
  put(block, static_cast<std::uint32_t>(compressed.size()));
  put(block, static_cast<std::uint32_t>(columns.size()));
  block += compressed;
  const std::string path =
      write("c.pcd", pcd_header("x y z intensity", "4 4 4 4", "F F F F", "1 1 1 1", 3, "binary_compressed") + block);
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  EXPECT_EQ(report.format, "pcd binary_compressed");
  EXPECT_EQ(report.trailing_bytes, 0u);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.0F, -1.0F, 0.5F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(2.0F, -2.0F, 0.25F));
  EXPECT_EQ(cloud.points[2], Eigen::Vector3f(3.0F, -3.0F, 0.125F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{10.0F, 20.0F, 30.0F}));
}

/// A binary_compressed PCD of 2 points x y z with the given LZF block and announced sizes.
std::string compressed_pcd(const std::string& lzf, std::uint32_t compressed_size, std::uint32_t uncompressed_size,
                           std::size_t points = 2) {
  std::string out = xyz_header(points, "binary_compressed");
  put(out, compressed_size);
  put(out, uncompressed_size);
  return out + lzf;
}

TEST_F(PointCloudTest, PcdBinaryCompressedFollowsShortAndLongBackReferences) {
  // 24 bytes = six times 1.0f (00 00 80 3f): a literal run of 4 bytes, a short back reference
  // (110 00000, 3: length 6 + 2 = 8, from 4 bytes back) and a long one (111 00000, 3, 3: length
  // 7 + 3 + 2 = 12, from 4 bytes back), both copying over their own output.
  const std::string lzf("\x03\x00\x00\x80\x3f\xc0\x03\xe0\x03\x03", 10);
  const PointCloud cloud = read_point_cloud(write("backref.pcd", compressed_pcd(lzf, 10, 24)));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.0F, 1.0F, 1.0F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(1.0F, 1.0F, 1.0F));
}

TEST_F(PointCloudTest, PcdBinaryCompressedCorruptBlocksAreRefused) {
  std::string columns;
  for (int i = 0; i < 6; ++i) put(columns, static_cast<float>(i));
  const std::string good = lzf_literals(columns);
  expect_error(write("before_start.pcd", compressed_pcd(std::string("\xe0\x03\x03", 3), 3, 24)), 0,
               {"before the start"});
  expect_error(write("short_output.pcd", compressed_pcd(lzf_literals(columns.substr(0, 12)), 13, 24)), 0,
               {"decompresses to 12 bytes, expected 24"});
  expect_error(write("long_output.pcd", compressed_pcd(lzf_literals(columns + "abcd"), 29, 24)), 0,
               {"writes past the 24 bytes"});
  expect_error(write("cut_literal.pcd", compressed_pcd(good.substr(0, 10), 10, 24)), 0, {"runs past the end"});
  expect_error(write("wrong_size.pcd", compressed_pcd(good, static_cast<std::uint32_t>(good.size()), 36)), 0,
               {"holds 36 bytes uncompressed", "2 points of 12 bytes"});
  expect_error(write("block_too_big.pcd", compressed_pcd(good, 1000, 24)), 0, {"truncated", "1000 compressed bytes"});
  expect_error(write("ratio.pcd", compressed_pcd(good, static_cast<std::uint32_t>(good.size()), 12000, 1000)), 0,
               {"cannot expand more than 88 times"});
  expect_error(write("no_sizes.pcd", xyz_header(2, "binary_compressed") + "abc"), 0, {"truncated", "8 bytes of sizes"});
}

TEST_F(PointCloudTest, PcdHeaderErrorsNameTheLineAndWhatWasExpected) {
  struct Case {
    const char* name;
    std::string text;
    std::size_t line;
    std::string expected;
  };
  const std::string v = "VERSION 0.7\n";
  const std::string xyz = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  const std::string size = "WIDTH 1\nHEIGHT 1\nPOINTS 1\n";
  const std::string ascii = "DATA ascii\n1 2 3\n";
  const std::vector<Case> cases = {
      {"keyword", v + xyz + "COLOUR red\n" + size + ascii, 5, "unknown PCD header keyword 'COLOUR'"},
      {"version", "VERSION 0.6\n" + xyz + size + ascii, 1, "PCD version '0.6' is not supported: expected 0.7"},
      {"sizes", v + "FIELDS x y z\nSIZE 4 4\nTYPE F F F\n" + size + ascii, 3,
       "SIZE has 2 values, FIELDS (line 2) names 3"},
      {"type", v + "FIELDS x y z\nSIZE 4 2 4\nTYPE F F F\n" + size + ascii, 4, "field 'y' has TYPE 'F' and SIZE '2'"},
      {"u8", v + "FIELDS x y z\nSIZE 4 4 8\nTYPE F F U\n" + size + ascii, 4,
       "expected F4, F8, U1, U2, U4, I1, I2 or I4"},
      {"points", v + xyz + "WIDTH 2\nHEIGHT 1\nPOINTS 1\n" + ascii, 7, "POINTS 1 differs from WIDTH * HEIGHT = 2 * 1"},
      {"data", v + xyz + size + "DATA binary_lz4\n", 8, "expected ascii, binary or binary_compressed"},
      {"no_z", v + "FIELDS x y intensity\nSIZE 4 4 4\nTYPE F F F\n" + size + ascii, 2,
       "no field 'z': expected fields x, y and z"},
      {"ring_float", v + "FIELDS x y z ring\nSIZE 4 4 4 4\nTYPE F F F F\n" + size + "DATA ascii\n1 2 3 4\n", 4,
       "field 'ring' has TYPE F: expected an integer type"},
      {"two_intensities",
       v + "FIELDS x y z intensity i\nSIZE 4 4 4 4 4\nTYPE F F F F F\n" + size + "DATA ascii\n1 2 3 4 5\n", 2,
       "fields 'intensity' and 'i' both give the intensity"},
      {"same_field", v + "FIELDS x y z x\nSIZE 4 4 4 4\nTYPE F F F F\n" + size + "DATA ascii\n1 2 3 4\n", 2,
       "field 'x' appears twice"},
      {"second_width", v + xyz + "WIDTH 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\n" + ascii, 6,
       "second WIDTH line (the first is line 5)"},
      {"count_x", v + xyz + "COUNT 2 1 1\n" + size + "DATA ascii\n1 1 2 3\n", 5, "field 'x' has COUNT 2: expected 1"},
      {"count_zero", v + xyz + "COUNT 1 0 1\n" + size + ascii, 5, "field 'y' has COUNT '0'"},
      {"no_data", v + xyz + size, 7,
       "file ends inside the PCD header: expected a 'DATA ascii|binary|binary_compressed' line"},
      {"no_points", v + xyz + "WIDTH 1\nHEIGHT 1\n" + ascii, 7, "no POINTS line before DATA"},
      {"no_version", "# .PCD v0.7\n" + xyz + size + ascii, 8, "no VERSION line before DATA"},
      {"viewpoint", v + xyz + size + "VIEWPOINT 0 0 0 1 0 0\n" + ascii, 8, "VIEWPOINT expects 7 numbers"},
      {"viewpoint_nan", v + xyz + size + "VIEWPOINT 0 0 nan 1 0 0 0\n" + ascii, 8,
       "expected a finite number in VIEWPOINT, found 'nan'"},
      {"negative_width", v + xyz + "WIDTH -1\nHEIGHT 1\nPOINTS 1\n" + ascii, 5,
       "expected a non-negative integer for WIDTH, found '-1'"},
      {"binary_header", v + "FIELDS x y\x01 z\n", 2, "binary data (byte 0x01) in the header"},
      {"empty_value", v + xyz + "WIDTH\n", 5, "WIDTH without a value"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    expect_error(write(std::string(c.name) + ".pcd", c.text), c.line, {c.expected});
  }
}

TEST_F(PointCloudTest, PcdAsciiDataErrorsNameTheLine) {
  const std::string header = xyz_header(2, "ascii");  // 11 lines
  expect_error(write("count.pcd", header + "1 2 3\n1 2222222\n"), 13, {"point 1 has 2 values: expected 3"});
  expect_error(write("word.pcd", header + "1 2 3\n1 two 3\n"), 13,
               {"expected a number for field 'y' of point 1, found 'two'"});
  expect_error(write("extra.pcd", header + "1 2 3\n4 5 6\n7 8 9\n"), 14, {"unexpected data after the 2 points"});
  expect_error(write("short.pcd", header + "111111 2 3\n"), 12, {"file ends after 1 of the 2 points", "truncated"});
  expect_error(write("binary.pcd", header + "1 2 3\n4 5 \x02\n"), 13, {"binary data (byte 0x02) in the ASCII data"});
  expect_error(write("huge.pcd", xyz_header(1'000'000'000'000, "ascii") + "1 2 3\n"), 11,
               {"more than the 6 bytes after the DATA line can hold"});
  expect_error(write("cut.pcd", header + "1 2 3\n1 2\n"), 11,
               {"2 points of 12 bytes (3 values each), more than the 10 bytes"});
  const std::string with_ring = pcd_header("x y z ring", "4 4 4 2", "F F F I", "", 1, "ascii");
  expect_error(write("ring.pcd", with_ring + "1 2 3 -1\n"), 11,
               {"point 0: ring -1", "expected an integer in 0..65535"});
  const std::string with_intensity = pcd_header("x y z intensity", "4 4 4 4", "F F F F", "", 1, "ascii");
  expect_error(write("intensity.pcd", with_intensity + "1 2 3 nan\n"), 11, {"intensity nan of a valid point"});
}

// --- PLY ----------------------------------------------------------------------------------------

const std::string kPlyAsciiHeader =
    "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 3\nproperty float x\nproperty float y\nproperty float "
    "z\n"
    "property uchar intensity\nproperty float nx\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

TEST_F(PointCloudTest, PlyAsciiReadsVerticesAndSkipsFaces) {
  const std::string path = write("a.ply", kPlyAsciiHeader + "1 2 3 10 0\nnan 0 0 0 0\n-4.5 5.25 -6 255 1\n3 0 1 2\n");
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(path, &report);
  EXPECT_EQ(report.format, "ply ascii");
  EXPECT_EQ(report.dropped_non_finite, 1u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.0F, 2.0F, 3.0F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(-4.5F, 5.25F, -6.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{10.0F, 255.0F}));
}

TEST_F(PointCloudTest, PlyBinaryReadsDoublesRingsSkipsOtherElementsAndCountsTrailingBytes) {
  const std::string header =
      "ply\r\nformat binary_little_endian 1.0\r\nelement camera 1\r\nproperty float focal\r\nelement vertex 2\r\n"
      "property double x\r\nproperty double y\r\nproperty double z\r\nproperty uchar scalar_intensity\r\n"
      "property ushort ring\r\nproperty float curvature\r\nelement face 2\r\nproperty list uchar int vertex_indices\r\n"
      "end_header\r\n";
  std::string data;
  put(data, 500.0F);  // camera
  put(data, 0.1);
  put(data, -0.2);
  put(data, 0.3);
  put(data, std::uint8_t{17});
  put(data, std::uint16_t{2});
  put(data, 9.0F);
  put(data, 100.0);
  put(data, 200.0);
  put(data, -300.0);
  put(data, std::uint8_t{255});
  put(data, std::uint16_t{60000});
  put(data, 9.0F);
  put(data, std::uint8_t{3});  // face 0: 3 indices
  for (const std::int32_t i : {0, 1, 0}) put(data, i);
  put(data, std::uint8_t{0});  // face 1: empty
  data += "tail!";
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(write("b.ply", header + data), &report);
  EXPECT_EQ(report.format, "ply binary_little_endian");
  EXPECT_EQ(report.trailing_bytes, 5u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(0.1F, -0.2F, 0.3F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(100.0F, 200.0F, -300.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{17.0F, 255.0F}));
  EXPECT_EQ(cloud.ring, (std::vector<std::uint16_t>{2, 60000}));
}

TEST_F(PointCloudTest, PlyErrorsNameTheLineAndWhatWasExpected) {
  const std::string start = "ply\nformat ascii 1.0\nelement vertex 1\n";
  const std::string xyz = "property float x\nproperty float y\nproperty float z\n";
  expect_error(write("big.ply", "ply\nformat binary_big_endian 1.0\n" + xyz), 2,
               {"binary_big_endian is not supported"});
  expect_error(write("format.ply", "ply\nformat ascii 2.0\n"), 2, {"expected 'format ascii|binary_little_endian 1.0'"});
  expect_error(write("list.ply", start + "property list uchar int idx\n"), 4,
               {"list property 'idx' in element vertex is not supported"});
  expect_error(write("no_end.ply", start + xyz), 6, {"file ends inside the PLY header: expected 'end_header'"});
  expect_error(write("early.ply", "ply\nformat ascii 1.0\nproperty float x\n"), 3, {"property before any element"});
  expect_error(write("type.ply", start + "property float128 x\n"), 4, {"unknown property type 'float128'"});
  expect_error(write("keyword.ply", start + xyz + "colour red\nend_header\n"), 7,
               {"unknown PLY header keyword 'colour'"});
  expect_error(write("no_y.ply", start + "property float x\nproperty float z\nend_header\n1 2\n"), 3, {"no field 'y'"});
  expect_error(write("no_format.ply", "ply\nelement vertex 1\n" + xyz + "end_header\n1 2 3\n"), 6,
               {"no 'format' line"});
  expect_error(write("no_vertex.ply", "ply\nformat ascii 1.0\nelement point 1\n" + xyz + "end_header\n1 2 3\n"), 7,
               {"no 'element vertex'"});
  expect_error(write("huge.ply", "ply\nformat ascii 1.0\nelement vertex 1000000000000\n" + xyz + "end_header\n1 2 3\n"),
               3, {"announces 1000000000000 entries, more than the 6 bytes after end_header can hold"});
  expect_error(write("extra.ply", start + xyz + "end_header\n1 2 3\n4\n"), 9,
               {"unexpected data after the last element: '4'"});
  expect_error(write("short.ply", start + xyz + "end_header\n1 22222\n"), 8,
               {"file ends in vertex 0 of 1: expected property 'z'"});
  expect_error(write("word.ply", start + xyz + "end_header\n1\n2 zz\n"), 9,
               {"expected a number for property 'z' of vertex 0, found 'zz'"});
  const std::string binary = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n" + xyz + "end_header\n";
  expect_error(write("cut.ply", binary + std::string(23, '\0')), 0,
               {"truncated binary data: vertex 1 of 2 needs 12 bytes at byte offset"});
  const std::string faces = "ply\nformat binary_little_endian 1.0\nelement vertex 0\n" + xyz +
                            "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
  expect_error(write("cut_list.ply", faces + "\x03" + std::string(8, '\0')), 0,
               {"list 'vertex_indices' of face 0", "has 3 items"});
}

// --- KITTI .bin ---------------------------------------------------------------------------------

TEST_F(PointCloudTest, KittiBinReadsIntensityAndDropsNaN) {
  std::string data;
  for (const float v :
       {1.0F, 2.0F, 3.0F, 0.5F, std::numeric_limits<float>::quiet_NaN(), 0.0F, 0.0F, 0.0F, 4.0F, 5.0F, 6.0F, 0.25F}) {
    put(data, v);
  }
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(write("000000.bin", data), &report);
  EXPECT_EQ(report.format, "kitti bin");
  EXPECT_EQ(report.dropped_non_finite, 1u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(4.0F, 5.0F, 6.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{0.5F, 0.25F}));
}

TEST_F(PointCloudTest, KittiBinOfTheWrongSizeOrEmptyIsRefused) {
  expect_error(write("odd.bin", std::string(33, '\0')), 0, {"KITTI .bin file of 33 bytes: expected a multiple of 16"});
  expect_error(write("empty.bin", ""), 0, {"file is empty"});
}

TEST_F(PointCloudTest, GzipCompressedKittiBinIsRecognisedThroughItsName) {
  const PointCloud cloud = read_point_cloud(write("000001.BIN.gz", kSmallBinGz, sizeof kSmallBinGz));
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.5F, -2.0F, 0.25F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(3.0F, 4.0F, 5.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{0.5F, 0.75F}));
}

TEST_F(PointCloudTest, UnknownFormatsAndEmptyFilesAreRefused) {
  expect_error(write("empty.pcd", ""), 0, {"file is empty: expected a point cloud"});
  expect_error(write("garbage.pcd", std::string("\x01\x02hello\xff", 8)), 0,
               {"unknown point-cloud format", "'\\x01\\x02hello\\xff'"});
  expect_error(write("scan.xyz", "1 2 3\n"), 0, {"unknown point-cloud format"});
}

// --- xz -----------------------------------------------------------------------------------------

TEST_F(PointCloudTest, XzCompressedPcdIsDecompressedByItsMagicBytes) {
  PointCloudReadReport report;
  const PointCloud cloud = read_point_cloud(write("small.pcd.xz", kSmallPcdXz, sizeof kSmallPcdXz), &report);
  EXPECT_EQ(report.format, "pcd ascii");
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points[0], Eigen::Vector3f(1.5F, -2.0F, 0.25F));
  EXPECT_EQ(cloud.points[1], Eigen::Vector3f(3.0F, 4.0F, 5.0F));
  EXPECT_EQ(cloud.intensity, (std::vector<float>{7.0F, 255.0F}));
}

TEST_F(PointCloudTest, TruncatedCorruptOrOversizedXzIsRefused) {
  expect_error(write("cut.pcd.xz", kSmallPcdXz, 120), 0, {"xz data is truncated"});
  std::string corrupt(reinterpret_cast<const char*>(kSmallPcdXz), sizeof kSmallPcdXz);
  corrupt[60] = static_cast<char>(corrupt[60] ^ 0x55);
  expect_error(write("corrupt.pcd.xz", corrupt), 0, {"xz data is corrupt"});
  const std::string garbage_after =
      std::string(reinterpret_cast<const char*>(kSmallPcdXz), sizeof kSmallPcdXz) + "this is not xz data";
  expect_error(write("junk.pcd.xz", garbage_after), 0, {"xz data is corrupt"});
  const std::string path = write("small.pcd.xz", kSmallPcdXz, sizeof kSmallPcdXz);
  try {
    read_maybe_compressed(path, 100);
    ADD_FAILURE() << "expected the 100-byte limit to be enforced";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("decompressed data exceeds 100 bytes"), std::string::npos) << e.what();
  }
}

// --- KITTI ring and time recovery ---------------------------------------------------------------

Eigen::Vector3f at(double azimuth, double elevation_deg, double range = 10.0) {
  const double elevation = elevation_deg * std::numbers::pi / 180.0;
  return Eigen::Vector3d(range * std::cos(elevation) * std::cos(azimuth),
                         range * std::cos(elevation) * std::sin(azimuth), range * std::sin(elevation))
      .cast<float>();
}

TEST(KittiRingAndTime, RingsChangeAtTheFrontNotAtTheWrapBehindTheCar) {
  constexpr double pi = std::numbers::pi;
  // KITTI order: each ring from just left of straight ahead, counter-clockwise round the back
  // (where atan2 jumps from +pi to -pi) to just right of straight ahead. The second ring has
  // jitter at the wrap (+pi, -pi, +pi, -pi): still one ring.
  const std::vector<std::vector<double>> rings = {
      {0.0, pi / 4, pi / 2, 3 * pi / 4, pi - 1e-3, -pi + 1e-3, -pi / 2, -1e-3},
      {0.01, pi / 2, pi - 1e-3, -pi + 1e-3, pi - 2e-3, -pi + 2e-3, -pi / 2, -0.02},
      {0.02, pi / 2, pi - 0.1, -pi + 0.1, -pi / 2, -0.01},
  };
  PointCloud cloud;
  std::vector<std::uint16_t> expected_ring;
  for (std::size_t r = 0; r < rings.size(); ++r) {
    for (const double azimuth : rings[r]) {
      cloud.points.push_back(at(azimuth, 2.0 - static_cast<double>(r)));
      expected_ring.push_back(static_cast<std::uint16_t>(r));
    }
  }
  recover_kitti_ring_and_time(cloud);
  EXPECT_EQ(cloud.ring, expected_ring);
  ASSERT_EQ(cloud.time_s.size(), cloud.points.size());
  // Sweep from behind the car (0 s) through the left (period/4) to straight ahead (period/2)
  // and the right (3 period/4): KITTI raw devkit, KISS-ICP's KITTI time stamps.
  EXPECT_NEAR(static_cast<double>(cloud.time_s[0]), 0.05, 1e-6);   // azimuth 0
  EXPECT_NEAR(static_cast<double>(cloud.time_s[2]), 0.025, 1e-6);  // +pi/2
  EXPECT_NEAR(static_cast<double>(cloud.time_s[6]), 0.075, 1e-6);  // -pi/2
  EXPECT_NEAR(static_cast<double>(cloud.time_s[4]), 0.0, 1e-4);    // just left of behind
  EXPECT_NEAR(static_cast<double>(cloud.time_s[5]), 0.1, 1e-4);    // just right of behind
  recover_kitti_ring_and_time(cloud, 0.2);
  EXPECT_NEAR(static_cast<double>(cloud.time_s[2]), 0.05, 1e-6);
}

TEST(KittiRingAndTime, EmptyCloudGivesEmptyAttributes) {
  PointCloud cloud;
  recover_kitti_ring_and_time(cloud);
  EXPECT_TRUE(cloud.ring.empty());
  EXPECT_TRUE(cloud.time_s.empty());
}

// --- Real data ----------------------------------------------------------------------------------

double median(std::vector<double> values) {
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

TEST(PointCloudRealData, KittiKeyFramesHoldWhatTheirSourceFileStates) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes/key_frames/key_frame_0.pcd.xz");
  for (const int k : {0, 1, 109}) {
    const std::string path =
        cairn::test::data_path("lidar3d/kitti00_keyframes/key_frames/key_frame_" + std::to_string(k) + ".pcd.xz")
            .string();
    SCOPED_TRACE(path);
    // The decompressed bytes, read apart from the PCD parser: POINTS from the header text, the
    // data right after "DATA binary\n", then 3,922 zero bytes (SOURCE.txt, "TRAP").
    const std::string raw = read_maybe_compressed(path);
    const std::size_t data_at = raw.find("DATA binary\n");
    ASSERT_NE(data_at, std::string::npos);
    const std::size_t data_offset = data_at + 12;
    const std::size_t points_at = raw.find("\nPOINTS ");
    ASSERT_LT(points_at, data_at);
    const std::size_t points = std::stoul(raw.substr(points_at + 8, 12));
    EXPECT_GE(points, 111'881u);
    EXPECT_LE(points, 126'327u);
    ASSERT_EQ(raw.size(), data_offset + 12 * points + 3922);
    EXPECT_TRUE(std::all_of(raw.begin() + static_cast<std::ptrdiff_t>(data_offset + 12 * points), raw.end(),
                            [](char c) { return c == '\0'; }));

    PointCloudReadReport report;
    PointCloud cloud = read_point_cloud(path, &report);
    EXPECT_EQ(report.format, "pcd binary");
    EXPECT_EQ(report.trailing_bytes, 3922u);
    EXPECT_EQ(report.dropped_non_finite, 0u);  // "no NaN"
    ASSERT_EQ(cloud.size(), points);
    EXPECT_TRUE(cloud.intensity.empty());  // "No intensity, no ring, no per-point time field"
    EXPECT_TRUE(cloud.ring.empty());
    EXPECT_TRUE(cloud.time_s.empty());
    for (const std::size_t i : {std::size_t{0}, points / 2, points - 1}) {
      float xyz[3];
      std::memcpy(xyz, raw.data() + data_offset + 12 * i, 12);
      EXPECT_EQ(cloud.points[i], Eigen::Vector3f(xyz[0], xyz[1], xyz[2])) << "point " << i;
    }
    float min_range = std::numeric_limits<float>::max();
    float max_range = 0.0F;
    for (const Eigen::Vector3f& p : cloud.points) {
      min_range = std::min(min_range, p.norm());
      max_range = std::max(max_range, p.norm());
    }
    EXPECT_GE(min_range, 1.45F);  // "range 1.46..80.0 m"
    EXPECT_LE(max_range, 80.01F);

    // "64 laser rings one after another (highest elevation first)".
    recover_kitti_ring_and_time(cloud);
    ASSERT_EQ(cloud.ring.size(), points);
    EXPECT_EQ(cloud.ring.front(), 0);
    EXPECT_EQ(cloud.ring.back(), 63);
    EXPECT_TRUE(std::is_sorted(cloud.ring.begin(), cloud.ring.end()));
    std::vector<std::vector<double>> elevation(64);
    std::vector<std::vector<double>> z(64);
    for (std::size_t i = 0; i < points; ++i) {
      const Eigen::Vector3d p = cloud.points[i].cast<double>();
      z[cloud.ring[i]].push_back(p.z());
      if (p.x() > 0.0) elevation[cloud.ring[i]].push_back(std::atan2(p.z(), p.head<2>().norm()));
    }
    std::vector<double> median_elevation;
    for (int r = 0; r < 64; ++r) {
      ASSERT_GT(z[r].size(), 500u) << "ring " << r;
      ASSERT_FALSE(elevation[r].empty()) << "ring " << r;  // about 2,000 points per full ring
      median_elevation.push_back(median(elevation[r]));
    }
    for (int r = 1; r < 64; ++r) EXPECT_LT(median_elevation[r], median_elevation[r - 1]) << "ring " << r;
    // HDL-64E: +2 deg .. -24.8 deg; the lowest ring sees the road ~1.73 m below the sensor.
    EXPECT_NEAR(median_elevation.front() * 180.0 / std::numbers::pi, 2.0, 1.5);
    EXPECT_NEAR(median_elevation.back() * 180.0 / std::numbers::pi, -24.0, 1.5);
    EXPECT_NEAR(median(z[63]), -1.73, 0.3);
    const auto [t_min, t_max] = std::minmax_element(cloud.time_s.begin(), cloud.time_s.end());
    EXPECT_GE(*t_min, 0.0F);
    EXPECT_LE(*t_max, 0.1F);
  }
}

TEST(PointCloudRealData, SmallGicpPairHoldsWhatItsSourceFileStates) {
  CAIRN_REQUIRE_DATA("lidar3d/small_gicp_pair/source.ply");
  const auto read = [](const std::string& name, std::size_t expected_points) {
    const std::string path = cairn::test::data_path("lidar3d/small_gicp_pair/" + name).string();
    // "binary_little_endian PLY ... float x, y, z, scalar_intensity (16 bytes/point)".
    const std::string raw = read_maybe_compressed(path);
    const std::size_t data_offset = raw.find("end_header\n") + 11;
    EXPECT_EQ(raw.size(), data_offset + 16 * expected_points) << path;
    PointCloudReadReport report;
    PointCloud cloud = read_point_cloud(path, &report);
    EXPECT_EQ(report.format, "ply binary_little_endian");
    EXPECT_EQ(report.trailing_bytes, 0u);
    EXPECT_EQ(report.dropped_non_finite, 0u);
    EXPECT_EQ(cloud.size(), expected_points) << path;
    EXPECT_EQ(cloud.intensity.size(), expected_points) << path;
    float first[4];
    std::memcpy(first, raw.data() + data_offset, 16);
    EXPECT_EQ(cloud.points[0], Eigen::Vector3f(first[0], first[1], first[2]));
    EXPECT_EQ(cloud.intensity[0], first[3]);
    return cloud;
  };
  const PointCloud source = read("source.ply", 69'792);
  const PointCloud target = read("target.ply", 69'088);
  ASSERT_FALSE(source.points.empty());
  ASSERT_FALSE(target.points.empty());
  // Missing returns are stored as (0, 0, 0), not NaN (counted with a separate script): finite,
  // so they are kept.
  const auto zeros = [](const PointCloud& cloud) {
    return std::count_if(cloud.points.begin(), cloud.points.end(),
                         [](const Eigen::Vector3f& p) { return p.isZero(0.0F); });
  };
  EXPECT_EQ(zeros(source), 5'107);
  EXPECT_EQ(zeros(target), 5'032);

  // T_target_source.txt maps source points onto the target: distant source points (> 15 m,
  // where a 0.49 m offset shows) land much closer to their nearest target point with it than
  // without it.
  Eigen::Matrix4d T_target_source;
  std::ifstream in(cairn::test::data_path("lidar3d/small_gicp_pair/T_target_source.txt"));
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) in >> T_target_source(r, c);
  }
  ASSERT_TRUE(in);
  std::vector<Eigen::Vector3d> far;
  for (const Eigen::Vector3f& p : source.points) {
    if (p.norm() > 15.0F) far.push_back(p.cast<double>());
  }
  std::vector<double> with_pose;
  std::vector<double> without_pose;
  for (std::size_t i = 0; i < far.size(); i += 40) {
    const Eigen::Vector3d mapped =
        T_target_source.topLeftCorner<3, 3>() * far[i] + T_target_source.topRightCorner<3, 1>();
    double best_mapped = std::numeric_limits<double>::max();
    double best_raw = std::numeric_limits<double>::max();
    for (const Eigen::Vector3f& q : target.points) {
      best_mapped = std::min(best_mapped, (q.cast<double>() - mapped).squaredNorm());
      best_raw = std::min(best_raw, (q.cast<double>() - far[i]).squaredNorm());
    }
    with_pose.push_back(std::sqrt(best_mapped));
    without_pose.push_back(std::sqrt(best_raw));
  }
  ASSERT_GT(with_pose.size(), 50u);
  EXPECT_LT(median(with_pose), 0.2);
  EXPECT_GT(median(without_pose), 0.3);
}

}  // namespace
}  // namespace cairn::io
