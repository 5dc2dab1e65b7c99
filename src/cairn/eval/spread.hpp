#pragma once
/// \file
/// Median, mean and maximum of per-scan / per-frame times, for the pipelines' reports (report.json's
/// timing sections). Errors against ground truth are summarised by statistics.hpp (evo's
/// definitions); this is the plain summary of wall-clock times, where pairwise summation buys
/// nothing.

#include <algorithm>
#include <numeric>
#include <nlohmann/json.hpp>
#include <vector>

namespace cairn::eval {

struct Spread {
  double median = 0.0, mean = 0.0, max = 0.0;
};

/// All zero for no values. The median of an even count is the mean of the two middle values.
inline Spread spread(std::vector<double> values) {
  Spread s;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  s.median = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  s.max = values.back();
  return s;
}

/// {"median", "mean", "max"} of `seconds`, in milliseconds.
inline nlohmann::json spread_json_ms(const std::vector<double>& seconds) {
  std::vector<double> ms;
  ms.reserve(seconds.size());
  for (const double s : seconds) ms.push_back(1e3 * s);
  const Spread s = spread(ms);
  return {{"median", s.median}, {"mean", s.mean}, {"max", s.max}};
}

}  // namespace cairn::eval
