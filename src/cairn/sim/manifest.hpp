#pragma once
/// \file
/// What `cairn simulate` records beside a run so it can be reproduced and checked byte for byte:
/// the scenario's parameters as set by NAME=VALUE assignments, and manifest.json (generator,
/// scenario, seed, command, parameters, a summary of the run, the ground truth of the mission and
/// 3D scenarios, and every file with its size and FNV-1a fingerprint). See docs/simulation.md.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cairn/sim/scenario.hpp"

namespace cairn::sim {

/// Applies NAME=VALUE assignments to `scenario`'s parameters (a sensor preset, lidar3d.model,
/// first, so the other lidar3d.* settings override it whatever their order). Returns every
/// problem (malformed assignment, unknown name, unparsable value); values that did not parse keep
/// their defaults.
std::vector<std::string> apply_assignments(Scenario& scenario, const std::vector<std::string>& assignments);

/// Counts the manifest and the terminal summary share.
struct RunCounts {
  std::size_t cloud_points = 0;
  std::size_t true_loops = 0, false_loops = 0;
};
RunCounts count_run(const SimulationResult& result);

/// manifest.json for the run whose files `files` (names relative to `directory`) were written to
/// `directory`; `overrides` are the assignments as given. Timings are not part of it: they would
/// make two identical runs differ. Throws io::ParseError when a file cannot be read back.
nlohmann::json manifest_json(const SimulationResult& result, Scenario& scenario, std::uint64_t seed,
                             const std::vector<std::string>& overrides, const std::string& directory,
                             const std::vector<std::string>& files);

}  // namespace cairn::sim
