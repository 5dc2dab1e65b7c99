#pragma once
/// \file
/// Wall-clock time of a pipeline's stages: the one clock every module measures with (monotonic,
/// never adjusted), and the seconds elapsed since a start point.

#include <chrono>

namespace cairn::core {

using Clock = std::chrono::steady_clock;

/// Seconds elapsed since `start` on Clock.
inline double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

}  // namespace cairn::core
