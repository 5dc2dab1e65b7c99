#include "cairn/navigation/navigation_run.hpp"

#include <stdexcept>

#include "cairn/inertial/imu_csv.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::navigation {

NavigationRecording read_navigation_bag(const std::string& bag_path, const std::string& imu_topic,
                                        const std::string& wheel_topic, const std::string& gnss_topic, bool with_gnss) {
  NavigationRecording r;
  r.imu = inertial::read_imu_topic(bag_path, imu_topic);
  if (r.imu.empty()) throw io::ParseError(bag_path, 0, "the IMU topic " + (imu_topic.empty() ? std::string("(the only one)") : imu_topic) + " has no sample");
  r.wheels = read_wheel_odometry_bag(bag_path, wheel_topic);
  if (with_gnss) r.fixes = gnss::read_gnss_bag(bag_path, gnss_topic, &r.gnss_report);
  return r;
}

NavigationRecording first_seconds(const NavigationRecording& recording, double seconds) {
  NavigationRecording r;
  if (recording.imu.empty()) return r;
  const core::Timestamp end = core::Timestamp::from_seconds(recording.imu.front().stamp.seconds() + seconds);
  for (const inertial::ImuSample& s : recording.imu) {
    if (!(end < s.stamp)) r.imu.push_back(s);
  }
  r.wheels.frame_id = recording.wheels.frame_id;
  r.wheels.child_frame_id = recording.wheels.child_frame_id;
  for (std::size_t k = 0; k < recording.wheels.speeds.size(); ++k) {
    if (end < recording.wheels.speeds[k].stamp) break;
    r.wheels.speeds.push_back(recording.wheels.speeds[k]);
    if (k < recording.wheels.poses.size()) {
      r.wheels.poses.stamps.push_back(recording.wheels.poses.stamps[k]);
      r.wheels.poses.poses.push_back(recording.wheels.poses.poses[k]);
    }
  }
  for (const gnss::GnssFix& f : recording.fixes) {
    if (!(end < f.stamp)) r.fixes.push_back(f);
  }
  r.gnss_report = recording.gnss_report;
  return r;
}

NavigationRun run_navigation(const NavigationRecording& recording, const GnssInertialOdometryOptions& options,
                             const std::optional<GnssWithholding>& withholding) {
  if (withholding && !(withholding->to_s > withholding->from_s)) {
    throw std::invalid_argument("the GNSS withheld must end after it starts");
  }
  NavigationRun run;
  run.start_s = recording.imu.empty() ? 0.0 : recording.imu.front().stamp.seconds();
  const double from_s = withholding ? run.start_s + withholding->from_s : 0.0;
  const double to_s = withholding ? run.start_s + withholding->to_s : 0.0;
  if (withholding) run.split = withhold_fixes(recording.fixes, from_s, to_s);
  GnssInertialOdometry odometry(options);
  run_in_time_order(odometry, recording.imu, recording.wheels.speeds, run.split ? run.split->kept : recording.fixes);
  run.states = odometry.states();
  run.fix_results = odometry.fix_results();
  run.summary = odometry.summary();
  if (!withholding) return run;
  if (run.split->withheld.empty()) {
    run.withheld_note = "no fix lies in the withheld interval";
  } else if (!run.summary.enu_origin || run.summary.status != NavigationStatus::kOk) {
    run.withheld_note = "the GNSS never aligned the estimate, so it has no ENU position to compare";
  } else {
    run.withheld = compare_with_withheld(run.states, *run.split, from_s, to_s, *run.summary.enu_origin, options.T_imu_vehicle,
                                         recording.wheels.poses);
  }
  return run;
}

}  // namespace cairn::navigation
