#include "cairn/cli/commands.hpp"

#include <limits>

#include "cairn/cli/flag_checks.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::cli {

void LogReplayFlags::add_to(CLI::App& command) {
  command.add_option("--max-scans", max_scans, "Process only the first N scans")->check(checks::count(std::numeric_limits<long>::max()));
  command.add_flag("--lenient", lenient, "Skip malformed log records (counted) instead of stopping");
  command.add_flag("-q,--quiet", quiet, "Print nothing on success");
  command.add_flag("--progress", progress, "Progress as a line every 200 scans on stderr, also when stderr is not a terminal");
  command.add_flag("--overwrite", overwrite,
                   "Write into an --out directory that already holds files (those of the same names are replaced)");
}

io::CarmenLog LogReplayFlags::read_log(const std::string& path, io::CarmenReadReport* report) const {
  io::CarmenReadOptions options;
  options.skip_malformed_records = lenient;
  io::CarmenLog log = io::read_carmen_log(path, report, options);
  if (log.scans.empty()) throw io::ParseError(path, 0, "no laser records (FLASER, RLASER, ROBOTLASER1) in the log");
  return log;
}

}  // namespace cairn::cli
