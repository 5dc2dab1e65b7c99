#pragma once
/// \file
/// Spurious observations for data-association experiments. The simulator's landmark sensor
/// always reports true identities and never clutter, so clutter is injected here, seeded, and
/// marked with kSpuriousId so that associations can be scored afterwards.

#include <cstdint>
#include <string>
#include <vector>

#include "cairn/landmarks/landmark_run.hpp"

namespace cairn::landmarks {

struct ClutterOptions {
  /// Share of spurious observations in the output, [0, 0.9]: n_spurious = round(f n / (1 - f))
  /// for n true observations.
  double spurious_fraction = 0.1;
  /// Spurious observations are uniform over the area of the annulus min_range_m .. max_range_m
  /// (metres, 0 < min < max) and uniform in bearing over (-pi, pi].
  double min_range_m = 0.5;
  double max_range_m = 10.0;
  std::uint64_t seed = 1;

  bool is_valid(std::string* why) const;
};

/// `observations` plus spurious ones, each at the time of a uniformly chosen existing
/// observation, kept in time order (spurious after the true ones of the same time). Returns the
/// number added. Precondition: options.is_valid().
std::size_t add_spurious_observations(std::vector<Observation>* observations, const ClutterOptions& options);

}  // namespace cairn::landmarks
