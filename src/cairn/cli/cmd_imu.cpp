// `cairn imu DATA`: an IMU recording examined as people who calibrate IMUs do (allan_variance_ros,
// imu_utils): rates, gaps and saturation; static initialisation; the Allan deviation with its noise
// fits; and, given --groundtruth, the preintegration check over windows against the ground truth's
// states (inertial/imu_analysis.hpp). Prints a summary, --json the whole report, --out DIR the
// report and pictures.

#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>

#include "cairn/bag/bag.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/inertial/euroc_files.hpp"
#include "cairn/inertial/imu_analysis.hpp"
#include "cairn/inertial/imu_analysis_outputs.hpp"
#include "cairn/inertial/imu_csv.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::cli {
namespace {

namespace fs = std::filesystem;

struct ImuFlags {
  std::string data, topic, calibration, ground_truth, poses, poses_format, out;
  double window_s = 1.0, static_window_s = 2.0, time_offset_s = 0.0, init_window_s = 2.0;
  double gyro_saturation_deg_s = 0.0, accel_saturation_g = 0.0;
  int stride = 1;
  bool no_allan = false, json = false, overwrite = false, quiet = false;
};

/// The noise model: --calibration, else the sensor.yaml of an EuRoC imu0 folder the data is in
/// (or is), else EuRoC's ADIS16448 values (ImuNoise's defaults), saying which.
inertial::ImuNoise noise_of(const ImuFlags& flags, std::string& source) {
  fs::path yaml = flags.calibration;
  if (yaml.empty()) {
    const fs::path data(flags.data);
    for (const fs::path& candidate : {data / "sensor.yaml", data / "imu0" / "sensor.yaml", data / "mav0" / "imu0" / "sensor.yaml",
                                      data.parent_path() / "sensor.yaml"}) {
      std::error_code ec;
      if (fs::is_regular_file(candidate, ec)) {
        yaml = candidate;
        break;
      }
    }
  }
  if (yaml.empty()) {
    source = "EuRoC's ADIS16448 values (no --calibration and no sensor.yaml beside the data)";
    return inertial::ImuNoise{};
  }
  source = yaml.string();
  return inertial::read_euroc_imu_calibration(yaml).noise;
}

void print_summary(const ImuFlags& flags, const inertial::ImuAnalysis& a, const std::string& noise_source) {
  const inertial::ImuDataReport& d = a.data;
  std::printf("%s: %zu samples over %.1f s, %.1f Hz (median step %.3f ms, max %.3f ms), %zu gaps, "
              "%zu gyro / %zu accel samples saturated\n",
              flags.data.c_str(), d.samples, d.duration_s, d.median_rate_hz, 1e3 * d.median_dt_s, 1e3 * d.max_dt_s,
              d.gaps.size(), d.gyro_saturated_samples, d.accel_saturated_samples);
  const inertial::StaticInitialization& s = a.initialization;
  if (s.ok) {
    const Vector3 rpy = s.R_world_body.to_rpy() * 180.0 / M_PI;
    std::printf("static initialisation (%.1f s, %d samples): gyro bias %.5f %.5f %.5f rad/s, roll %.2f deg, pitch %.2f deg, "
                "accelerometer bias along gravity %.4f m/s^2\n",
                s.end_s - s.start_s, s.samples, s.gyro_bias_rad_s.x(), s.gyro_bias_rad_s.y(), s.gyro_bias_rad_s.z(), rpy.x(),
                rpy.y(), s.accel_bias_along_gravity_mps2);
  } else {
    std::printf("static initialisation: not possible: %s\n", s.message.c_str());
  }
  if (a.initialization_vs_truth) {
    std::printf("  against the ground truth: gyro bias off by %.5f rad/s, gravity direction off by %.3f deg\n",
                a.initialization_vs_truth->gyro_bias_error_rad_s, a.initialization_vs_truth->gravity_angle_error_deg);
  }
  if (a.allan) {
    const char* axes = "xyz";
    for (int k = 0; k < 3; ++k) {
      const inertial::AllanFit& g = a.allan->gyro_fit[static_cast<std::size_t>(k)];
      const inertial::AllanFit& f = a.allan->accel_fit[static_cast<std::size_t>(k)];
      std::printf("Allan %c: gyro N %.3g rad/s/sqrt(Hz), B %.3g rad/s; accel N %.3g m/s^2/sqrt(Hz), B %.3g m/s^2%s\n", axes[k],
                  g.white_noise_density, g.bias_instability, f.white_noise_density, f.bias_instability,
                  d.duration_s < 600.0 ? " (static recordings only; under 10 min the long-term terms are unreliable)" : " (static recordings only)");
    }
  }
  if (a.check) {
    const inertial::PreintegrationCheck& c = *a.check;
    std::printf("preintegration over %zu windows of %.2f s (noise: %s):\n", c.windows.size(), flags.window_s,
                noise_source.c_str());
    std::printf("  rotation error   median %.4f deg   p90 %.4f deg\n", c.rotation_deg.median, c.rotation_deg.p90);
    std::printf("  velocity error   median %.4f m/s   p90 %.4f m/s\n", c.velocity_mps.median, c.velocity_mps.p90);
    std::printf("  position error   median %.4f m     p90 %.4f m\n", c.position_m.median, c.position_m.p90);
    std::printf("  NEES (9 dof)     median %.2f       mean %.2f (9 for a consistent model)\n", c.nees.median, c.nees.mean);
  }
  if (a.moving_initialization) {
    const inertial::MovingInitializationCheck& m = *a.moving_initialization;
    std::size_t ok = 0;
    for (const inertial::MovingInitializationWindow& w : m.windows) ok += w.ok ? 1 : 0;
    std::printf("initialisation while moving (from the ground truth's poses), %zu of %zu windows initialised, %d still ones skipped:\n", ok,
                m.windows.size(), m.windows_still);
    std::printf("  gravity error    median %.3f deg   max %.3f deg\n", m.gravity_deg.median, m.gravity_deg.max);
    std::printf("  gyro bias error  median %.2e rad/s max %.2e rad/s\n", m.gyro_bias_rad_s.median, m.gyro_bias_rad_s.max);
    std::printf("  accel bias error median %.3f m/s^2 max %.3f m/s^2\n", m.accel_bias_mps2.median, m.accel_bias_mps2.max);
  }
}

int run_imu(const ImuFlags& flags) {
  inertial::ImuAnalysisOptions options;
  options.input.time_offset_s = flags.time_offset_s;
  options.input.gyro_saturation_rad_s = flags.gyro_saturation_deg_s * M_PI / 180.0;
  options.input.accel_saturation_mps2 = flags.accel_saturation_g * inertial::kStandardGravity;
  options.initialization.window_s = flags.static_window_s;
  options.allan = !flags.no_allan;
  options.check.window_s = flags.window_s;
  options.check.stride = flags.stride;
  options.moving_initialization = flags.init_window_s > 0.0;
  if (options.moving_initialization) options.moving.window_s = flags.init_window_s;
  std::string noise_source;
  options.check.noise = noise_of(flags, noise_source);
  if (std::string why; !options.is_valid(&why)) throw UsageError(why);
  if (!flags.topic.empty() && !bag::is_bag(flags.data)) throw UsageError("--topic goes with a bag; " + flags.data + " is not one");
  std::optional<io::OutputDirectory> out;
  if (!flags.out.empty()) out.emplace(flags.out, flags.overwrite);

  const std::vector<inertial::ImuSample> raw =
      flags.topic.empty() ? inertial::read_imu_file(flags.data) : inertial::read_imu_topic(flags.data, flags.topic);
  const std::vector<inertial::ImuSample> samples = inertial::apply_imu_input(raw, options.input);
  std::vector<inertial::GroundTruthState> states;
  if (!flags.ground_truth.empty()) states = inertial::read_euroc_ground_truth(flags.ground_truth);
  io::Trajectory poses;
  if (!flags.poses.empty()) {
    if (flags.ground_truth.empty()) throw UsageError("--poses refines --groundtruth's poses: give --groundtruth too");
    poses = read_trajectory(flags.poses, resolve_format(flags.poses, flags.poses_format, "--poses-format"), "", nullptr);
  }
  const inertial::ImuAnalysis analysis = inertial::analyse_imu(samples, states, poses, options);

  if (flags.json) {
    nlohmann::json report = inertial::to_json(analysis);
    report["noise_source"] = noise_source;
    std::printf("%s\n", io::json_text(report).c_str());
  } else if (!flags.quiet) {
    print_summary(flags, analysis, noise_source);
  }
  if (out) {
    const nlohmann::json inputs = {{"data", flags.data}, {"topic", flags.topic}, {"noise_source", noise_source},
                                   {"ground_truth", flags.ground_truth}, {"poses", flags.poses},
                                   {"window_s", flags.window_s}, {"stride", flags.stride}};
    inertial::write_imu_analysis_outputs(*out, analysis, inputs);
    out->commit();
  }
  return 0;
}

}  // namespace

Runner register_imu(CLI::App& app) {
  auto flags = std::make_shared<ImuFlags>();
  app.add_option("DATA", flags->data, "IMU recording: EuRoC mav0/ or imu0/ folder or data.csv, a plain IMU CSV (docs/formats.md), or a bag")
      ->required();
  app.add_option("--topic", flags->topic, "Bag input: the sensor_msgs/Imu topic (default: the only one)");
  app.add_option("--calibration", flags->calibration,
                 "Noise model: an EuRoC / Kalibr sensor.yaml (default: the one beside the data, else EuRoC's ADIS16448)");
  app.add_option("--groundtruth", flags->ground_truth,
                 "State ground truth with velocities and biases (EuRoC state_groundtruth_estimate0/data.csv layout): "
                 "the preintegration check runs over its states");
  app.add_option("--poses", flags->poses, "Poses for the check instead of --groundtruth's (e.g. the Vicon TUM file), interpolated");
  app.add_option("--poses-format", flags->poses_format, "tum, euroc or kitti (default: from the file)");
  app.add_option("--window", flags->window_s, "Preintegration window, seconds")->check(checks::in_range(0.001, 1e4))->capture_default_str();
  app.add_option("--stride", flags->stride, "Start a window at every Nth ground-truth state")->check(checks::count(1000000))->capture_default_str();
  app.add_option("--init-window", flags->init_window_s,
                 "With --groundtruth: the initialisation while moving (ORB-SLAM3's inertial-only MAP from the ground truth's poses) "
                 "on windows of S seconds, one every 10 s (0: off)")
      ->check(checks::in_range(0.0, 1e4))
      ->capture_default_str();
  app.add_option("--static-window", flags->static_window_s, "Static initialisation over the first S seconds")
      ->check(checks::in_range(0.01, 1e4))->capture_default_str();
  app.add_option("--time-offset", flags->time_offset_s, "Seconds added to every IMU stamp")
      ->check(checks::in_range(-inertial::kMaxAbsTimeOffsetS, inertial::kMaxAbsTimeOffsetS))
      ->capture_default_str();
  app.add_option("--gyro-saturation", flags->gyro_saturation_deg_s, "Gyro range, deg/s (0: guess from repeated extremes)")
      ->check(checks::in_range(0.0, 1e6));
  app.add_option("--accel-saturation", flags->accel_saturation_g, "Accelerometer range, g (0: guess)")->check(checks::in_range(0.0, 1e4));
  app.add_flag("--no-allan", flags->no_allan, "Skip the Allan deviation (it suits a static recording)");
  app.add_flag("--json", flags->json, "Print the whole report as JSON instead of the summary");
  app.add_option("--out", flags->out, "Output directory: report.json, allan.png, preintegration.png");
  app.add_flag("--overwrite", flags->overwrite, "Replace the files of a previous run in --out");
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  return [flags] { return run_imu(*flags); };
}

}  // namespace cairn::cli
