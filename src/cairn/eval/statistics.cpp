#include "cairn/eval/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "cairn/core/assert.hpp"

namespace cairn::eval {

// numpy/core/src/umath/loops_utils.h.src, pairwise_sum: below 8 elements a plain loop; up to
// 128 elements eight interleaved accumulators; above, split in two halves (the first rounded
// down to a multiple of 8). Reproduced so that mean and sse agree with evo beyond 1e-15.
double pairwise_sum(std::span<const double> values) {
  const std::size_t n = values.size();
  if (n < 8) {
    double sum = 0.0;
    for (double v : values) sum += v;
    return sum;
  }
  if (n <= 128) {
    double r[8];
    for (std::size_t k = 0; k < 8; ++k) r[k] = values[k];
    std::size_t i = 8;
    for (; i + 8 <= n; i += 8) {
      for (std::size_t k = 0; k < 8; ++k) r[k] += values[i + k];
    }
    double sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
    for (; i < n; ++i) sum += values[i];
    return sum;
  }
  std::size_t half = n / 2;
  half -= half % 8;
  return pairwise_sum(values.first(half)) + pairwise_sum(values.subspan(half));
}

Statistics compute_statistics(std::span<const double> errors) {
  CAIRN_ASSERT(!errors.empty(), "compute_statistics needs at least one error");
  const auto n = static_cast<double>(errors.size());
  Statistics s;
  s.count = errors.size();
  std::vector<double> work(errors.begin(), errors.end());
  s.mean = pairwise_sum(work) / n;
  for (double& v : work) v = v * v;
  s.sse = pairwise_sum(work);
  s.rmse = std::sqrt(s.sse / n);
  for (std::size_t i = 0; i < errors.size(); ++i) {
    const double d = std::abs(errors[i] - s.mean);
    work[i] = d * d;
  }
  s.std = std::sqrt(pairwise_sum(work) / n);
  std::copy(errors.begin(), errors.end(), work.begin());
  std::sort(work.begin(), work.end());
  const std::size_t mid = work.size() / 2;
  s.median = work.size() % 2 == 1 ? work[mid] : (work[mid - 1] + work[mid]) / 2.0;
  s.min = work.front();
  s.max = work.back();
  return s;
}

}  // namespace cairn::eval
