#pragma once
/// \file
/// Kidnapping: the robot is picked up and put down elsewhere. Between two ground-truth samples
/// the true pose jumps to another room, while the wheels do not turn, so the odometry shows no
/// motion across the jump (simulate_odometry's carried samples) and goes on from where it was:
/// nothing in ODOM or in FLASER's odometry fields tells the SLAM system what happened; only the
/// scans do. After the drop the robot leaves the room and drives through places it mapped before.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/time.hpp"
#include "cairn/sim/office_floor.hpp"
#include "cairn/sim/trajectory.hpp"

namespace cairn::sim {

struct KidnapOptions {
  /// When the robot is picked up, seconds after the first sample (> 0 and before the office
  /// laps end). The jump happens between the last sample at or before it and the next one.
  double time_s = 55.0;
  /// Where it is put down: the centre of a place of the office (OfficeFloor::place_names), at
  /// least kMinimumJumpM from where it was picked up.
  std::string drop_place = "top-room-0";
  /// Its heading when put down, radians (0 = +x, east).
  double drop_heading_rad = 0.0;
  /// How many times it then drives round the ring corridor (1-5). A merge of the segment started
  /// after the drop needs evidence along a long stretch of mapped corridor (slam2d's
  /// merge_min_spread_m); one lap gives some drop places too little of it.
  int rings_after = 1;

  /// The smallest distance between pick-up and drop the validation accepts, metres.
  static constexpr double kMinimumJumpM = 3.0;
};

/// The route after the drop: from the place's centre out of its door onto the ring corridor,
/// `rings` times round it counter-clockwise and back to the door. Preconditions:
/// floor.place_center(place), rings >= 1.
std::vector<Vector2> route_after_drop(const OfficeFloor& floor, std::string_view place, int rings = 1);

/// `before` up to and including its last sample at most `time_s` after its first, then every
/// sample of `after`, re-stamped to follow on one sample period later, one after another.
/// Writes the index of the first sample after the jump to `first_sample_after`.
/// Preconditions: both have >= 2 samples with the same period; time_s lies inside `before`.
std::vector<TrajectorySample> splice_kidnap(const std::vector<TrajectorySample>& before,
                                            const std::vector<TrajectorySample>& after, double time_s,
                                            std::size_t* first_sample_after);

/// What happened, from the simulated data (written to kidnap.txt and the manifest).
struct KidnapEvent {
  /// Ground-truth sample indices and scan indices on either side of the jump.
  std::size_t last_sample_before = 0;
  std::size_t first_sample_after = 0;
  std::size_t last_scan_before = 0;
  std::size_t first_scan_after = 0;
  core::Timestamp stamp_before;
  core::Timestamp stamp_after;
  core::SE2 T_world_body_before;
  core::SE2 T_world_body_after;
  /// Dead reckoning at both samples: the same pose (the wheels did not turn).
  core::SE2 T_odom_body_before;
  core::SE2 T_odom_body_after;
};

/// Writes kidnap.txt: comment lines, then one "key values" line each: time_before_s,
/// time_after_s, T_world_body_before x y theta, T_world_body_after x y theta,
/// T_odom_body_before x y theta, T_odom_body_after x y theta, last_scan_before, first_scan_after,
/// jump_m, jump_heading_rad. Throws io::ParseError when the file cannot be written.
void write_kidnap_file(const std::string& path, const KidnapEvent& event, const std::string& comment);

}  // namespace cairn::sim
