#include "cairn/viz/ticks.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace cairn::viz {

double nice_number(double x, bool round) {
  const double exponent = std::floor(std::log10(x));
  const double fraction = x / std::pow(10.0, exponent);
  double nice = 10;
  if (round) {
    if (fraction < 1.5) {
      nice = 1;
    } else if (fraction < 3) {
      nice = 2;
    } else if (fraction < 7) {
      nice = 5;
    }
  } else {
    if (fraction <= 1) {
      nice = 1;
    } else if (fraction <= 2) {
      nice = 2;
    } else if (fraction <= 5) {
      nice = 5;
    }
  }
  return nice * std::pow(10.0, exponent);
}

Ticks nice_ticks(double lo, double hi, int target) {
  Ticks ticks;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) {
    ticks.values = {std::isfinite(lo) ? lo : 0.0};
    return ticks;
  }
  target = std::max(target, 2);
  // Heckbert rounds the range up to a nice number first; stepping the raw range gives ticks
  // closer to `target` (a 600 m wide map gets 100 m ticks, not 200 m).
  ticks.step = nice_number((hi - lo) / static_cast<double>(target - 1), true);
  ticks.decimals = std::max(0, static_cast<int>(-std::floor(std::log10(ticks.step) + 1e-9)));
  const double first = std::ceil(lo / ticks.step - 1e-9) * ticks.step;
  for (double v = first; v <= hi + 1e-9 * ticks.step; v += ticks.step) {
    // Snap to the grid so 0.30000000000000004 prints and compares as 0.3.
    ticks.values.push_back(std::round(v / ticks.step) * ticks.step);
    if (ticks.values.size() > 100) break;
  }
  return ticks;
}

std::string format_tick(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  std::string text(buffer);
  if (text.find_first_not_of("-0.") == std::string::npos && text.front() == '-') text.erase(0, 1);
  return text;
}

}  // namespace cairn::viz
