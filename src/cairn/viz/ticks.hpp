#pragma once
/// \file
/// Axis tick positions at "nice" numbers (1, 2, 5 times a power of ten), after Heckbert,
/// "Nice numbers for graph labels", Graphics Gems I (1990), pp. 61-63.

#include <string>
#include <vector>

namespace cairn::viz {

struct Ticks {
  /// Tick values inside [lo, hi], increasing.
  std::vector<double> values;
  /// Distance between ticks.
  double step = 1;
  /// Decimals needed to print the step exactly (0 for steps >= 1).
  int decimals = 0;
};

/// About `target` ticks (>= 2) covering [lo, hi]: step = nice_number((hi - lo) / (target - 1), round). lo == hi (or non-finite bounds) gives one tick.
Ticks nice_ticks(double lo, double hi, int target = 6);

/// The nice number near x (x > 0): 1, 2, 5 or 10 times a power of ten; rounded when `round`,
/// otherwise the smallest such number >= x (Heckbert's nicenum).
double nice_number(double x, bool round);

/// `value` with `decimals` decimals, "-0" printed as "0".
std::string format_tick(double value, int decimals);

}  // namespace cairn::viz
