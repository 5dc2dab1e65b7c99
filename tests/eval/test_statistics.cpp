#include "cairn/eval/statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace cairn::eval {
namespace {

// Values worked out by hand from the definitions in evo's PE.get_statistic.
TEST(Statistics, EvenCountByHand) {
  const std::vector<double> e = {4.0, 1.0, 3.0, 2.0};
  const Statistics s = compute_statistics(e);
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);  // mean of the two middle values
  EXPECT_DOUBLE_EQ(s.sse, 30.0);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population: (2.25 + 0.25 + 0.25 + 2.25) / 4
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
}

TEST(Statistics, OddCountAndSingleValue) {
  const std::vector<double> e = {5.0, 1.0, 2.0};
  const Statistics s = compute_statistics(e);
  EXPECT_DOUBLE_EQ(s.median, 2.0);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(((5.0 - 8.0 / 3) * (5.0 - 8.0 / 3) + (1.0 - 8.0 / 3) * (1.0 - 8.0 / 3) +
                                      (2.0 - 8.0 / 3) * (2.0 - 8.0 / 3)) / 3.0));
  const std::vector<double> one = {0.5};
  const Statistics t = compute_statistics(one);
  EXPECT_DOUBLE_EQ(t.std, 0.0);
  EXPECT_DOUBLE_EQ(t.rmse, 0.5);
  EXPECT_DOUBLE_EQ(t.median, 0.5);
}

// Pairwise summation against a long-double running sum, over the block sizes where numpy's
// scheme switches (7/8, 128/129) and a few larger ones.
TEST(Statistics, PairwiseSumAgreesWithExtendedPrecision) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(0.0, 3.0);
  for (std::size_t n : {1u, 7u, 8u, 9u, 127u, 128u, 129u, 1000u, 4541u}) {
    std::vector<double> v(n);
    long double exact = 0.0L;
    for (double& x : v) {
      x = u(rng);
      exact += static_cast<long double>(x);
    }
    EXPECT_NEAR(pairwise_sum(v), static_cast<double>(exact), 1e-12 * static_cast<double>(n)) << n;
  }
}

}  // namespace
}  // namespace cairn::eval
