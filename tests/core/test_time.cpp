#include <gtest/gtest.h>

#include "cairn/core/time.hpp"

namespace cairn::core {
namespace {

TEST(Timestamp, ParsesDecimalSecondsExactly) {
  const auto t = Timestamp::parse_seconds("1305031102.175304");
  ASSERT_TRUE(t.has_value());
  EXPECT_EQ(t->nanoseconds(), 1305031102175304000LL);
  EXPECT_EQ(t->to_seconds_string(), "1305031102.175304000");
  EXPECT_EQ(Timestamp::parse_seconds(t->to_seconds_string()), t);
}

TEST(Timestamp, RoundsPastNineDecimals) {
  EXPECT_EQ(Timestamp::parse_seconds("0.0000000015")->nanoseconds(), 2);
  EXPECT_EQ(Timestamp::parse_seconds("0.0000000014")->nanoseconds(), 1);
  EXPECT_EQ(Timestamp::parse_seconds("-1.5")->nanoseconds(), -1500000000LL);
}

TEST(Timestamp, ParsesScientificNotationOfKittiTimes) {
  EXPECT_EQ(Timestamp::parse_seconds("1.036614e-01")->nanoseconds(), 103661400);
  EXPECT_EQ(Timestamp::parse_seconds("0.000000e+00")->nanoseconds(), 0);
}

TEST(Timestamp, RejectsGarbage) {
  for (const char* bad : {"", "abc", "1.2.3", "nan", "inf", "1e400", "12x", ".", "-", "1 2",
                          "99999999999999999999"}) {
    EXPECT_FALSE(Timestamp::parse_seconds(bad).has_value()) << bad;
  }
  EXPECT_FALSE(Timestamp::parse_nanoseconds("1.5").has_value());
  EXPECT_EQ(Timestamp::parse_nanoseconds("1403715524907143168")->nanoseconds(), 1403715524907143168LL);
}

TEST(Timestamp, PrintsTheExtremesWithoutOverflow) {
  EXPECT_EQ(Timestamp::from_nanoseconds(INT64_MIN).to_seconds_string(), "-9223372036.854775808");
  EXPECT_EQ(Timestamp::from_nanoseconds(INT64_MAX).to_seconds_string(), "9223372036.854775807");
  EXPECT_EQ(Timestamp::from_nanoseconds(-1).to_seconds_string(), "-0.000000001");
}

}  // namespace
}  // namespace cairn::core
