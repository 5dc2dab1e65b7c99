// `cairn register SOURCE TARGET`: one point cloud registered onto another, from a guess or from
// nothing (--global), with how well it fits and how much to trust it (lidar3d/
// pairwise_registration.hpp). Prints T_target_source, fitness, inlier RMSE, degeneracy and a
// covariance; --json writes them, --aligned the source moved into the target's frame. A
// registration that did not converge, or a global one refused (ambiguous, too little overlap),
// exits with status 1, as a failed command, after printing why; its --json still holds the result
// and the reason (the record of what was tried), --aligned is not written.

#include <cmath>
#include <cstdio>
#include <memory>
#include <numbers>
#include <string>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"
#include "cairn/io/transform_file.hpp"
#include "cairn/lidar3d/pairwise_registration.hpp"

namespace cairn::cli {
namespace {

struct RegisterFlags {
  std::string source;
  std::string target;
  std::string guess;
  bool global = false;
  std::string method = "gicp";
  lidar3d::PairwiseRegistrationOptions options;
  std::string json;
  std::string aligned;
};

void print_result(const lidar3d::PairwiseRegistrationResult& r, double max_correspondence_m) {
  const Matrix4 T = r.T_target_source.matrix();
  std::printf("T_target_source (%s, %s):\n", std::string(lidar3d::to_string(r.method)).c_str(),
              r.proposals.empty() ? "from the guess" : "global");
  for (int i = 0; i < 4; ++i) std::printf("  %13.9f %13.9f %13.9f %13.9f\n", T(i, 0), T(i, 1), T(i, 2), T(i, 3));
  const Eigen::Vector3d rpy = r.T_target_source.so3().to_rpy() * (180.0 / std::numbers::pi);
  const Eigen::Vector3d& t = r.T_target_source.translation();
  std::printf("translation %.4f %.4f %.4f m, roll %.3f pitch %.3f yaw %.3f deg\n", t.x(), t.y(), t.z(), rpy.x(),
              rpy.y(), rpy.z());
  std::printf("fitness %.4f (%zu of %zu source points within %g m of a target point), inlier RMSE %.4f m; %s after %d "
              "iterations; %zu target points; %.1f ms\n",
              r.fitness, r.correspondences, r.source_points, max_correspondence_m, r.inlier_rmse_m,
              r.converged ? "converged" : "NOT converged", r.iterations, r.target_points, 1e3 * r.time_s);
  std::printf("degeneracy %.4f%s%s\n", r.degeneracy, r.degenerate_directions > 0 ? ", degenerate along " : "",
              r.degenerate_directions > 0 ? r.weakest_direction.c_str() : "");
  const auto& C = r.covariance;
  if (C.isZero()) {
    std::printf("covariance: unavailable (a singular information matrix, or no residual left to scale it)\n");
  } else {
    std::printf("1-sigma: x %.2f y %.2f z %.2f cm, roll %.3f pitch %.3f yaw %.3f deg\n", 100 * std::sqrt(C(0, 0)),
                100 * std::sqrt(C(1, 1)), 100 * std::sqrt(C(2, 2)), std::sqrt(C(3, 3)) * 180 / std::numbers::pi,
                std::sqrt(C(4, 4)) * 180 / std::numbers::pi, std::sqrt(C(5, 5)) * 180 / std::numbers::pi);
  }
  for (const auto& p : r.proposals) {
    std::printf("  proposal: start yaw %7.2f deg -> fitness %.4f, RMSE %.4f m%s\n", p.yaw_rad * 180 / std::numbers::pi,
                p.fitness, p.inlier_rmse_m, p.converged ? "" : " (not converged)");
  }
}

/// The source's points moved into the target's frame (all of them, not the thinned ones).
void write_aligned(const std::string& path, const io::PointCloud& source, const core::SE3& T_target_source) {
  std::vector<Eigen::Vector3f> points;
  points.reserve(source.size());
  for (const Eigen::Vector3f& p : source.points) points.push_back((T_target_source * p.cast<double>()).cast<float>());
  io::write_output(path, [&](std::ostream& out) { io::write_ply(out, points, "cairn register: source in the target frame"); });
}

int register_command(RegisterFlags& flags) {
  flags.options.method = flags.method == "icp" ? lidar3d::PairwiseMethod::kPointToPlane : lidar3d::PairwiseMethod::kGicp;
  if (std::string why; !flags.options.is_valid(&why)) throw io::ParseError("cairn register", 0, why);
  if (flags.global && !flags.guess.empty()) throw UsageError("--global registers from nothing: drop --guess");
  io::check_distinct_outputs({{"--json", flags.json}, {"--aligned", flags.aligned}});
  const core::SE3 guess = flags.guess.empty() ? core::SE3() : io::read_transform(flags.guess);
  const io::PointCloud source = io::read_point_cloud(flags.source);
  const io::PointCloud target = io::read_point_cloud(flags.target);
  const lidar3d::PairwiseRegistrationResult result =
      flags.global ? lidar3d::register_pair_globally(source, target, flags.options)
                   : lidar3d::register_pair(source, target, guess, flags.options);
  print_result(result, flags.options.max_correspondence_m);
  if (!flags.json.empty()) {
    nlohmann::json j = lidar3d::pairwise_registration_json(result);
    j["source"] = flags.source;
    j["target"] = flags.target;
    io::write_output(flags.json, [&](std::ostream& out) { out << io::json_text(j); });
  }
  if (!result.accepted()) {
    std::fprintf(stderr, "cairn register: not trusted: %s\n", result.refusal.c_str());
    return 1;
  }
  if (!flags.aligned.empty()) write_aligned(flags.aligned, source, result.T_target_source);
  return 0;
}

}  // namespace

Runner register_register(CLI::App& app) {
  auto flags = std::make_shared<RegisterFlags>();
  app.add_option("SOURCE", flags->source, "Point cloud to move (PCD, PLY, KITTI .bin; compressed or not)")->required();
  app.add_option("TARGET", flags->target, "Point cloud to register onto")->required();
  app.add_option("--guess", flags->guess, "Initial T_target_source: a file with 12 (3 x 4) or 16 (4 x 4) numbers "
                                          "(default: identity)");
  app.add_flag("--global", flags->global, "No guess: Scan Context's yaw proposals, each refined; refused when "
                                          "ambiguous or below --min-fitness");
  app.add_option("--method", flags->method, "gicp (Generalized-ICP, Segal et al. 2009) or icp (point-to-plane)")
      ->check(CLI::IsMember({"gicp", "icp"}))
      ->capture_default_str();
  auto& o = flags->options;
  app.add_option("--max-distance", o.max_correspondence_m, "Maximum correspondence distance, m")->check(checks::positive())->capture_default_str();
  app.add_option("--source-voxel", o.source_voxel_m, "Source thinned to one point per voxel, m")->check(checks::positive())->capture_default_str();
  app.add_option("--target-voxel", o.target_voxel_m, "Target thinned to one point per voxel, m")->check(checks::positive())->capture_default_str();
  app.add_option("--min-range", o.min_range_m, "Points nearer the sensor dropped, m")->check(checks::non_negative())->capture_default_str();
  app.add_option("--max-range", o.max_range_m, "Points farther dropped, m")->check(checks::positive())->capture_default_str();
  app.add_option("--max-iterations", o.max_iterations, "Iteration limit")->check(checks::count())->capture_default_str();
  app.add_option("--min-fitness", o.global_min_fitness, "--global: the least fitness accepted")->check(checks::in_range(0.0, 1.0))->capture_default_str();
  app.add_option("--json", flags->json, "Write the result as JSON");
  app.add_option("--aligned", flags->aligned, "Write the source moved into the target frame (PLY)");
  app.footer("Exit status: 0 registered; 1 bad input, or a registration not to be trusted (not converged, too few "
             "points, --global ambiguous or below --min-fitness: the reason on stderr and in --json, no --aligned); "
             "2 bad flags.");
  return [flags]() { return register_command(*flags); };
}

}  // namespace cairn::cli
