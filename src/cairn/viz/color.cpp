#include "cairn/viz/color.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace cairn::viz {
namespace {

Rgb from_hex(unsigned hex) {
  return {static_cast<double>((hex >> 16) & 0xffu) / 255.0, static_cast<double>((hex >> 8) & 0xffu) / 255.0,
          static_cast<double>(hex & 0xffu) / 255.0};
}

// viridisLite::viridis(9): #440154 #472D7B #3B528B #2C728E #21908C #27AD81 #5DC863 #AADC32 #FDE725.
constexpr std::array<unsigned, 9> kViridis = {0x440154, 0x472D7B, 0x3B528B, 0x2C728E, 0x21908C,
                                              0x27AD81, 0x5DC863, 0xAADC32, 0xFDE725};
// matplotlib tab10.
constexpr std::array<unsigned, 10> kTab10 = {0x1f77b4, 0xff7f0e, 0x2ca02c, 0xd62728, 0x9467bd,
                                             0x8c564b, 0xe377c2, 0x7f7f7f, 0xbcbd22, 0x17becf};

}  // namespace

Rgb viridis(double t) {
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0);
  const double scaled = t * static_cast<double>(kViridis.size() - 1);
  const auto i = std::min(static_cast<std::size_t>(scaled), kViridis.size() - 2);
  const double f = scaled - static_cast<double>(i);
  const Rgb a = from_hex(kViridis[i]);
  const Rgb b = from_hex(kViridis[i + 1]);
  return {a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b)};
}

Rgb categorical(int index) {
  const auto n = static_cast<int>(kTab10.size());
  return from_hex(kTab10[static_cast<std::size_t>(((index % n) + n) % n)]);
}

}  // namespace cairn::viz
