#pragma once
// Landmark runs straight from the simulator's library (no files): the same numbers
// `cairn simulate landmarks --seed S --out DIR` writes, converted as read_landmark_run reads them.

#include <cstdint>
#include <functional>

#include "cairn/landmarks/landmark_run.hpp"
#include "cairn/sim/scenario.hpp"

namespace cairn::landmarks::testing {

inline LandmarkRun simulated_run(std::uint64_t seed, const std::function<void(sim::Scenario&)>& adjust = {}) {
  sim::Scenario scenario = *sim::make_scenario("landmarks");
  if (adjust) adjust(scenario);
  const sim::SimulationResult result = sim::simulate(scenario, seed);
  LandmarkRun run;
  run.source = "simulated landmarks, seed " + std::to_string(seed);
  for (const std::size_t i : result.odometry_samples) {
    const core::SE2& T = result.odometry.poses[i];
    run.odometry.push_back({result.truth[i].stamp, Vector3(T.x(), T.y(), T.angle())});
  }
  for (const std::size_t i : result.scan_samples) {
    const core::SE2& T = result.truth[i].T_world_body;
    run.ground_truth.push_back({result.truth[i].stamp, Vector3(T.x(), T.y(), T.angle())});
  }
  for (const sim::Landmark& l : result.world.world.landmarks) run.true_landmarks[l.id] = l.position;
  for (const sim::LandmarkObservation& o : result.landmark_observations) {
    run.observations.push_back({o.stamp, o.landmark_id, o.range_m, o.bearing_rad, 0});
  }
  return run;
}

}  // namespace cairn::landmarks::testing
