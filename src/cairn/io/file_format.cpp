#include "cairn/io/file_format.hpp"

#include <filesystem>

#include "cairn/io/input_file.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {

std::string_view to_string(FileFormat format) {
  switch (format) {
    case FileFormat::kG2o: return "g2o";
    case FileFormat::kToro: return "toro";
    case FileFormat::kTum: return "tum";
    case FileFormat::kKitti: return "kitti";
    case FileFormat::kEuroc: return "euroc";
    case FileFormat::kCarmen: return "carmen";
  }
  return "?";
}

std::optional<FileFormat> file_format_from_name(std::string_view name) {
  for (FileFormat f : {FileFormat::kG2o, FileFormat::kToro, FileFormat::kTum, FileFormat::kKitti,
                       FileFormat::kEuroc, FileFormat::kCarmen}) {
    if (to_string(f) == name) return f;
  }
  return std::nullopt;
}

FileKind kind_of(FileFormat format) {
  if (format == FileFormat::kCarmen) return FileKind::kSensorLog;
  return format == FileFormat::kG2o || format == FileFormat::kToro ? FileKind::kPoseGraph
                                                                     : FileKind::kTrajectory;
}

std::optional<FileFormat> format_from_extension(const std::string& path) {
  std::filesystem::path name(path);
  if (name.extension() == ".gz" || name.extension() == ".bz2") name = name.stem();
  const std::string extension = name.extension().string();
  if (extension == ".clf" || extension == ".log") return FileFormat::kCarmen;
  if (extension == ".g2o") return FileFormat::kG2o;
  if (extension == ".graph" || extension == ".toro") return FileFormat::kToro;
  if (extension == ".tum") return FileFormat::kTum;
  if (extension == ".kitti") return FileFormat::kKitti;
  if (extension == ".csv") return FileFormat::kEuroc;
  return std::nullopt;
}

std::optional<FileFormat> detect_file_format(const std::string& path) {
  if (auto by_extension = format_from_extension(path)) return by_extension;
  if (path != "-") check_input_file(path);  // a directory or a missing file is said so, not "unknown format"
  std::error_code ec;
  if (path != "-" && !std::filesystem::is_regular_file(path, ec)) return std::nullopt;  // a FIFO is read once, by its reader
  TextReader reader(path);
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const std::string_view line = reader.line();
    const auto tokens = split_whitespace(line);
    const std::string_view tag = tokens[0];
    if (tag == "VERTEX_SE2" || tag == "EDGE_SE2" || tag == "VERTEX_SE3:QUAT" || tag == "EDGE_SE3:QUAT" ||
        tag == "FIX") {
      return FileFormat::kG2o;
    }
    if (tag == "VERTEX2" || tag == "EDGE2" || tag == "VERTEX3" || tag == "EDGE3" || tag == "VERTEX" ||
        tag == "EDGE") {
      return FileFormat::kToro;
    }
    if (line.find(',') != std::string_view::npos) return FileFormat::kEuroc;
    if (tokens.size() == 8) return FileFormat::kTum;
    if (tokens.size() == 12) return FileFormat::kKitti;
    return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace cairn::io
