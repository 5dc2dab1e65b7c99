// Message definitions and the two serialisations, on bytes written out by hand from the
// specifications (wiki.ros.org/msg "Serialization"; OMG CDR as ROS 2 uses it), not by cairn.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "cairn/bag/deserialize.hpp"
#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put_u32(Bytes& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}
void put_string(Bytes& b, const std::string& s) {
  put_u32(b, static_cast<std::uint32_t>(s.size()));
  b.insert(b.end(), s.begin(), s.end());
}

TEST(MessageSchema, ParsesFieldsArraysConstantsAndNestedTypes) {
  const char* text =
      "# a comment\n"
      "Header header\n"
      "uint8 KIND=3   # a constant is not a field\n"
      "float32[] ranges\n"
      "float64[9] covariance\n"
      "Point p\n"
      "================================================================================\n"
      "MSG: std_msgs/Header\n"
      "uint32 seq\ntime stamp\nstring frame_id\n"
      "================================================================================\n"
      "MSG: geometry_msgs/Point\n"
      "float64 x\nfloat64 y\nfloat64 z\n";
  const SchemaSet set = SchemaSet::parse("geometry_msgs/Thing", text, SchemaSet::Dialect::kRos1, "test");
  const MessageSchema& root = set.root();
  ASSERT_EQ(root.fields.size(), 4u);
  EXPECT_EQ(root.fields[0].message_type, "std_msgs/Header");
  EXPECT_EQ(root.fields[1].name, "ranges");
  EXPECT_EQ(root.fields[1].array, Field::Array::kSequence);
  EXPECT_EQ(root.fields[2].array, Field::Array::kFixed);
  EXPECT_EQ(root.fields[2].array_size, 9u);
  EXPECT_EQ(root.fields[3].message_type, "geometry_msgs/Point");  // short name: the message's package
  EXPECT_EQ(set.at("std_msgs/Header").fields[1].primitive, Primitive::kTime);
}

TEST(MessageSchema, RefusesUndefinedTypesAndBadArrays) {
  EXPECT_THROW(SchemaSet::parse("a/B", "c/D d\n", SchemaSet::Dialect::kRos1, "t"), io::ParseError);
  EXPECT_THROW(SchemaSet::parse("a/B", "int32[x] d\n", SchemaSet::Dialect::kRos1, "t"), io::ParseError);
  EXPECT_THROW(SchemaSet::parse("a/B", "int32\n", SchemaSet::Dialect::kRos1, "t"), io::ParseError);
  try {
    SchemaSet::parse("a/B", "int32 x\nfoo/Bar y\n", SchemaSet::Dialect::kRos1, "bag.bag: /t");
    FAIL();
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("foo/Bar"), std::string::npos) << e.what();
  }
}

TEST(MessageSchema, Ros2HeaderAndTimeAreImplicitAndBoundsParse) {
  const SchemaSet set = SchemaSet::parse("pkg/msg/T", "std_msgs/Header header\nstring<=8 name\nint16[<=4] values\n",
                                         SchemaSet::Dialect::kRos2, "t");
  EXPECT_EQ(set.root().type, "pkg/T");
  EXPECT_EQ(set.at("std_msgs/Header").fields[0].message_type, "builtin_interfaces/Time");
  EXPECT_EQ(set.root().fields[2].array_size, 4u);
}

TEST(Deserialize, Ros1LaserScanFromHandWrittenBytes) {
  const char* text =
      "Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\nfloat32 time_increment\n"
      "float32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n"
      "================================================================================\n"
      "MSG: std_msgs/Header\nuint32 seq\ntime stamp\nstring frame_id\n";
  const SchemaSet set = SchemaSet::parse("sensor_msgs/LaserScan", text, SchemaSet::Dialect::kRos1, "t");
  Bytes b;
  put_u32(b, 7);           // seq
  put_u32(b, 100);         // stamp.sec
  put_u32(b, 5);           // stamp.nsec
  put_string(b, "laser");  // frame_id
  const float header_floats[] = {-1.5f, 1.5f, 0.5f, 0.0f, 0.1f, 0.1f, 30.0f};
  for (float f : header_floats) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    put_u32(b, u);
  }
  put_u32(b, 2);
  for (float f : {1.25f, 2.5f}) {
    std::uint32_t u;
    std::memcpy(&u, &f, 4);
    put_u32(b, u);
  }
  put_u32(b, 0);
  const LaserScan scan = to_laser_scan(deserialize(set, b, Serialization::kRos1, "t"));
  EXPECT_EQ(scan.header.seq, 7u);
  EXPECT_EQ(scan.header.stamp_ns, 100'000'000'005);
  EXPECT_EQ(scan.header.frame_id, "laser");
  EXPECT_EQ(scan.angle_min_rad, -1.5);
  EXPECT_EQ(scan.range_max_m, 30.0);
  EXPECT_EQ(scan.ranges_m, (std::vector<float>{1.25f, 2.5f}));
  EXPECT_TRUE(scan.intensities.empty());

  Bytes truncated(b.begin(), b.end() - 3);
  EXPECT_THROW(deserialize(set, truncated, Serialization::kRos1, "t"), io::ParseError);
  Bytes longer = b;
  longer.push_back(0);
  EXPECT_THROW(deserialize(set, longer, Serialization::kRos1, "t"), io::ParseError);  // trailing bytes
}

TEST(Deserialize, CdrAlignsToTheFieldSizeAfterTheHeaderInBothByteOrders) {
  // uint8 a; float64 b; string c; int16[] d  (XCDR1: b at offset 8 after the 4-byte header)
  const SchemaSet set = SchemaSet::parse("p/M", "uint8 a\nfloat64 b\nstring c\nint16[] d\n", SchemaSet::Dialect::kRos2, "t");
  const Bytes little = {0x00, 0x01, 0x00, 0x00,                          // CDR_LE
                        0x05, 0, 0, 0, 0, 0, 0, 0,                       // a = 5, 7 bytes padding
                        0, 0, 0, 0, 0, 0, 0xF8, 0x3F,                    // b = 1.5
                        3, 0, 0, 0, 'h', 'i', 0,                         // c = "hi" (length 3 with NUL)
                        0,                                               // pad to 4
                        2, 0, 0, 0, 0xFF, 0xFF, 0x02, 0x00};             // d = [-1, 2]
  const Bytes big = {0x00, 0x00, 0x00, 0x00,                             // CDR_BE
                     0x05, 0, 0, 0, 0, 0, 0, 0,
                     0x3F, 0xF8, 0, 0, 0, 0, 0, 0,
                     0, 0, 0, 3, 'h', 'i', 0,
                     0,
                     0, 0, 0, 2, 0xFF, 0xFF, 0x00, 0x02};
  for (const Bytes& bytes : {little, big}) {
    const Value v = deserialize(set, bytes, Serialization::kCdr, "t");
    EXPECT_EQ(v["a"].as_uint(), 5u);
    EXPECT_EQ(v["b"].number(), 1.5);
    EXPECT_EQ(v["c"].text(), "hi");
    ASSERT_EQ(v["d"].items().size(), 2u);
    EXPECT_EQ(v["d"].items()[0].as_int(), -1);
    EXPECT_EQ(v["d"].items()[1].as_int(), 2);
  }
  Bytes lying = little;
  lying[28] = 0xFF;  // d's count far beyond the bytes left
  EXPECT_THROW(deserialize(set, lying, Serialization::kCdr, "t"), io::ParseError);
  Bytes no_nul = little;
  no_nul[26] = 'x';
  EXPECT_THROW(deserialize(set, no_nul, Serialization::kCdr, "t"), io::ParseError);
  Bytes xcdr2 = little;
  xcdr2[1] = 0x07;
  EXPECT_THROW(deserialize(set, xcdr2, Serialization::kCdr, "t"), io::ParseError);
}

TEST(Deserialize, CdrEmptyMessageTakesOneByte) {
  const SchemaSet set = SchemaSet::parse("p/M", "p/Empty e\nuint8 after\n===\nMSG: p/Empty\nint32 CONST=1\n",
                                         SchemaSet::Dialect::kRos2, "t");
  const Bytes bytes = {0x00, 0x01, 0x00, 0x00, 0x00, 0x2A};
  EXPECT_EQ(deserialize(set, bytes, Serialization::kCdr, "t")["after"].as_uint(), 42u);
}

}  // namespace
}  // namespace cairn::bag
