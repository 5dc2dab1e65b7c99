#pragma once
/// \file
/// A PNG picture of a world with the ground-truth path and the dead-reckoning path, drawn with
/// cairo: walls black, pillars and posts grey, landmarks as red crosses, walkers' tracks purple
/// (with a disc where each is at time 0), ground truth blue,
/// dead reckoning orange, the start as a green dot, a 5 m scale bar and a legend. North (+y)
/// is up.

#include <string>
#include <vector>

#include "cairn/core/types.hpp"
#include "cairn/sim/world.hpp"

namespace cairn::sim {

struct RenderOptions {
  /// Image scale, pixels per metre (> 0).
  double pixels_per_m = 20.0;
  /// Empty border around the world, pixels.
  int margin_px = 40;
  /// First legend line (the scenario and seed, say).
  std::string title;
};

/// Draws and writes `path` atomically. `truth` and `dead_reckoning` are positions in the world
/// frame (the odometry frame coincides with it at the start); either may be empty. A non-finite
/// point (NaN) breaks the line there: the ground truth of a kidnapped robot jumps.
/// Throws io::ParseError when the image cannot be written.
void render_png(const std::string& path, const World& world, const std::vector<Vector2>& truth,
                const std::vector<Vector2>& dead_reckoning, const RenderOptions& options);

}  // namespace cairn::sim
