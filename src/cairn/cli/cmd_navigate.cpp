// `cairn navigate BAG`: a ground vehicle's trajectory from a bag's IMU, wheel odometry and GNSS
// (navigation/navigation_run.hpp: GnssInertialOdometry, a fixed-lag smoother with IMU
// preintegration, the wheels' speed with the non-holonomic constraint, and GNSS fixes under the
// Cauchy kernel; docs/navigation.md). --withhold-gnss FROM,TO holds a stretch of fixes back and
// reports how far the dead reckoning (IMU + wheels) and the wheel odometry alone drift from them.
// This file parses flags and prints; the run and its outputs are the library's.

#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/core/so3.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/navigation/config.hpp"
#include "cairn/navigation/navigation_outputs.hpp"
#include "cairn/navigation/navigation_run.hpp"

namespace cairn::cli {
namespace {

struct NavigateFlags {
  std::string bag, imu_topic, wheel_topic, gnss_topic, config, out;
  std::vector<std::string> set;
  std::vector<double> imu_in_vehicle;  ///< x, y, z, yaw, pitch, roll (tf's static_transform_publisher order)
  std::vector<double> antenna_m;       ///< x, y, z in the vehicle frame
  std::vector<double> withhold_s;      ///< from, to: seconds after the IMU's first sample
  double until_s = 0.0;                ///< 0: the whole recording
  bool print_config = false, overwrite = false, quiet = false, no_gnss = false;
};

navigation::GnssInertialOdometryOptions navigate_options(const NavigateFlags& flags) {
  navigation::GnssInertialOdometryOptions options;
  checks::apply_configuration(navigation::configuration(), flags.config, flags.set, options);
  navigation::sync_gravity(options);
  if (!flags.imu_in_vehicle.empty()) {
    const std::vector<double>& v = flags.imu_in_vehicle;
    // R = Rz(yaw) Ry(pitch) Rx(roll), as tf's static_transform_publisher builds it.
    const core::SO3 R_vehicle_imu =
        core::SO3::exp(Vector3(0, 0, v[3])) * core::SO3::exp(Vector3(0, v[4], 0)) * core::SO3::exp(Vector3(v[5], 0, 0));
    options.T_imu_vehicle = core::SE3(R_vehicle_imu, Vector3(v[0], v[1], v[2])).inverse();
  }
  const Vector3 antenna_vehicle = flags.antenna_m.empty() ? Vector3::Zero() : Vector3(flags.antenna_m[0], flags.antenna_m[1], flags.antenna_m[2]);
  options.gnss.lever_arm_body_m = options.T_imu_vehicle * antenna_vehicle;
  if (std::string why; !options.is_valid(&why)) throw UsageError("invalid configuration: " + why);
  return options;
}

void print_summary(const NavigateFlags& flags, const navigation::NavigationRecording& recording, const navigation::NavigationRun& run) {
  const navigation::NavigationSummary& s = run.summary;
  const double duration_s = recording.imu.back().stamp.seconds() - recording.imu.front().stamp.seconds();
  std::printf("%s: %zu IMU samples, %zu wheel speeds, %zu GNSS fixes over %.1f s\n", flags.bag.c_str(), recording.imu.size(),
              recording.wheels.speeds.size(), recording.fixes.size(), duration_s);
  std::printf("%zu states (%zu without a wheel speed); %s start; solve %.2f s in all, slowest state %.1f ms\n", s.states,
              s.states_without_wheel, s.still_start ? "still" : "moving", s.solve_s, 1e3 * s.max_step_s);
  if (s.ok()) {
    std::printf("GNSS: aligned at %.1f s (yaw sigma %.2f deg, path spread %.1f m); %zu of %zu fixes used, %zu outliers, %zu late, "
                "%zu dropouts\n",
                s.alignment_time_s - run.start_s, s.alignment.yaw_sigma_rad * 180.0 / M_PI, s.alignment.spread_m, s.fixes_used,
                s.fixes_received, s.outliers, s.fixes_late, s.dropouts.size());
  } else if (flags.no_gnss) {
    std::printf("no GNSS (--no-gnss): the trajectory is in the IMU's start frame (z up, yaw 0)\n");
  } else {
    std::printf("GNSS: not aligned (%s): the trajectory stays in the IMU's start frame\n", s.message.c_str());
  }
  if (run.withheld) {
    const navigation::WithheldComparison& c = *run.withheld;
    std::printf("GNSS withheld %.1f-%.1f s (%zu fixes):\n", c.from_s - run.start_s, c.to_s - run.start_s, c.fixes.size());
    if (c.first_fix_back) {
      std::printf("  at the first fix back (%.1f s)  fused %.2f m", c.first_fix_back->time_s - run.start_s, c.first_fix_back->fused_m);
      if (c.first_fix_back->wheel_m) std::printf(", wheel odometry alone %.2f m", *c.first_fix_back->wheel_m);
      std::printf("\n");
    }
    std::printf("  RMS over the withheld fixes    fused %.2f m", c.fused_rms_m);
    if (c.wheel_rms_m) std::printf(", wheel odometry alone %.2f m", *c.wheel_rms_m);
    std::printf(" (horizontal)\n");
  } else if (!run.withheld_note.empty()) {
    std::printf("GNSS withheld: no comparison: %s\n", run.withheld_note.c_str());
  }
}

int run_navigate(const NavigateFlags& flags) {
  const navigation::GnssInertialOdometryOptions options = navigate_options(flags);
  if (flags.print_config) {
    std::fputs(navigation::configuration().yaml(options).c_str(), stdout);
    if (flags.bag.empty()) return 0;
  }
  if (flags.bag.empty()) throw UsageError("BAG is required");
  if (flags.out.empty()) throw UsageError("--out DIR is required");
  if (flags.no_gnss && (!flags.gnss_topic.empty() || !flags.withhold_s.empty() || !flags.antenna_m.empty())) {
    throw UsageError("--no-gnss leaves the fixes out: --gnss-topic, --antenna and --withhold-gnss need them");
  }
  std::optional<navigation::GnssWithholding> withholding;
  if (!flags.withhold_s.empty()) {
    if (!(flags.withhold_s[1] > flags.withhold_s[0])) throw UsageError("--withhold-gnss FROM,TO: TO must be after FROM");
    withholding = navigation::GnssWithholding{flags.withhold_s[0], flags.withhold_s[1]};
  }
  io::OutputDirectory out(flags.out, flags.overwrite);
  navigation::NavigationRecording recording =
      navigation::read_navigation_bag(flags.bag, flags.imu_topic, flags.wheel_topic, flags.gnss_topic, !flags.no_gnss);
  if (flags.until_s > 0.0) recording = navigation::first_seconds(recording, flags.until_s);
  const navigation::NavigationRun run = navigation::run_navigation(recording, options, withholding);
  const nlohmann::json inputs = {{"bag", flags.bag},
                                 {"imu_topic", flags.imu_topic},
                                 {"wheel_topic", flags.wheel_topic},
                                 {"gnss_topic", flags.gnss_topic},
                                 {"no_gnss", flags.no_gnss},
                                 {"imu_samples", recording.imu.size()},
                                 {"wheel_speeds", recording.wheels.speeds.size()},
                                 {"gnss_fixes", recording.fixes.size()},
                                 {"gnss_dropped_no_fix", recording.gnss_report.dropped_no_fix},
                                 {"gnss_dropped_not_finite", recording.gnss_report.dropped_not_finite},
                                 {"wheel_frame", recording.wheels.frame_id},
                                 {"vehicle_frame", recording.wheels.child_frame_id},
                                 {"imu_in_vehicle_xyz_ypr", flags.imu_in_vehicle},
                                 {"antenna_in_vehicle_m", flags.antenna_m},
                                 {"withhold_gnss_s", flags.withhold_s},
                                 {"until_s", flags.until_s}};
  const std::vector<std::string> names =
      navigation::write_navigation_outputs(out, run, options, inputs, navigation::configuration().json(options));
  out.commit();
  if (!flags.quiet) {
    print_summary(flags, recording, run);
    std::printf("wrote");
    for (std::size_t k = 0; k < names.size(); ++k) std::printf("%s %s", k == 0 ? "" : ",", names[k].c_str());
    std::printf(" to %s\n", flags.out.c_str());
  }
  return 0;
}

}  // namespace

Runner register_navigate(CLI::App& app) {
  auto flags = std::make_shared<NavigateFlags>();
  CLI::Option* bag = app.add_option("BAG", flags->bag,
                                    "A bag (ROS 1 .bag, .mcap, rosbag2 .db3 or folder) with sensor_msgs/Imu, nav_msgs/Odometry "
                                    "(the wheels) and sensor_msgs/NavSatFix")
                         ->required();
  app.add_option("--imu-topic", flags->imu_topic, "The sensor_msgs/Imu topic (default: the only one)");
  app.add_option("--wheel-topic", flags->wheel_topic, "The wheels' nav_msgs/Odometry topic (default: the only one)");
  app.add_option("--gnss-topic", flags->gnss_topic, "The sensor_msgs/NavSatFix topic (default: the only one)");
  app.add_flag("--no-gnss", flags->no_gnss, "IMU and wheel odometry alone: read no fixes (the trajectory stays in the IMU's start frame)");
  app.add_option("--imu-in-vehicle", flags->imu_in_vehicle,
                 "The IMU in the vehicle frame (the wheel odometry's child frame), as tf's static_transform_publisher takes it: "
                 "X,Y,Z,YAW,PITCH,ROLL in metres and radians (default: the same frame)")
      ->expected(6)
      ->delimiter(',')
      ->check(checks::finite());
  app.add_option("--antenna", flags->antenna_m, "The GNSS antenna in the vehicle frame, metres: X,Y,Z (default 0,0,0)")
      ->expected(3)
      ->delimiter(',')
      ->check(checks::finite());
  app.add_option("--withhold-gnss", flags->withhold_s,
                 "Hold back the fixes FROM,TO seconds after the IMU's first sample and report the dead reckoning's and the wheel "
                 "odometry's horizontal error against them")
      ->expected(2)
      ->delimiter(',')
      ->check(checks::non_negative());
  app.add_option("--until", flags->until_s, "Use the recording's first S seconds after the IMU's first sample (0 = all)")
      ->check(checks::non_negative());
  app.add_option("--config", flags->config, "YAML configuration (every key optional; --print-config lists them)");
  app.add_option("--set", flags->set, "Override one key: section.key=value (repeatable), after --config");
  app.add_flag_callback("--print-config", [flags, bag] { flags->print_config = true; bag->required(false); },
                        "Print the configuration in effect (YAML) and exit unless BAG is given");
  app.add_option("--out", flags->out, "Output directory: report.json, states.csv, trajectory.tum, navigation.png");
  app.add_flag("--overwrite", flags->overwrite, "Replace the files of a previous run in --out");
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  return [flags] { return run_navigate(*flags); };
}

}  // namespace cairn::cli
