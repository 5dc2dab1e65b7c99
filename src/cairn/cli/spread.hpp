#pragma once
/// \file
/// Median, mean and maximum of per-frame / per-scan times, for the commands' reports.

#include <nlohmann/json.hpp>
#include <vector>

namespace cairn::cli {

struct Spread {
  double median = 0.0, mean = 0.0, max = 0.0;
};

/// All zero for no values.
Spread spread(std::vector<double> values);

/// {"median", "mean", "max"} of `seconds`, in milliseconds.
nlohmann::json spread_json_ms(const std::vector<double>& seconds);

}  // namespace cairn::cli
