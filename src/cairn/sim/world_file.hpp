#pragma once
/// \file
/// The exact world as text (world.txt), so evaluations can compare a map with the true walls,
/// pillars and people. One element per line, world frame, metres; '#' lines are comments:
///
///   WALL ax ay bx by
///   GLASS ax ay bx by      (a glass pane: Segment::glass)
///   CIRCLE cx cy radius
///   LANDMARK id x y
///   WALKER from_x from_y to_x to_y speed_mps radius_m phase_s
///
/// A walker at time t is at distance s = speed (t + phase) along from -> to -> from, repeating
/// (World::Walker). Numbers are the shortest text that reads back to the same double.

#include <string>

#include "cairn/sim/world.hpp"

namespace cairn::sim {

/// Writes `world` atomically. Throws io::ParseError when the file cannot be written.
void write_world_file(const std::string& path, const World& world);

}  // namespace cairn::sim
