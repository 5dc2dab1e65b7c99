#include "cairn/eval/association.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace cairn::eval {
namespace {

using core::SE3;
using core::Timestamp;

io::Trajectory stamped(const std::vector<double>& seconds) {
  io::Trajectory t;
  for (double s : seconds) {
    t.stamps.push_back(Timestamp::from_nanoseconds(std::llround(s * 1e9)));
    t.poses.push_back(SE3(core::SO3(), Vector3(s, 0.0, 0.0)));
  }
  return t;
}

// evo matching_time_indices: each stamp of the shorter trajectory takes the nearest stamp of the
// longer one if within max_diff; the longer one's stamps may be reused.
TEST(Association, NearestWithinToleranceShorterTrajectoryWalked) {
  const io::Trajectory reference = stamped({0.0, 0.1, 0.2, 0.3, 0.4, 0.5});
  const io::Trajectory estimate = stamped({0.104, 0.105, 0.3095, 0.45});
  const Association a = associate(reference, estimate, {.max_time_difference_s = 0.01});
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_TRUE(a.by_time);
  EXPECT_EQ(a.max_pairs, 4u);
  // 0.104 -> 0.1, 0.105 -> 0.1 again, 0.3095 -> 0.3, 0.45: 0.05 away from both, dropped.
  EXPECT_EQ(a.estimate_indices, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(a.reference_indices, (std::vector<std::size_t>{1, 1, 3}));
}

TEST(Association, TieGoesToTheEarlierStampAsNumpyArgmin) {
  // Binary fractions, so the two differences are exactly equal in double as well.
  const io::Trajectory reference = stamped({1.0, 1.5, 2.0});
  const io::Trajectory estimate = stamped({1.25});
  const Association a = associate(reference, estimate, {.max_time_difference_s = 0.25});
  ASSERT_TRUE(a.outcome.ok());
  EXPECT_EQ(a.reference_indices, (std::vector<std::size_t>{0}));
}

TEST(Association, OffsetIsAddedToTheEstimateWhicheverIsLonger) {
  const io::Trajectory reference = stamped({10.0, 11.0, 12.0});
  const io::Trajectory estimate_short = stamped({10.5, 11.5});
  AssociationOptions options{.max_time_difference_s = 0.001, .offset_s = 0.5};
  Association a = associate(reference, estimate_short, options);
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_EQ(a.reference_indices, (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(a.estimate_indices, (std::vector<std::size_t>{0, 1}));
  const io::Trajectory estimate_long = stamped({9.5, 10.5, 11.5, 12.5});
  a = associate(reference, estimate_long, options);
  ASSERT_TRUE(a.outcome.ok()) << a.outcome.message;
  EXPECT_EQ(a.reference_indices, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(a.estimate_indices, (std::vector<std::size_t>{0, 1, 2}));
}

TEST(Association, WithoutStampsPairsByIndex) {
  io::Trajectory reference = stamped({0, 1, 2});
  io::Trajectory estimate = stamped({0, 1, 2});
  reference.stamps.clear();
  estimate.stamps.clear();
  const Association a = associate(reference, estimate);
  ASSERT_TRUE(a.outcome.ok());
  EXPECT_FALSE(a.by_time);
  EXPECT_EQ(a.estimate_indices, (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(a.reference_indices, (std::vector<std::size_t>{0, 1, 2}));
}

}  // namespace
}  // namespace cairn::eval
