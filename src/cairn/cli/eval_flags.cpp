// Flags and inputs of `cairn eval` (see eval_flags.hpp; the runs are in cmd_eval.cpp).

#include "cairn/cli/eval_flags.hpp"

#include <stdexcept>
#include <string>

#include "cairn/bag/pose_topic.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/file_format.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {
namespace {

eval::MatrixTrajectory read_matrices(const std::string& path, const std::string& own_format,
                                     const std::string& shared_format, const char* flag_name,
                                     const std::string& times) {
  if (const auto bag_topic = bag::split_bag_topic(path)) {  // BAG:/topic, as evo's `bag` mode
    if (!times.empty()) throw io::ParseError(times, 0, "a times file goes with a KITTI trajectory, not a bag topic");
    return eval::MatrixTrajectory(bag::read_pose_topic(bag_topic->first, bag_topic->second));
  }
  const std::string& flag = own_format.empty() ? shared_format : own_format;
  const io::FileFormat format = resolve_format(path, flag, flag_name);
  if (io::kind_of(format) != io::FileKind::kTrajectory) {
    throw io::ParseError(path, 0,
                         "expected a trajectory (TUM, KITTI or EuRoC), found a " + std::string(io::to_string(format)) +
                             " file; name the format with " + flag_name + " if it was guessed wrongly");
  }
  if (!times.empty() && format != io::FileFormat::kKitti) {
    throw io::ParseError(times, 0, "a times file goes with a KITTI trajectory only; " + path + " is " +
                                       std::string(io::to_string(format)));
  }
  // KITTI: the 3x4 blocks as written, as evo and the devkit use them (eval/matrix_trajectory.hpp).
  if (format == io::FileFormat::kKitti) return eval::read_kitti_matrices(path, times);
  io::TrajectoryReadReport report;
  const io::Trajectory trajectory = read_trajectory(path, format, times, &report);
  if (report.repeated_stamps_dropped > 0) {
    warn(path + ": " + std::to_string(report.repeated_stamps_dropped) +
         " poses dropped because their timestamp repeated the previous one");
  }
  if (report.quaternions_normalised > 0) {
    warn(path + ": " + std::to_string(report.quaternions_normalised) + " quaternions were not unit and were normalised");
  }
  return eval::MatrixTrajectory(trajectory);
}

}  // namespace

eval::MatrixTrajectory read_eval_reference(const EvalFlags& f) {
  return read_matrices(f.reference, f.reference_format, f.format, "--gt-format", f.reference_times);
}
eval::MatrixTrajectory read_eval_estimate(const EvalFlags& f) {
  return read_matrices(f.estimate, f.estimate_format, f.format, "--est-format", f.estimate_times);
}

eval::MatrixTrajectory read_relations_estimate(const EvalFlags& f) {
  if (bag::split_bag_topic(f.estimate)) return read_eval_estimate(f);
  const std::string& flag = f.estimate_format.empty() ? f.format : f.estimate_format;
  const io::FileFormat format = resolve_format(f.estimate, flag, "--est-format");
  if (format != io::FileFormat::kCarmen) return read_eval_estimate(f);
  io::CarmenReadReport report;
  const io::CarmenLog log = io::read_carmen_log(f.estimate, &report);
  return eval::relations_estimate_from_carmen(log, f.estimate);
}

eval::AssociationOptions eval_association_options(const EvalFlags& f) {
  eval::AssociationOptions a;
  if (f.max_diff_s >= 0) a.max_time_difference_s = f.max_diff_s;
  a.offset_s = f.offset_s;
  return a;
}

eval::AlignmentOptions eval_alignment_options(const EvalFlags& f) {
  eval::AlignmentOptions a;
  a.method = *eval::alignment_method_from_name(f.align);  // CLI11 checked the name
  return a;
}

void fail_evaluation(const EvalFlags& f, const eval::Outcome& outcome) {
  throw std::runtime_error(f.estimate + " against " + f.reference + ": " + outcome.message + " [" +
                           std::string(eval::to_string(outcome.status)) + "]");
}

void add_eval_common_flags(CLI::App& command, EvalFlags& f, bool relations) {
  if (relations) {
    command.add_option("RELATIONS", f.reference, "Relations file: 't_i t_j x y z roll pitch yaw' per line")->required();
  } else {
    command.add_option("GT", f.reference, "Reference (ground-truth) trajectory: TUM, KITTI or EuRoC, or BAG:/topic (Odometry, PoseStamped, PoseWithCovarianceStamped or TransformStamped)")->required();
  }
  command.add_option("EST", f.estimate,
                     relations ? "Estimate: TUM, KITTI (with --est-times) or EuRoC trajectory, or a corrected CARMEN log"
                               : "Estimated trajectory: TUM, KITTI or EuRoC, or BAG:/topic")
      ->required();
  command.add_option("--format", f.format, "Format of both trajectories: tum, kitti, euroc (default: from the name)")
      ->check(CLI::IsMember({"tum", "kitti", "euroc"}));
  if (!relations) {
    command.add_option("--gt-format", f.reference_format, "Format of GT only")->check(CLI::IsMember({"tum", "kitti", "euroc"}));
    command.add_option("--gt-times", f.reference_times, "KITTI times file for GT (then poses associate by time)");
  }
  command.add_option("--est-format", f.estimate_format, "Format of EST only")
      ->check(relations ? CLI::IsMember({"tum", "kitti", "euroc", "carmen"}) : CLI::IsMember({"tum", "kitti", "euroc"}));
  command.add_option("--est-times", f.estimate_times, "KITTI times file for EST");
  command.add_option("--max-diff", f.max_diff_s,
                     relations ? "Largest time difference to the nearest estimated pose, s (default 0.1)"
                               : "Largest time difference of an associated pair, s (default 0.01, as evo)")
      ->check(checks::non_negative());
  if (!relations) {
    command.add_option("--offset", f.offset_s, "Added to every EST time stamp before association, s (default 0)")
        ->check(checks::finite());
  }
  command.add_option("--json", f.json, "Also write the results as JSON to this file ('-' for stdout)");
  command.add_option("--plot", f.plot,
                     "Write plots: PREFIX gives PREFIX_<name>.png; PREFIX.svg or PREFIX.png picks the format");
  command.add_option("--plot-plane", f.plot_plane, "Plane of the top view: auto (the reference's widest), xy, xz, yz")
      ->check(CLI::IsMember({"auto", "xy", "xz", "yz"}));
}

void add_eval_align_and_relation_flags(CLI::App& command, EvalFlags& f) {
  command.add_option("--align", f.align, "Alignment of EST onto GT: none, se3, sim3, se2, first (default none)")
      ->check(CLI::IsMember({"none", "se3", "sim3", "se2", "first"}));
  command
      .add_option("--relation", f.relation,
                  "What to measure: trans_part (m), angle_deg, angle_rad, rot_part, full (default trans_part)")
      ->check(CLI::IsMember({"trans_part", "angle_deg", "angle_rad", "rot_part", "full"}));
}

}  // namespace cairn::cli
