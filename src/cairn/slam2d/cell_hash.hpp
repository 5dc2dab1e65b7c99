#pragma once
/// \file
/// The hash of a grid cell's 64-bit key for the open-addressing tables of slam2d (the voxel
/// filter, range_scan.cpp; the point map's cell index, point_map.cpp).

#include <cstdint>

namespace cairn::slam2d {

/// splitmix64's finaliser (Steele, Lea & Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): every bit of the key reaches the low bits a table mask keeps.
inline std::uint64_t mix_cell_key(std::uint64_t x) {
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace cairn::slam2d
