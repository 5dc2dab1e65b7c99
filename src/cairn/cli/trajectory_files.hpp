#pragma once
/// \file
/// Reading and writing a trajectory by FileFormat, for the commands.

#include <string>

#include "cairn/io/file_format.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::cli {

io::Trajectory read_trajectory(const std::string& path, io::FileFormat format, const std::string& times_path,
                               io::TrajectoryReadReport* report);
void write_trajectory(const std::string& path, const io::Trajectory& trajectory, io::FileFormat format,
                      const std::string& times_path);

/// The format named by `flag` if given, otherwise detected from the path; throws ParseError
/// naming the file when neither works.
io::FileFormat resolve_format(const std::string& path, const std::string& flag, const char* flag_name);

}  // namespace cairn::cli
