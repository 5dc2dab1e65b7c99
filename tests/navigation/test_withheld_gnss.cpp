// withheld_gnss.hpp on a made-up drive whose errors are known by construction: the vehicle drives
// east at 1 m/s, the withheld fixes lie 2 m north of it (placed through GeographicLib's reverse
// projection, not the code under test), and the wheel odometry drives the same path in a frame
// turned by 90 degrees and shifted, which the comparison must undo at the gap's start.

#include <gtest/gtest.h>

#include <cmath>

#include "cairn/core/so3.hpp"
#include "cairn/gnss/local_frame.hpp"
#include "cairn/navigation/withheld_gnss.hpp"

namespace cairn::navigation {
namespace {

const gnss::GeodeticPosition kOrigin{47.3769, 8.5417, 408.0};

gnss::GnssFix fix_at(double t_s, const Vector3& p_enu) {
  const gnss::GeodeticPosition g = gnss::LocalFrame(kOrigin).reverse(p_enu);
  gnss::GnssFix fix;
  fix.stamp = core::Timestamp::from_seconds(t_s);
  fix.latitude_deg = g.latitude_deg;
  fix.longitude_deg = g.longitude_deg;
  fix.altitude_m = g.altitude_m;
  return fix;
}

TEST(WithheldGnss, ErrorsOfAKnownDriveAndTheWheelsTurnedOntoIt) {
  std::vector<NavigationState> states;
  for (int k = 0; k <= 200; ++k) {
    NavigationState s;
    s.time_s = 100.0 + 0.1 * k;
    s.state.T_world_body = core::SE3(core::SO3(), Vector3(0.1 * k, 0.0, 0.0));
    s.state.v_world_mps = Vector3(1.0, 0.0, 0.0);
    s.predicted = s.state;
    states.push_back(s);
  }
  // Fixes every 0.5 s; 105-110 s withheld, 2 m north of the path; the first one back 1 m south.
  std::vector<gnss::GnssFix> fixes;
  for (double t = 100.0; t <= 119.9; t += 0.5) {
    const double north = t >= 105.0 && t < 110.0 ? 2.0 : (t >= 110.0 && t < 110.1 ? -1.0 : 0.0);
    fixes.push_back(fix_at(t, Vector3(t - 100.0, north, 0.0)));
  }
  const WithheldFixes split = withhold_fixes(fixes, 105.0, 110.0);
  ASSERT_EQ(split.withheld.size(), 10u);
  ASSERT_EQ(split.kept.size(), fixes.size() - 10);
  // The wheels' own frame: the path runs north from (5, -3), so R_enu_odom is -90 deg about z.
  io::Trajectory wheels;
  for (int k = 0; k <= 200; ++k) {
    wheels.stamps.push_back(core::Timestamp::from_seconds(100.0 + 0.1 * k));
    wheels.poses.emplace_back(core::SO3::exp(Vector3(0, 0, M_PI / 2)), Vector3(5.0, -3.0 + 0.1 * k, 0.0));
  }
  const WithheldComparison c = compare_with_withheld(states, split, 105.0, 110.0, kOrigin, core::SE3(), wheels);
  ASSERT_EQ(c.fixes.size(), 10u);
  for (const WithheldFixError& e : c.fixes) {
    EXPECT_NEAR(e.fused_m, 2.0, 1e-6) << e.time_s;
    ASSERT_TRUE(e.wheel_m.has_value());
    EXPECT_NEAR(*e.wheel_m, 2.0, 1e-6) << e.time_s;
  }
  EXPECT_NEAR(c.fused_rms_m, 2.0, 1e-6);
  ASSERT_TRUE(c.wheel_rms_m && c.first_fix_back && c.first_fix_back->wheel_m);
  EXPECT_NEAR(*c.wheel_rms_m, 2.0, 1e-6);
  EXPECT_NEAR(c.first_fix_back->time_s, 110.0, 1e-9);
  EXPECT_NEAR(c.first_fix_back->fused_m, 1.0, 1e-6);
  EXPECT_NEAR(*c.first_fix_back->wheel_m, 1.0, 1e-6);
}

TEST(WithheldGnss, NothingToCompareIsAnError) {
  std::vector<NavigationState> states(1);
  EXPECT_THROW(compare_with_withheld(states, WithheldFixes{}, 0.0, 1.0, kOrigin, core::SE3(), io::Trajectory{}), std::invalid_argument);
  WithheldFixes one;
  one.withheld.push_back(fix_at(0.5, Vector3::Zero()));
  EXPECT_THROW(compare_with_withheld({}, one, 0.0, 1.0, kOrigin, core::SE3(), io::Trajectory{}), std::invalid_argument);
  // Without wheel poses there is no wheel error, but the fused one is there.
  const WithheldComparison c = compare_with_withheld(states, one, 0.0, 1.0, kOrigin, core::SE3(), io::Trajectory{});
  EXPECT_FALSE(c.wheel_rms_m.has_value());
  EXPECT_NEAR(c.fused_rms_m, 0.0, 1e-6);
}

}  // namespace
}  // namespace cairn::navigation
