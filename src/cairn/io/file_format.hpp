#pragma once
/// \file
/// Which of cairn's file formats a path holds: by explicit name, by extension, and for the
/// ambiguous ".txt" by looking at the first record.

#include <optional>
#include <string>
#include <string_view>

namespace cairn::io {

enum class FileFormat { kG2o, kToro, kTum, kKitti, kEuroc, kCarmen };

enum class FileKind { kPoseGraph, kTrajectory, kSensorLog };

std::string_view to_string(FileFormat format);
/// "g2o", "toro", "tum", "kitti", "euroc", "carmen"; nullopt otherwise.
std::optional<FileFormat> file_format_from_name(std::string_view name);
FileKind kind_of(FileFormat format);

/// By extension: .g2o -> g2o; .graph, .toro -> TORO; .tum -> TUM; .kitti -> KITTI;
/// .csv -> EuRoC; .clf, .log (also .clf.gz, .clf.bz2, ...) -> CARMEN. Otherwise nullopt.
std::optional<FileFormat> format_from_extension(const std::string& path);

/// format_from_extension, and if that does not tell and the file exists, its first record:
/// a g2o or TORO tag, 8 numbers (TUM), 12 numbers (KITTI), or comma-separated fields (EuRoC).
std::optional<FileFormat> detect_file_format(const std::string& path);

}  // namespace cairn::io
