#include "cairn/sim/random.hpp"

#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::sim {

double Random::uniform() {
  // 2^-53: every double in [0, 1) with 53-bit spacing is equally likely.
  return static_cast<double>(engine_() >> 11) * 0x1.0p-53;
}

double Random::gaussian() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  double u = 0.0;
  double v = 0.0;
  double s = 0.0;
  do {
    u = 2.0 * uniform() - 1.0;
    v = 2.0 * uniform() - 1.0;
    s = u * u + v * v;
  } while (s >= 1.0 || s == 0.0);
  const double factor = std::sqrt(-2.0 * std::log(s) / s);
  spare_ = v * factor;
  has_spare_ = true;
  return u * factor;
}

std::uint64_t Random::index(std::uint64_t n) {
  CAIRN_ASSERT(n > 0, "Random::index needs a non-empty range");
  // Largest multiple of n that fits: values at or above it would favour small results.
  const std::uint64_t limit = UINT64_MAX - UINT64_MAX % n;
  std::uint64_t x = engine_();
  while (x >= limit) x = engine_();
  return x % n;
}

std::uint64_t Random::derive_seed(std::uint64_t seed, std::uint64_t stream) {
  // SplitMix64 finaliser (Steele, Lea, Flood, OOPSLA 2014) over seed and stream.
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace cairn::sim
