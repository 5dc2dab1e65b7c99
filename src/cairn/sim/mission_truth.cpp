#include "cairn/sim/mission_truth.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>

#include "cairn/core/assert.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::sim {
namespace {

/// The nearest scan i in [0, last_earlier] meeting `options` for scan j (the earliest among
/// equally near ones); nullopt when none does.
std::optional<Revisit> nearest_earlier(const ScanTruth& scans, std::size_t j, std::size_t last_earlier,
                                       const RevisitOptions& options) {
  std::optional<Revisit> best;
  for (std::size_t i = 0; i <= last_earlier && i < j; ++i) {
    const double dt = scans.times_s[j] - scans.times_s[i];
    if (dt < options.min_separation_s) break;  // times increase: later i are closer still
    const double distance = (scans.T_world_body[j].translation() - scans.T_world_body[i].translation()).norm();
    if (distance > options.max_distance_m || (best && distance >= best->distance_m)) continue;
    best = Revisit{j,
                   i,
                   distance,
                   std::abs(core::wrap_angle(scans.T_world_body[j].angle() - scans.T_world_body[i].angle())),
                   dt,
                   scans.path_m[j] - scans.path_m[i]};
  }
  return best;
}

}  // namespace

bool RevisitOptions::is_valid(std::string* why) const {
  std::string problems;
  if (!(max_distance_m > 0.0 && std::isfinite(max_distance_m))) problems += "max_distance_m must be > 0; ";
  if (!(min_separation_s >= 0.0 && std::isfinite(min_separation_s))) problems += "min_separation_s must be >= 0; ";
  if (why != nullptr) *why = problems.empty() ? "" : problems.substr(0, problems.size() - 2);
  return problems.empty();
}

std::vector<ScanSegment> find_segments(const WorldWithRoute& world, const ScanTruth& scans, int few_returns,
                                       const std::vector<std::size_t>& breaks) {
  std::vector<ScanSegment> segments;
  for (std::size_t k = 0; k < scans.T_world_body.size(); ++k) {
    const std::string region = world.region_at(scans.T_world_body[k].translation());
    const bool starts_new = segments.empty() || segments.back().region != region ||
                            std::binary_search(breaks.begin(), breaks.end(), k);
    if (starts_new) segments.push_back({region, k, k, scans.times_s[k], scans.times_s[k], 0.0, 0});
    ScanSegment& segment = segments.back();
    segment.last_scan = k;
    segment.end_time_s = scans.times_s[k];
    segment.path_length_m = scans.path_m[k] - scans.path_m[segment.first_scan];
    segment.few_return_scans += scans.returns[k] < few_returns ? 1 : 0;
  }
  return segments;
}

std::vector<Revisit> find_revisits(const ScanTruth& scans, const RevisitOptions& options) {
  std::vector<Revisit> revisits;
  for (std::size_t j = 0; j < scans.T_world_body.size(); ++j) {
    if (auto revisit = nearest_earlier(scans, j, j, options)) revisits.push_back(*revisit);
  }
  return revisits;
}

std::optional<Absence> find_absence(const std::vector<ScanSegment>& segments, const RevisitOptions& options,
                                    const ScanTruth& scans) {
  if (segments.empty()) return std::nullopt;
  const std::string& home = segments.front().region;
  std::optional<Absence> longest;
  std::size_t last_home = 0;  // index into segments
  for (std::size_t k = 1; k < segments.size(); ++k) {
    if (segments[k].region != home) continue;
    if (k > last_home + 1) {  // something else in between
      Absence absence;
      absence.region = home;
      absence.left_scan = segments[last_home].last_scan;
      absence.returned_scan = segments[k].first_scan;
      absence.left_time_s = scans.times_s[absence.left_scan];
      absence.returned_time_s = scans.times_s[absence.returned_scan];
      absence.duration_s = absence.returned_time_s - absence.left_time_s;
      absence.path_length_m = scans.path_m[absence.returned_scan] - scans.path_m[absence.left_scan];
      if (!longest || absence.duration_s > longest->duration_s) longest = absence;
    }
    last_home = k;
  }
  if (longest) {
    for (std::size_t j = longest->returned_scan; j < scans.T_world_body.size() && !longest->first_revisit; ++j) {
      longest->first_revisit = nearest_earlier(scans, j, longest->left_scan, options);
    }
  }
  return longest;
}

void write_segments_file(const std::string& path, const std::vector<ScanSegment>& segments, int few_returns,
                         const std::string& comment) {
  io::write_output(path, [&](std::ostream& out) {
    out << "# " << comment << '\n'
        << "# runs of consecutive scans (0-based FLASER indices = lines of ground_truth.tum) taken in one region;\n"
        << "# few_return_scans: scans with fewer than " << few_returns << " readings below max range\n"
        << "# first_scan last_scan start_time_s end_time_s path_length_m scans few_return_scans region\n";
    char text[160];
    for (const auto& s : segments) {
      std::snprintf(text, sizeof text, "%zu %zu %.6f %.6f %.3f %zu %zu ", s.first_scan, s.last_scan, s.start_time_s,
                    s.end_time_s, s.path_length_m, s.last_scan - s.first_scan + 1, s.few_return_scans);
      out << text << s.region << '\n';
    }
  });
}

void write_revisits_file(const std::string& path, const std::vector<Revisit>& revisits, const RevisitOptions& options,
                         const std::string& comment) {
  io::write_output(path, [&](std::ostream& out) {
    std::string distance;
    io::append_number(distance, options.max_distance_m);
    std::string separation;
    io::append_number(separation, options.min_separation_s);
    out << "# " << comment << '\n'
        << "# for every scan j, the nearest earlier scan i (the earliest if several) whose ground-truth position is at\n"
        << "# most " << distance << " m away and whose time is at least " << separation
        << " s earlier; scans are 0-based FLASER indices\n"
        << "# j i distance_m heading_difference_deg (0: same direction, 180: reverse) time_difference_s path_between_m\n";
    char text[160];
    for (const auto& r : revisits) {
      std::snprintf(text, sizeof text, "%zu %zu %.3f %.1f %.1f %.1f\n", r.later, r.earlier, r.distance_m,
                    r.heading_difference_rad * 180.0 / std::numbers::pi, r.time_difference_s, r.path_between_m);
      out << text;
    }
  });
}

}  // namespace cairn::sim
