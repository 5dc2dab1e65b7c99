#include "cairn/landmarks/clutter.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "cairn/core/assert.hpp"

namespace cairn::landmarks {

bool ClutterOptions::is_valid(std::string* why) const {
  std::string problems;
  const auto add = [&](const std::string& p) { problems += (problems.empty() ? "" : "; ") + p; };
  if (!(spurious_fraction >= 0.0 && spurious_fraction <= 0.9)) add("spurious_fraction must be in [0, 0.9]");
  if (!(min_range_m > 0.0 && max_range_m > min_range_m && std::isfinite(max_range_m))) {
    add("need 0 < min_range_m < max_range_m");
  }
  if (why != nullptr) *why = problems;
  return problems.empty();
}

std::size_t add_spurious_observations(std::vector<Observation>* observations, const ClutterOptions& options) {
  CAIRN_ASSERT(options.is_valid(nullptr), "add_spurious_observations: invalid options");
  if (observations->empty() || options.spurious_fraction == 0.0) return 0;
  const double n = static_cast<double>(observations->size());
  const auto count = static_cast<std::size_t>(std::llround(options.spurious_fraction * n / (1.0 - options.spurious_fraction)));
  std::mt19937_64 engine(options.seed);
  // Top 53 bits of one engine output: the same numbers with every standard library.
  const auto uniform = [&engine]() { return static_cast<double>(engine() >> 11) * 0x1.0p-53; };
  const double r0 = options.min_range_m * options.min_range_m;
  const double r1 = options.max_range_m * options.max_range_m;
  std::vector<Observation> added;
  added.reserve(count);
  for (std::size_t k = 0; k < count; ++k) {
    const auto pick = std::min(observations->size() - 1, static_cast<std::size_t>(uniform() * n));
    Observation o;
    o.time = (*observations)[pick].time;
    o.landmark_id = kSpuriousId;
    o.range_m = std::sqrt(r0 + uniform() * (r1 - r0));
    o.bearing_rad = std::numbers::pi * (1.0 - 2.0 * uniform());
    added.push_back(o);
  }
  observations->insert(observations->end(), added.begin(), added.end());
  std::stable_sort(observations->begin(), observations->end(),
                   [](const Observation& a, const Observation& b) { return a.time < b.time; });
  return count;
}

}  // namespace cairn::landmarks
