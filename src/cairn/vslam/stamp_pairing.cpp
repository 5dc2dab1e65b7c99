#include "cairn/vslam/stamp_pairing.hpp"

#include <algorithm>
#include <map>
#include <numeric>
#include <tuple>

namespace cairn::vslam {
namespace {

/// Indices of `stamps` ordered by stamp (ties in list order).
std::vector<std::size_t> order_by_stamp(const std::vector<std::int64_t>& stamps) {
  std::vector<std::size_t> order(stamps.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return stamps[a] < stamps[b]; });
  return order;
}

void sort_by_first_stamp(std::vector<StampPair>& pairs, const std::vector<std::int64_t>& first) {
  std::sort(pairs.begin(), pairs.end(), [&](const StampPair& a, const StampPair& b) {
    return std::tie(first[a.first], a.first) < std::tie(first[b.first], b.first);
  });
}

}  // namespace

std::vector<StampPair> pair_equal_stamps(const std::vector<std::int64_t>& first, const std::vector<std::int64_t>& second) {
  std::map<std::int64_t, std::size_t> second_by_stamp;
  for (std::size_t j = 0; j < second.size(); ++j) second_by_stamp.emplace(second[j], j);  // keeps the first occurrence
  std::vector<StampPair> pairs;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const auto found = second_by_stamp.find(first[i]);
    if (found == second_by_stamp.end()) continue;
    pairs.push_back({i, found->second});
    second_by_stamp.erase(found);  // a repeated first stamp finds nothing now
  }
  sort_by_first_stamp(pairs, first);
  return pairs;
}

std::vector<StampPair> associate_stamps(const std::vector<std::int64_t>& first, const std::vector<std::int64_t>& second,
                                        std::int64_t max_difference_ns) {
  // associate.py: potential_matches = [(abs(a - b), a, b) ... if abs(a - b) < max_difference], sorted.
  const std::vector<std::size_t> second_order = order_by_stamp(second);
  std::vector<std::tuple<std::int64_t, std::int64_t, std::int64_t, std::size_t, std::size_t>> candidates;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const auto lower = std::upper_bound(second_order.begin(), second_order.end(), first[i] - max_difference_ns,
                                        [&](std::int64_t t, std::size_t j) { return t < second[j]; });
    for (auto it = lower; it != second_order.end() && second[*it] < first[i] + max_difference_ns; ++it) {
      const std::int64_t difference = first[i] > second[*it] ? first[i] - second[*it] : second[*it] - first[i];
      candidates.emplace_back(difference, first[i], second[*it], i, *it);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> first_used(first.size(), false), second_used(second.size(), false);
  std::vector<StampPair> pairs;
  for (const auto& [difference, a, b, i, j] : candidates) {
    if (first_used[i] || second_used[j]) continue;
    first_used[i] = second_used[j] = true;
    pairs.push_back({i, j});
  }
  sort_by_first_stamp(pairs, first);
  return pairs;
}

}  // namespace cairn::vslam
