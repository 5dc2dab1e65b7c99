// `cairn convert IN OUT`: between pose-graph formats, or between trajectory formats; a bag into a
// folder of the formats cairn reads (bag/extract.hpp).

#include <cstdio>
#include <iostream>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/extract.hpp"
#include "cairn/cli/commands.hpp"
#include "cairn/cli/interrupt.hpp"
#include "cairn/cli/trajectory_files.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {
namespace {

struct ConvertFlags {
  std::string input;
  std::string output;
  std::string from;
  std::string to;
  std::string times;
  std::string out_times;
  GraphReadFlags graph;
  std::vector<std::string> topics;
  bool overwrite = false;
};

/// `cairn convert BAG DIR` (or `cairn convert BAG --to DIR`): every sensor topic into DIR.
int convert_bag(const ConvertFlags& flags) {
  const std::string& dir = flags.output.empty() ? flags.to : flags.output;
  if (dir.empty()) throw UsageError("cairn convert BAG DIR: name the output folder");
  if (!flags.output.empty() && !flags.to.empty()) throw UsageError("a bag converts into a folder: give DIR or --to DIR, not both");
  bag::ExtractOptions options;
  options.topics = flags.topics;
  options.overwrite = flags.overwrite;
  const bag::ExtractReport report = bag::extract_bag(flags.input, dir, options);
  for (const bag::ExtractedTopic& t : report.topics) {
    if (t.output.empty()) {
      std::printf("  %-36s %-32s skipped: %s\n", t.topic.c_str(), t.type.c_str(), t.skipped_because.c_str());
    } else {
      std::printf("  %-36s %-32s %zu messages -> %s\n", t.topic.c_str(), t.type.c_str(), t.messages, t.output.c_str());
    }
  }
  std::printf("wrote %zu messages to %s\n", report.messages, dir.c_str());
  return 0;
}

int convert(const ConvertFlags& flags) {
  if (flags.from.empty() && bag::is_bag(flags.input)) return convert_bag(flags);
  if (!flags.topics.empty() || flags.overwrite) throw UsageError("--topic and --overwrite go with a bag");
  if (flags.output.empty()) throw UsageError("OUT is required");
  claim_standard_output(flags.output);
  claim_standard_output(flags.out_times);
  if (!flags.out_times.empty() && io::is_standard_output(flags.output) && io::is_standard_output(flags.out_times)) {
    throw io::ParseError(flags.out_times, 0, "the poses already go to standard output: give --out-times a file");
  }
  io::check_distinct_outputs({{"OUT", flags.output}, {"--out-times", flags.out_times}});
  const io::FileFormat from = resolve_format(flags.input, flags.from, "--from");
  io::FileFormat to{};
  if (!flags.to.empty()) {
    to = resolve_format(flags.output, flags.to, "--to");
  } else if (auto by_extension = io::format_from_extension(flags.output)) {
    to = *by_extension;
  } else {
    throw io::ParseError(flags.output, 0,
                         "cannot tell the output format from the name: expected .g2o, .graph, .tum, "
                         ".kitti or .csv, or name it with --to (needed for '-', standard output)");
  }
  if (io::kind_of(from) == io::FileKind::kSensorLog || io::kind_of(to) == io::FileKind::kSensorLog) {
    throw io::ParseError(flags.input, 0, "convert handles pose graphs and trajectories, not CARMEN sensor logs");
  }
  if (io::kind_of(from) != io::kind_of(to)) {
    throw io::ParseError(flags.output, 0,
                         std::string("cannot convert ") +
                             (io::kind_of(from) == io::FileKind::kPoseGraph ? "a pose graph" : "a trajectory") +
                             " (" + std::string(io::to_string(from)) + ") into " +
                             (io::kind_of(to) == io::FileKind::kPoseGraph ? "a pose-graph format" : "a trajectory format") +
                             " (" + std::string(io::to_string(to)) + ")");
  }
  if (io::kind_of(from) == io::FileKind::kPoseGraph) {
    io::GraphReadOptions options = flags.graph.options();
    options.format = from == io::FileFormat::kG2o ? io::GraphFormat::kG2o : io::GraphFormat::kToro;
    const io::GraphFile file = io::read_graph(flags.input, options);
    for (const auto& w : file.report.warnings) warn(w);
    const auto warnings = io::write_graph(flags.output, file.graph,
                                          to == io::FileFormat::kG2o ? io::GraphFormat::kG2o : io::GraphFormat::kToro);
    for (const auto& w : warnings) warn(w);
    const std::size_t edges = std::visit([](const auto& g) { return g.edges.size(); }, file.graph);
    const std::size_t vertices = std::visit([](const auto& g) { return g.vertices.size(); }, file.graph);
    std::cout << "wrote " << io::output_display_name(flags.output) << " (" << io::to_string(to) << ", " << io::dimension(file.graph)
              << "D, " << vertices << " vertices, " << edges << " edges)\n";
    return 0;
  }
  io::TrajectoryReadReport report;
  const io::Trajectory trajectory = read_trajectory(flags.input, from, flags.times, &report);
  for (const auto& w : report.warnings) warn(w);
  if (to != io::FileFormat::kKitti && !trajectory.has_stamps()) {
    throw io::ParseError(flags.input, 0,
                         "the trajectory has no timestamps but " + std::string(io::to_string(to)) +
                             " needs them: pass the KITTI times file with --times");
  }
  write_trajectory(flags.output, trajectory, to, flags.out_times);
  std::cout << "wrote " << io::output_display_name(flags.output) << " (" << io::to_string(to) << ", " << trajectory.poses.size()
            << " poses)";
  if (!flags.out_times.empty()) std::cout << " and " << io::output_display_name(flags.out_times);
  std::cout << '\n';
  return 0;
}

}  // namespace

Runner register_convert(CLI::App& app) {
  auto flags = std::make_shared<ConvertFlags>();
  app.add_option("IN", flags->input, "Input pose graph, trajectory, or bag (ROS 1 .bag, .mcap, rosbag2 .db3 or folder)")
      ->required();
  app.add_option("OUT", flags->output,
                 "Output file; its format follows its extension unless --to is given. For a bag: the output folder");
  app.add_option("--from", flags->from, "Input format: g2o, toro, tum, kitti, euroc (default: detected)");
  app.add_option("--to", flags->to, "Output format: g2o, toro, tum, kitti, euroc (default: by extension)");
  app.add_option("--times", flags->times, "KITTI input: times file (one time in seconds per pose)");
  app.add_option("--out-times", flags->out_times, "KITTI output: also write the times to this file");
  app.add_option("--topic", flags->topics, "Bag input: extract only this topic (repeatable)");
  app.add_flag("--overwrite", flags->overwrite, "Bag input: write into a folder that already holds files");
  flags->graph.add_to(app);
  return [flags]() { return convert(*flags); };
}

}  // namespace cairn::cli
