#pragma once
/// \file
/// The flags of `cairn eval ape|rpe|kitti|relations` (cmd_eval.cpp), the options they give the
/// metrics, and reading the two inputs they name (format resolution, read warnings).

#include <CLI/CLI.hpp>
#include <string>

#include "cairn/eval/alignment.hpp"
#include "cairn/eval/association.hpp"
#include "cairn/eval/matrix_trajectory.hpp"
#include "cairn/eval/status.hpp"

namespace cairn::cli {

struct EvalFlags {
  std::string reference;  // GT, or the relations file
  std::string estimate;
  std::string format;
  std::string reference_format;
  std::string estimate_format;
  std::string reference_times;
  std::string estimate_times;
  std::string align = "none";
  std::string relation = "trans_part";
  double max_diff_s = -1;  // < 0: the metric's default (0.01 s; relations 0.1 s)
  double offset_s = 0;
  double delta = 1;
  std::string unit = "frames";
  bool all_pairs = false;
  std::string json;
  std::string plot;
  std::string plot_plane = "auto";
};

/// The inputs, outputs and association flags of every eval subcommand; `relations` for
/// `eval relations` (RELATIONS instead of GT, a CARMEN estimate allowed, no GT flags).
void add_eval_common_flags(CLI::App& command, EvalFlags& flags, bool relations);
/// --align and --relation (ape, rpe).
void add_eval_align_and_relation_flags(CLI::App& command, EvalFlags& flags);

eval::AssociationOptions eval_association_options(const EvalFlags& flags);
eval::AlignmentOptions eval_alignment_options(const EvalFlags& flags);

/// GT and EST as matrices: the format from --gt-format / --est-format, else --format, else the
/// name; KITTI blocks as written. Warns on dropped repeated stamps and normalised quaternions;
/// throws io::ParseError on a file that is no trajectory or a times file with a non-KITTI one.
eval::MatrixTrajectory read_eval_reference(const EvalFlags& flags);
eval::MatrixTrajectory read_eval_estimate(const EvalFlags& flags);

/// The estimate of a relations evaluation: a trajectory file, or a (corrected) CARMEN log whose
/// laser poses are the estimate (eval::relations_estimate_from_carmen).
eval::MatrixTrajectory read_relations_estimate(const EvalFlags& flags);

/// Throws the failure of a metric as "EST against GT: <message> [<status>]".
[[noreturn]] void fail_evaluation(const EvalFlags& flags, const eval::Outcome& outcome);

}  // namespace cairn::cli
