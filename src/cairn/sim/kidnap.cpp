#include "cairn/sim/kidnap.hpp"

#include <cmath>
#include <ostream>

#include "cairn/core/assert.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/sim/carmen_log.hpp"

namespace cairn::sim {

std::vector<Vector2> route_after_drop(const OfficeFloor& floor, std::string_view place, int rings) {
  const auto center = floor.place_center(place);
  CAIRN_ASSERT(center.has_value(), "route_after_drop: unknown place (check is_valid first)");
  CAIRN_ASSERT(rings >= 1, "route_after_drop: at least one ring");
  const Vector2 exit = floor.place_exit(place);
  std::vector<Vector2> route = {*center, exit};
  const std::vector<Vector2> ring = floor.ring_from(exit, true);
  for (int i = 0; i < rings; ++i) route.insert(route.end(), ring.begin(), ring.end());
  return route;
}

std::vector<TrajectorySample> splice_kidnap(const std::vector<TrajectorySample>& before,
                                            const std::vector<TrajectorySample>& after, double time_s,
                                            std::size_t* first_sample_after) {
  CAIRN_ASSERT(before.size() >= 2 && after.size() >= 2, "splice_kidnap: both parts need two samples");
  const std::int64_t period_ns = before[1].stamp.nanoseconds() - before[0].stamp.nanoseconds();
  CAIRN_ASSERT(after[1].stamp.nanoseconds() - after[0].stamp.nanoseconds() == period_ns,
               "splice_kidnap: both parts need the same sample period");
  const std::int64_t pick_up_ns = before.front().stamp.nanoseconds() + std::llround(time_s * 1e9);
  std::vector<TrajectorySample> truth;
  for (const auto& sample : before) {
    if (sample.stamp.nanoseconds() > pick_up_ns) break;
    truth.push_back(sample);
  }
  CAIRN_ASSERT(truth.size() < before.size(), "splice_kidnap: the kidnap time lies after the first part");
  if (first_sample_after != nullptr) *first_sample_after = truth.size();
  const std::int64_t offset_ns = truth.back().stamp.nanoseconds() + period_ns - after.front().stamp.nanoseconds();
  for (TrajectorySample sample : after) {
    sample.stamp = core::Timestamp::from_nanoseconds(sample.stamp.nanoseconds() + offset_ns);
    truth.push_back(sample);
  }
  return truth;
}

void write_kidnap_file(const std::string& path, const KidnapEvent& event, const std::string& comment) {
  io::write_output(path, [&](std::ostream& out) {
    auto number = [](double value) {
      std::string text;
      io::append_number(text, value);
      return text;
    };
    auto pose = [&](const core::SE2& T) { return number(T.x()) + ' ' + number(T.y()) + ' ' + number(T.angle()); };
    const core::SE2 jump = event.T_world_body_before.inverse() * event.T_world_body_after;
    out << "# " << comment << '\n'
        << "# the robot is picked up after the first time and put down before the second: the ground truth\n"
        << "# (T_world_body) jumps, the odometry (T_odom_body: ODOM, FLASER odometry fields, odometry.tum) does not\n"
        << "# times as the FLASER ipc_timestamps; scans are 0-based indices of FLASER records (= lines of\n"
        << "# ground_truth.tum); poses are x_m y_m theta_rad\n"
        << "time_before_s " << format_carmen_time(event.stamp_before) << '\n'
        << "time_after_s " << format_carmen_time(event.stamp_after) << '\n'
        << "T_world_body_before " << pose(event.T_world_body_before) << '\n'
        << "T_world_body_after " << pose(event.T_world_body_after) << '\n'
        << "T_odom_body_before " << pose(event.T_odom_body_before) << '\n'
        << "T_odom_body_after " << pose(event.T_odom_body_after) << '\n'
        << "last_scan_before " << event.last_scan_before << '\n'
        << "first_scan_after " << event.first_scan_after << '\n'
        << "jump_m " << number(jump.translation().norm()) << '\n'
        << "jump_heading_rad " << number(jump.angle()) << '\n';
  });
}

}  // namespace cairn::sim
