// `cairn landmarks DIR --method ekf|graph --association known|nn|jcbb --out OUT`: landmark SLAM
// (EKF-SLAM or graph SLAM) on a `cairn simulate landmarks --out DIR` directory. The pipeline is
// cairn::landmarks (see docs/landmark-slam.md); this file parses flags and prints.

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <numbers>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/landmarks/clutter.hpp"
#include "cairn/landmarks/landmark_run.hpp"
#include "cairn/landmarks/landmark_slam.hpp"
#include "cairn/landmarks/outputs.hpp"

namespace cairn::cli {
namespace {

struct LandmarksFlags {
  std::string log;
  std::string out;
  std::string method = "ekf";
  std::string association = "known";
  double spurious_fraction = 0.0;
  std::uint64_t clutter_seed = 1;
  double odometry_inflation = 1.0;
  double gate_probability = 0.99;
  int nees_checkpoints = 8;
  int graph_solve_every = 100;
  bool quiet = false;
  bool overwrite = false;
};

int landmarks_command(const LandmarksFlags& flags) {
  landmarks::LandmarkSlamOptions options;
  options.method = *landmarks::method_from_name(flags.method);
  options.association = *landmarks::association_from_name(flags.association);
  options.odometry.inflation = flags.odometry_inflation;
  options.gating.gate_probability = flags.gate_probability;
  options.nees_checkpoints = flags.nees_checkpoints;
  options.graph_solve_every_steps = flags.graph_solve_every;
  options.should_stop = stop_on_signal();
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid options: " + why);
  landmarks::ClutterOptions clutter;
  clutter.spurious_fraction = flags.spurious_fraction;
  clutter.seed = flags.clutter_seed;
  if (!clutter.is_valid(&why)) throw std::invalid_argument("invalid --spurious-fraction: " + why);

  // Refuse a directory of another run before the work; files appear together at the end.
  io::OutputDirectory directory(flags.out, flags.overwrite);
  landmarks::LandmarkRun run = landmarks::read_landmark_run(flags.log);
  const std::size_t added = landmarks::add_spurious_observations(&run.observations, clutter);
  const landmarks::LandmarkSlamResult result = landmarks::run_landmark_slam(run, options);

  landmarks::write_trajectory_tum(directory.staging_path("trajectory.tum"), result.trajectory);
  landmarks::write_landmark_estimates_csv(directory.staging_path("landmarks.csv"), result.landmarks);
  landmarks::write_report_json(directory.staging_path("report.json"), result.report);
  landmarks::write_landmarks_png(directory.staging_path("landmarks.png"), run, result);
  directory.commit();
  if (result.report.interrupted) {
    std::fprintf(stderr, "cairn landmarks: interrupted after step %zu of %zu: wrote the result so far to %s\n",
                 result.report.steps, result.report.steps_in_run, flags.out.c_str());
    return interrupted_exit_status();
  }

  if (flags.quiet) return 0;
  const landmarks::LandmarkSlamReport& r = result.report;
  const landmarks::AssociationCounts& a = r.association_counts;
  std::printf("%s SLAM, %s association: %zu steps, %zu landmarks, %zu observations (%zu spurious added)\n",
              r.method.c_str(), r.association.c_str(), r.steps, r.landmarks, a.observations, added);
  if (std::isfinite(r.ate_rmse_m)) {
    std::printf("ATE (no alignment) %.4f m RMSE, %.4f m max; final pose %.4f m / %.3f deg; landmarks %.4f m RMSE\n",
                r.ate_rmse_m, r.ate_max_m, r.final_position_error_m, r.final_heading_error_rad * 180.0 / std::numbers::pi,
                r.landmark_rmse_m);
  }
  std::printf("associations: %zu correct, %zu wrong (%zu spurious accepted), %zu spurious rejected, "
              "%zu invalid rejected, %zu landmarks created (%zu duplicates, %zu from clutter)\n",
              a.paired_correct, a.paired_wrong, a.spurious_paired, a.spurious_rejected, a.rejected_invalid,
              a.landmarks_created, a.landmarks_duplicated, a.landmarks_from_spurious);
  for (const landmarks::NeesPoint& p : r.nees) {
    std::printf("  NEES at t = %7.1f s: pose %8.2f (chi2(3) 95%% band 0.22..9.35), landmarks mean %8.2f over %zu\n",
                p.time_s, p.pose_nees, p.landmark_nees_mean, p.landmarks_evaluated);
  }
  std::printf("time: total %.3f s", r.total_time_s);
  if (r.ekf_time_s > 0) std::printf(", EKF %.3f s (%.1f us per step mean)", r.ekf_time_s, r.ekf_mean_step_s * 1e6);
  if (r.graph_time_s > 0) {
    std::printf(", graph %.3f s over %zu solves (last %.3f s, %s)", r.graph_time_s, r.graph_solves, r.graph_final_solve_s,
                r.graph_summary.message.c_str());
  }
  std::printf("\nwrote trajectory.tum, landmarks.csv, report.json, landmarks.png to %s\n", flags.out.c_str());
  return 0;
}

}  // namespace

Runner register_landmarks(CLI::App& app) {
  auto flags = std::make_shared<LandmarksFlags>();
  app.add_option("LOG", flags->log,
                 "Directory written by `cairn simulate landmarks --out DIR` (log.clf, landmark_observations.csv; "
                 "landmarks.csv and ground_truth.tum for errors and NEES)")
      ->required();
  app.add_option("--out", flags->out, "Output directory: trajectory.tum, landmarks.csv, report.json, landmarks.png")
      ->required();
  app.add_flag("--overwrite", flags->overwrite,
               "Write into an --out directory that already holds files (those of the same names are replaced)");
  app.add_option("--method", flags->method, "ekf (EKF-SLAM) or graph (graph SLAM, Levenberg-Marquardt)")
      ->check(CLI::IsMember({"ekf", "graph"}))
      ->capture_default_str();
  app.add_option("--association", flags->association,
                 "known (the sensor's ids), nn (nearest neighbour, chi^2 gate) or jcbb (joint compatibility B&B)")
      ->check(CLI::IsMember({"known", "nn", "jcbb"}))
      ->capture_default_str();
  app.add_option("--spurious-fraction", flags->spurious_fraction,
                 "Inject this share of spurious observations (uniform clutter, 0..0.9) before running")
      ->check(checks::in_range(0.0, 0.9))
      ->capture_default_str();
  app.add_option("--clutter-seed", flags->clutter_seed, "Seed of the injected clutter")->capture_default_str();
  app.add_option("--odometry-inflation", flags->odometry_inflation,
                 "Multiply the odometry noise model's variances (the simulator's odometry has biases it does not model), in (0, 1e6]")
      ->check(checks::above(0.0, 1e6))
      ->capture_default_str();
  app.add_option("--gate-probability", flags->gate_probability, "chi^2 gate probability for nn/jcbb, in (0, 1)")
      ->check(checks::above(0.0, 0.999999))
      ->capture_default_str();
  app.add_option("--nees-checkpoints", flags->nees_checkpoints,
                 "Steps (evenly spaced) where NEES is reported; graph SLAM solves the prefix at each")
      ->check(checks::count(1000000))
      ->capture_default_str();
  app.add_option("--graph-solve-every", flags->graph_solve_every,
                 "Graph SLAM: also solve the growing graph every N steps between checkpoints (0 = only at checkpoints)")
      ->check(checks::count_or_zero())
      ->capture_default_str();
  app.add_flag("-q,--quiet", flags->quiet, "Print nothing on success");
  return [flags]() { return landmarks_command(*flags); };
}

}  // namespace cairn::cli
