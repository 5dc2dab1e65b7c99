#pragma once
/// \file
/// Which images of two streams make one frame, by their header stamps (integer nanoseconds).
///
/// * A stereo pair is exposed at one trigger and both images carry its stamp: they pair by equal
///   stamps, as EuRoC's cam0 / cam1 lists do (io/image_sequence.hpp).
/// * A colour image and a depth map come from two sensors a few milliseconds apart: they pair as
///   TUM's associate.py pairs rgb.txt and depth.txt (vision.in.tum.de/data/datasets/rgbd-dataset/
///   tools): every pair closer than max_difference (0.02 s there), closest first, each image used
///   at most once.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cairn::vslam {

/// associate.py's default max_difference: 0.02 s.
inline constexpr std::int64_t kMaxDepthOffsetNs = 20'000'000;

/// One frame's two images: indices into the two stamp lists.
struct StampPair {
  std::size_t first = 0;
  std::size_t second = 0;
  bool operator==(const StampPair&) const = default;
};

/// The pairs with first[i] == second[j], ordered by stamp. A stamp that repeats within a list
/// pairs once (its first occurrence).
std::vector<StampPair> pair_equal_stamps(const std::vector<std::int64_t>& first, const std::vector<std::int64_t>& second);

/// associate.py's pairs: every (i, j) with |first[i] - second[j]| < max_difference_ns, taken in
/// increasing |difference| (ties: earlier first stamp, then earlier second stamp), each index
/// at most once; returned ordered by the first stamp. The lists need not be sorted.
std::vector<StampPair> associate_stamps(const std::vector<std::int64_t>& first, const std::vector<std::int64_t>& second,
                                        std::int64_t max_difference_ns = kMaxDepthOffsetNs);

}  // namespace cairn::vslam
