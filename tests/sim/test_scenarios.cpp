// Every named scenario runs, stays out of the walls, produces what its description promises,
// and exposes its parameters for listing, overriding and the manifest.

#include <gtest/gtest.h>

#include <algorithm>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {
namespace {

class EveryScenario : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryScenario, RunsAndStaysInFreeSpace) {
  auto scenario = make_scenario(GetParam());
  ASSERT_TRUE(scenario.has_value());
  if (scenario->is_3d()) scenario->lidar3d.columns = 90;  // the 3D LiDAR is tested in test_sim_3d*.cpp
  std::string why;
  ASSERT_TRUE(scenario->is_valid(&why)) << why;
  const SimulationResult result = simulate(*scenario, 1);
  EXPECT_GT(result.path_length_m, 100.0);
  EXPECT_GE(result.min_clearance_m, 0.3) << "the route passes too close to a wall or pillar";
  EXPECT_GT(result.scan_samples.size(), 400u);
  if (scenario->is_3d()) {
    EXPECT_EQ(result.clouds.size(), result.scan_samples.size());
    // Only the streets have lamps for the camera.
    EXPECT_EQ(result.camera_observations.empty(), scenario->world != WorldKind::kStreet3D);
    return;  // no 2D LiDAR, pose graph or relations
  }
  EXPECT_GT(result.relations.size(), 50u);
  std::size_t true_loops = 0;
  for (const auto& loop : result.graph.loops) true_loops += loop.is_false ? 0 : 1;
  EXPECT_GT(true_loops, 0u) << "every scenario closes at least one loop";
  EXPECT_EQ(result.landmark_observations.empty(), !scenario->simulate_landmarks);
}

INSTANTIATE_TEST_SUITE_P(Sim, EveryScenario, ::testing::ValuesIn(scenario_names()),
                         [](const auto& param_info) {
                           std::string name = param_info.param;
                           std::replace(name.begin(), name.end(), '-', '_');
                           return name;
                         });

TEST(Scenarios, UnknownNameIsRefused) { EXPECT_FALSE(make_scenario("office2").has_value()); }

TEST(Scenarios, OpenHallIsMostlyEmptyAndOfficeIsNot) {
  EXPECT_GT(simulate(*make_scenario("open-hall"), 1).max_range_fraction, 0.9);
  EXPECT_LT(simulate(*make_scenario("office"), 1).max_range_fraction, 0.1);
}

TEST(Scenarios, PeopleChangeTheScansButNotTheTruth) {
  const SimulationResult empty = simulate(*make_scenario("office"), 1);
  const SimulationResult busy = simulate(*make_scenario("office-people"), 1);
  ASSERT_EQ(empty.scans.size(), busy.scans.size());
  EXPECT_EQ(busy.world.world.walkers.size(), 8u);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < empty.scans.size(); ++i) differing += empty.scans[i] != busy.scans[i] ? 1 : 0;
  EXPECT_GT(differing, empty.scans.size() / 4);
  EXPECT_EQ(empty.truth.back().T_world_body.translation(), busy.truth.back().T_world_body.translation());
}

TEST(Scenarios, FastTurnsOverrideTheCornerHandling) {
  Scenario scenario = *make_scenario("office");
  scenario.fast_turns = true;
  const SimulationResult result = simulate(scenario, 1);
  double fastest = 0.0;
  for (const auto& s : result.truth) fastest = std::max(fastest, std::abs(s.yaw_rate_rad_s));
  EXPECT_NEAR(fastest, 2.5, 1e-9);
  EXPECT_GE(result.min_clearance_m, 0.3);
}

TEST(Parameters, TextParsesBackToTheSameValue) {
  for (const auto& name : scenario_names()) {
    Scenario scenario = *make_scenario(name);
    for (auto& p : parameters(scenario)) {
      const std::string before = p.text();
      std::string why;
      ASSERT_TRUE(p.set(before, &why)) << p.name << ": " << why;
      EXPECT_EQ(p.text(), before) << p.name;
      EXPECT_FALSE(p.unit.empty() && p.name.ends_with("_m")) << p.name << " has a unit in its name but none listed";
    }
  }
}

TEST(Parameters, SetChangesTheFieldAndBadTextIsRefused) {
  Scenario scenario = *make_scenario("office");
  auto params = parameters(scenario);
  auto find = [&](const std::string& name) -> Parameter& {
    for (auto& p : params) {
      if (p.name == name) return p;
    }
    throw std::runtime_error("no parameter " + name);
  };
  std::string why;
  ASSERT_TRUE(find("lidar.range_sigma_m").set("0.03", &why));
  EXPECT_EQ(scenario.lidar.range_sigma_m, 0.03);
  ASSERT_TRUE(find("lidar.beams").set("361", &why));
  EXPECT_EQ(scenario.lidar.beams, 361);
  ASSERT_TRUE(find("trajectory.fast_turns").set("true", &why));
  EXPECT_TRUE(scenario.fast_turns);
  EXPECT_FALSE(find("lidar.beams").set("12.5", &why));
  EXPECT_NE(why.find("lidar.beams"), std::string::npos) << why;
  EXPECT_FALSE(find("lidar.range_sigma_m").set("nan", &why));
  EXPECT_FALSE(find("trajectory.fast_turns").set("maybe", &why));
  // A value that parses but breaks a rule is caught by is_valid, naming the field.
  ASSERT_TRUE(find("lidar.period_s").set("0.015", &why));
  EXPECT_FALSE(scenario.is_valid(&why));
  EXPECT_NE(why.find("lidar.period_s"), std::string::npos) << why;
}

TEST(Parameters, OnlyTheScenariosWorldIsListed) {
  Scenario office = *make_scenario("office");
  Scenario corridor = *make_scenario("corridor-aliasing");
  auto has = [](Scenario& s, const std::string& prefix) {
    for (const auto& p : parameters(s)) {
      if (p.name.starts_with(prefix)) return true;
    }
    return false;
  };
  EXPECT_TRUE(has(office, "office."));
  EXPECT_FALSE(has(office, "corridor."));
  EXPECT_TRUE(has(corridor, "corridor."));
}

}  // namespace
}  // namespace cairn::sim
