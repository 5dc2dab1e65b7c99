#pragma once
/// \file
/// Colours for plots: a few distinct line colours and a perceptually uniform colour map.

namespace cairn::viz {

/// Red, green, blue in [0, 1].
struct Rgb {
  double r = 0;
  double g = 0;
  double b = 0;
};

/// Viridis (van der Walt and Smith, matplotlib 1.5 / 2.0 default), as 9 stops at 0, 1/8, ..., 1
/// (the values R's viridisLite gives for viridis(9)) interpolated linearly in RGB. Dark blue at
/// 0, yellow at 1; readable in grey scale and by colour-blind readers. `t` is clamped to [0, 1].
Rgb viridis(double t);

/// Distinct colours for lines (matplotlib's "tab10" order): 0 blue, 1 orange, 2 green, 3 red,
/// 4 purple, ...; cycles after 10.
Rgb categorical(int index);

/// Mid grey for reference data.
inline constexpr Rgb kGrey{0.45, 0.45, 0.45};
inline constexpr Rgb kBlack{0, 0, 0};

}  // namespace cairn::viz
