// `cairn eval ape|rpe|kitti|relations`: trajectory metrics (src/cairn/eval/, docs/evaluation.md)
// with a table on the terminal, JSON (eval/report_json.hpp) and plots (eval/plots.hpp, drawn by
// src/cairn/viz/).
//
//   cairn eval ape GT EST [--align se3] [--relation trans_part]     evo_ape's APE
//   cairn eval rpe GT EST --delta 10 --unit m [--all-pairs]         evo_rpe's RPE
//   cairn eval kitti GT EST                                          KITTI devkit t_err / r_err
//   cairn eval relations RELATIONS EST                               Kuemmerle et al. 2009
//
// Flags and reading the inputs: eval_flags.cpp; the terminal tables: eval_print.cpp.

#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "cairn/cli/commands.hpp"
#include "cairn/cli/eval_flags.hpp"
#include "cairn/cli/eval_print.hpp"
#include "cairn/cli/flag_checks.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/eval/ape.hpp"
#include "cairn/eval/kitti_metric.hpp"
#include "cairn/eval/plots.hpp"
#include "cairn/eval/relations.hpp"
#include "cairn/eval/report_json.hpp"
#include "cairn/eval/rpe.hpp"
#include "cairn/io/json_text.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/viz/render.hpp"

namespace cairn::cli {
namespace {

// ---------------------------------------------------------------------------------------------
// Outputs

// The files of one evaluation (--json and every --plot) form one result: each is produced in
// memory as the run goes and all are written at its end, after the last was produced
// (io::write_outputs), so a run that fails half way replaces none of them.
std::vector<io::PlannedOutput> g_pending_outputs;

void queue_output(const std::string& path, std::string bytes) {
  g_pending_outputs.push_back({path, [bytes = std::move(bytes)](std::ostream& out) { out << bytes; }});
}

void write_queued_outputs() {
  io::write_outputs(g_pending_outputs);
  for (const io::PlannedOutput& o : g_pending_outputs) {
    if (!io::is_standard_output(o.path)) std::cout << "wrote " << o.path << '\n';
  }
  g_pending_outputs.clear();
}

void emit_json(const std::string& destination, const nlohmann::json& j) {
  if (destination.empty()) return;
  queue_output(destination, io::json_text(j));
}

/// --plot PREFIX or --plot FILE.png|svg: each figure drawn into PREFIX_<name>.png (or .svg).
void save_plots(const std::string& flag, const std::vector<eval::NamedFigure>& figures) {
  std::string prefix = flag;
  viz::ImageFormat format = viz::ImageFormat::kPng;
  if (auto named = viz::image_format_from_path(flag)) {
    format = *named;
    prefix = flag.substr(0, flag.size() - 4);
  }
  for (const eval::NamedFigure& figure : figures) {
    const std::string path = prefix + "_" + figure.name + std::string(viz::extension(format));
    const viz::RenderResult image = viz::render(figure.figure, format);
    if (!image.ok) throw io::ParseError(path, 0, "cannot draw the plot: " + image.message);
    queue_output(path, image.bytes);
  }
}

// ---------------------------------------------------------------------------------------------
// The four metrics

int run_ape(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_eval_reference(f);
  const eval::MatrixTrajectory estimate = read_eval_estimate(f);
  eval::ApeOptions options;
  options.relation = *eval::pose_relation_from_name(f.relation);
  options.association = eval_association_options(f);
  options.alignment = eval_alignment_options(f);
  const eval::ApeResult r = eval::evaluate_ape(reference, estimate, options);
  if (!r.outcome.ok()) fail_evaluation(f, r.outcome);

  print_ape_table(r, f);
  emit_json(f.json, eval::ape_json(r, options, f.reference, f.estimate));
  if (!f.plot.empty()) save_plots(f.plot, eval::ape_figures(r, f.plot_plane));
  return 0;
}

int run_rpe(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_eval_reference(f);
  const eval::MatrixTrajectory estimate = read_eval_estimate(f);
  eval::RpeOptions options;
  options.relation = *eval::pose_relation_from_name(f.relation);
  options.delta = f.delta;
  options.delta_unit = *eval::delta_unit_from_name(f.unit);
  options.all_pairs = f.all_pairs;
  options.association = eval_association_options(f);
  options.alignment = eval_alignment_options(f);
  if (std::string problems; !options.is_valid(&problems)) {
    throw std::runtime_error("invalid RPE options: " + problems);
  }
  const eval::RpeResult r = eval::evaluate_rpe(reference, estimate, options);
  if (!r.outcome.ok()) fail_evaluation(f, r.outcome);

  print_rpe_table(r, options, f);
  emit_json(f.json, eval::rpe_json(r, options, f.reference, f.estimate));
  if (!f.plot.empty()) save_plots(f.plot, eval::rpe_figures(r, options, f.plot_plane));
  return 0;
}

int run_kitti(const EvalFlags& f) {
  const eval::MatrixTrajectory reference = read_eval_reference(f);
  const eval::MatrixTrajectory estimate = read_eval_estimate(f);
  eval::KittiOptions options;
  options.association = eval_association_options(f);
  const eval::KittiResult r = eval::evaluate_kitti(reference, estimate, options);
  if (!r.outcome.ok()) fail_evaluation(f, r.outcome);

  print_kitti_table(r, f);
  emit_json(f.json, eval::kitti_json(r, options, f.reference, f.estimate));
  if (!f.plot.empty()) save_plots(f.plot, eval::kitti_figures(r, f.plot_plane));
  return 0;
}

int run_relations(const EvalFlags& f) {
  const std::vector<eval::Relation> relations = eval::read_relations(f.reference);
  const eval::MatrixTrajectory estimate = read_relations_estimate(f);
  eval::RelationsOptions options;
  if (f.max_diff_s >= 0) options.max_time_difference_s = f.max_diff_s;
  const eval::RelationsResult r = eval::evaluate_relations(relations, estimate, options);
  if (!r.outcome.ok()) fail_evaluation(f, r.outcome);

  print_relations_table(r, relations.size(), f);
  emit_json(f.json, eval::relations_json(r, relations, options, f.reference, f.estimate));
  if (!f.plot.empty()) save_plots(f.plot, eval::relations_figures(r, relations));
  return 0;
}

}  // namespace

Runner register_eval(CLI::App& app) {
  auto flags = std::make_shared<EvalFlags>();
  app.require_subcommand(1);
  CLI::App* ape = app.add_subcommand("ape", "Absolute pose error, as evo_ape (association, alignment, statistics)");
  add_eval_common_flags(*ape, *flags, false);
  add_eval_align_and_relation_flags(*ape, *flags);

  CLI::App* rpe = app.add_subcommand("rpe", "Relative pose error over a delta in frames or metres, as evo_rpe");
  add_eval_common_flags(*rpe, *flags, false);
  add_eval_align_and_relation_flags(*rpe, *flags);
  rpe->add_option("--delta", flags->delta, "Pair distance in --unit (default 1)")->check(checks::positive());
  rpe->add_option("--unit", flags->unit, "Unit of --delta: frames or m (default frames)")
      ->check(CLI::IsMember({"frames", "f", "m", "meters", "metres"}));
  rpe->add_flag("--all-pairs", flags->all_pairs, "All overlapping pairs instead of consecutive ones");

  CLI::App* kitti = app.add_subcommand("kitti", "KITTI odometry metric: t_err [%] and r_err [deg/100 m] over 100..800 m");
  add_eval_common_flags(*kitti, *flags, false);

  CLI::App* relations =
      app.add_subcommand("relations", "Freiburg relations metric (Kuemmerle et al. 2009) on a relations file");
  add_eval_common_flags(*relations, *flags, true);

  return [flags, ape, rpe, kitti, relations]() {
    // With --json - the results table goes to stderr and standard output carries the JSON alone.
    claim_standard_output(flags->json);
    if (!flags->plot.empty() && (flags->plot == "-" || io::is_standard_output(flags->plot))) {
      throw io::ParseError(flags->plot, 0, "--plot writes several files (PREFIX_<name>.png): give a prefix, not standard output");
    }
    int status = 2;
    if (ape->parsed()) status = run_ape(*flags);
    if (rpe->parsed()) status = run_rpe(*flags);
    if (kitti->parsed()) status = run_kitti(*flags);
    if (relations->parsed()) status = run_relations(*flags);
    if (status == 0) write_queued_outputs();  // a failed evaluation writes nothing
    return status;
  };
}

}  // namespace cairn::cli
