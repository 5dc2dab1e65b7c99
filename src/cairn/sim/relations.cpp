#include "cairn/sim/relations.hpp"

#include <cmath>
#include <sstream>

#include "cairn/core/assert.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/sim/carmen_log.hpp"
#include "cairn/sim/random.hpp"

namespace cairn::sim {

bool RelationsOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  if (!(short_interval_s > 0.0)) problems << "short_interval_s must be > 0; ";
  if (long_count < 0) problems << "long_count must be >= 0; ";
  if (!(long_min_separation_s >= 0.0)) problems << "long_min_separation_s must be >= 0; ";
  if (!(long_max_distance_m > 0.0)) problems << "long_max_distance_m must be > 0; ";
  if (!(long_max_heading_difference_rad > 0.0)) problems << "long_max_heading_difference_rad must be > 0; ";
  if (!(long_candidate_spacing_s > 0.0)) problems << "long_candidate_spacing_s must be > 0; ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

std::vector<Relation> make_relations(const std::vector<TrajectorySample>& truth,
                                     const std::vector<std::size_t>& scan_samples, const RelationsOptions& options,
                                     std::uint64_t seed) {
  CAIRN_ASSERT(options.is_valid(nullptr), "make_relations: invalid options (check is_valid first)");
  std::vector<Relation> relations;
  if (scan_samples.empty()) return relations;
  auto relation = [&](std::size_t a, std::size_t b) {
    const TrajectorySample& from = truth[scan_samples[a]];
    const TrajectorySample& to = truth[scan_samples[b]];
    return Relation{from.stamp, to.stamp, from.T_world_body.inverse() * to.T_world_body};
  };
  auto seconds_between = [&](std::size_t a, std::size_t b) {
    return static_cast<double>(truth[scan_samples[b]].stamp.nanoseconds() - truth[scan_samples[a]].stamp.nanoseconds()) *
           1e-9;
  };

  // Short chain.
  std::size_t current = 0;
  for (std::size_t k = 1; k < scan_samples.size(); ++k) {
    if (seconds_between(current, k) + 1e-9 >= options.short_interval_s) {
      relations.push_back(relation(current, k));
      current = k;
    }
  }

  // Long relations among scans sampled every long_candidate_spacing_s.
  std::vector<std::size_t> sampled = {0};
  for (std::size_t k = 1; k < scan_samples.size(); ++k) {
    if (seconds_between(sampled.back(), k) + 1e-9 >= options.long_candidate_spacing_s) sampled.push_back(k);
  }
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t b = 0; b < sampled.size(); ++b) {
    for (std::size_t a = 0; a < b; ++a) {
      if (seconds_between(sampled[a], sampled[b]) < options.long_min_separation_s) break;
      const core::SE2 delta = relation(sampled[a], sampled[b]).T_from_to;
      if (delta.translation().norm() <= options.long_max_distance_m &&
          std::abs(delta.angle()) <= options.long_max_heading_difference_rad) {
        pairs.emplace_back(sampled[a], sampled[b]);
      }
    }
  }
  // Partial Fisher-Yates shuffle: the first long_count entries are a uniform random subset.
  Random random(seed);
  const std::size_t take = std::min(pairs.size(), static_cast<std::size_t>(options.long_count));
  for (std::size_t i = 0; i < take; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(random.index(pairs.size() - i));
    std::swap(pairs[i], pairs[j]);
    relations.push_back(relation(pairs[i].first, pairs[i].second));
  }
  return relations;
}

void write_relations(const std::string& path, const std::vector<Relation>& relations) {
  io::write_output(path, [&](std::ostream& out) {
    std::string line;
    for (const auto& r : relations) {
      line.clear();
      line += format_carmen_time(r.from);
      line += ' ';
      line += format_carmen_time(r.to);
      line += ' ';
      io::append_number(line, r.T_from_to.x());
      line += ' ';
      io::append_number(line, r.T_from_to.y());
      line += " 0 0 0 ";
      io::append_number(line, r.T_from_to.angle());
      line += '\n';
      out << line;
    }
  });
}

}  // namespace cairn::sim
