#pragma once
/// \file
/// Ground truth of the events the mission scenarios (building-yard, outdoor-stretch,
/// kidnapping, long-absence, second-session) provoke, measured from the simulated run: which
/// region each stretch of scans was taken in and how many returns its scans had (segments.txt),
/// which scans revisit earlier ones (revisits.txt), the longest absence from the region the run
/// starts in, the kidnapping (kidnap.txt) and, for a second session, where it starts.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/sim/kidnap.hpp"
#include "cairn/sim/world_builders.hpp"

namespace cairn::sim {

struct RevisitOptions {
  /// Scan j revisits an earlier scan i when their ground-truth body positions are at most
  /// max_distance_m apart, metres (> 0) ...
  double max_distance_m = 1.0;
  /// ... and their times differ by at least min_separation_s, seconds (>= 0).
  double min_separation_s = 30.0;

  bool is_valid(std::string* why) const;
};

/// A maximal run of consecutive scans whose ground-truth positions lie in one region; a
/// kidnapping also ends a run.
struct ScanSegment {
  std::string region;
  std::size_t first_scan = 0;
  std::size_t last_scan = 0;
  double start_time_s = 0.0;
  double end_time_s = 0.0;
  /// Ground-truth path driven from the first to the last scan, metres.
  double path_length_m = 0.0;
  /// Scans with fewer returns (readings below max range) than the threshold.
  std::size_t few_return_scans = 0;
};

/// Scan `later` comes back to where scan `earlier` was taken: of the scans meeting
/// RevisitOptions, the nearest (the earliest among equally near ones).
struct Revisit {
  std::size_t later = 0;
  std::size_t earlier = 0;
  double distance_m = 0.0;
  /// |heading(later) - heading(earlier)| wrapped to [0, pi]: near pi when driving the other way.
  double heading_difference_rad = 0.0;
  double time_difference_s = 0.0;
  /// Ground-truth path driven between the two scans, metres.
  double path_between_m = 0.0;
};

/// The longest stretch the robot spends outside the region its first scan is in, between two
/// stays in it.
struct Absence {
  std::string region;
  /// Last scan in the region before leaving, first scan back in it.
  std::size_t left_scan = 0;
  std::size_t returned_scan = 0;
  double left_time_s = 0.0;
  double returned_time_s = 0.0;
  /// returned_time_s - left_time_s, and the path driven between the two scans.
  double duration_s = 0.0;
  double path_length_m = 0.0;
  /// The first scan from returned_scan on that revisits a scan taken at or before left_scan.
  std::optional<Revisit> first_revisit;
};

/// Where a second session starts, and the session it is to be localised against.
struct SessionStart {
  /// The scenario whose map the session is localised in (same world frame).
  std::string pairs_with;
  std::string place;
  core::SE2 T_world_start;
  /// Where the paired session starts (its first ground-truth pose).
  core::SE2 T_world_paired_start;
};

struct MissionTruth {
  std::vector<Region> regions;
  std::string outside_region;
  std::vector<Doorway> doors;
  /// Scans with fewer returns than this count as "few returns".
  int few_returns = 10;
  std::vector<ScanSegment> segments;
  std::vector<Revisit> revisits;
  RevisitOptions revisit_options;
  std::optional<Absence> absence;
  std::optional<KidnapEvent> kidnap;
  std::optional<SessionStart> session;
};

/// The per-scan ground truth the functions below read.
struct ScanTruth {
  std::vector<core::SE2> T_world_body;
  std::vector<double> times_s;
  /// Ground-truth path driven from the first sample to each scan, metres (a carry not counted).
  std::vector<double> path_m;
  /// Readings below max range, per scan.
  std::vector<int> returns;
};

/// The segments: consecutive scans grouped by world.region_at(position); `breaks` (increasing)
/// lists scans that start a new segment whatever their region (the first scan after a kidnap).
std::vector<ScanSegment> find_segments(const WorldWithRoute& world, const ScanTruth& scans, int few_returns,
                                       const std::vector<std::size_t>& breaks = {});

/// For every scan, its revisit of an earlier scan, if any, in scan order. O(n^2).
std::vector<Revisit> find_revisits(const ScanTruth& scans, const RevisitOptions& options);

/// The longest absence from the first segment's region, with its first revisit by `options`;
/// nullopt when the robot never leaves that region and comes back.
std::optional<Absence> find_absence(const std::vector<ScanSegment>& segments, const RevisitOptions& options,
                                    const ScanTruth& scans);

/// segments.txt: comment lines, then per segment
/// `first_scan last_scan start_time_s end_time_s path_length_m scans few_return_scans region`.
void write_segments_file(const std::string& path, const std::vector<ScanSegment>& segments, int few_returns,
                         const std::string& comment);
/// revisits.txt: comment lines, then per revisit
/// `later earlier distance_m heading_difference_deg time_difference_s path_between_m`.
void write_revisits_file(const std::string& path, const std::vector<Revisit>& revisits, const RevisitOptions& options,
                         const std::string& comment);

}  // namespace cairn::sim
