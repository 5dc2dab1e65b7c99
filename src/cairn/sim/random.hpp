#pragma once
/// \file
/// The simulator's one source of randomness: std::mt19937_64 plus distributions written here.
///
/// The engine's output is fixed by the C++ standard, but std::uniform_real_distribution and
/// std::normal_distribution are not (libstdc++, libc++ and MSVC give different numbers for the
/// same engine state). Every variate cairn::sim draws therefore goes through this class:
///  - uniform(): the top 53 bits of one 64-bit engine output, times 2^-53: a double in [0, 1).
///  - gaussian(): Marsaglia's polar method (Marsaglia & Bray, SIAM Review 6(3), 1964): draw
///    u, v uniform in (-1, 1) until s = u^2 + v^2 is in (0, 1), return u * sqrt(-2 ln s / s) and
///    keep v * sqrt(-2 ln s / s) for the next call. It needs only +, *, /, sqrt (exact in IEEE 754)
///    and one log, so the output is the same bit for bit wherever std::log is correctly rounded
///    for these arguments (glibc's is, to < 1 ulp; a different libm may differ in the last bit).

#include <cstdint>
#include <random>

namespace cairn::sim {

class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}

  /// Uniform in [0, 1), 53 random bits.
  double uniform();
  /// Uniform in [low, high).
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  /// Standard normal N(0, 1) by the polar method (see the file comment).
  double gaussian();
  /// N(0, sigma^2). sigma = 0 returns 0 but still draws, so streams stay aligned whatever the
  /// noise settings.
  double gaussian(double sigma) { return sigma * gaussian(); }
  /// true with probability p (uniform() < p; always draws one variate).
  bool bernoulli(double p) { return uniform() < p; }
  /// Uniform integer in [0, n). Precondition: n > 0. Uses rejection, so it is unbiased.
  std::uint64_t index(std::uint64_t n);

  /// A seed for an independent sub-stream: a SplitMix64 hash of (seed, stream). Each sensor
  /// gets its own stream, so switching one sensor's noise off does not change another's noise.
  static std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream);

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace cairn::sim
