#include "cairn/cli/spread.hpp"

#include <algorithm>
#include <numeric>

namespace cairn::cli {

Spread spread(std::vector<double> values) {
  Spread s;
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  s.median = n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
  s.mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(n);
  s.max = values.back();
  return s;
}

nlohmann::json spread_json_ms(const std::vector<double>& seconds) {
  std::vector<double> ms;
  ms.reserve(seconds.size());
  for (const double s : seconds) ms.push_back(1e3 * s);
  const Spread s = spread(ms);
  return {{"median", s.median}, {"mean", s.mean}, {"max", s.max}};
}

}  // namespace cairn::cli
