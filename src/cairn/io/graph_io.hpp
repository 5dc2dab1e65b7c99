#pragma once
/// \file
/// Reading and writing pose graphs: g2o (VERTEX_SE2, EDGE_SE2, VERTEX_SE3:QUAT, EDGE_SE3:QUAT,
/// FIX) and TORO (VERTEX2, EDGE2, VERTEX3, EDGE3). Formats and our strictness are documented
/// in docs/formats.md; frames, units and information-matrix orders in docs/conventions.md.
///
/// Readers reject malformed input with a ParseError naming file, line and what was expected.
/// Record types they do not know are counted in the report (and refused on request), never
/// silently dropped. Writers write a temporary file and rename it, so an output is whole or absent.

#include <cstddef>
#include <map>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "cairn/io/information.hpp"
#include "cairn/io/pose_graph.hpp"

namespace cairn::io {

enum class GraphFormat { kG2o, kToro };
std::string_view to_string(GraphFormat format);
/// "g2o" or "toro"; nullopt for anything else.
std::optional<GraphFormat> graph_format_from_name(std::string_view name);

/// How to read the six numbers of a TORO EDGE2 information matrix.
enum class ToroInformationOrder {
  /// TORO's order unless every matrix of the file is invalid in it and valid in g2o's order
  /// (GTSAM's w20000.txt is tagged EDGE2 but written in g2o order); the choice is reported.
  kAuto,
  /// I_xx I_xy I_yy I_tt I_xt I_yt (TORO's documentation and GTSAM's reader).
  kToro,
  /// I11 I12 I13 I22 I23 I33 (g2o's upper triangle).
  kG2o,
};

struct GraphReadOptions {
  /// nullopt: by extension (.g2o -> g2o, .graph/.toro -> TORO), otherwise by the first record's
  /// tag.
  std::optional<GraphFormat> format;
  /// What to do with an information matrix that is not positive definite.
  InformationPolicy information_policy = InformationPolicy::kProject;
  /// Refuse the file at the first record type the reader does not know, instead of counting it.
  bool reject_unknown_records = false;
  ToroInformationOrder toro_information_order = ToroInformationOrder::kAuto;
};

/// Count and first line (1-based) of one kind of record.
struct RecordCount {
  std::size_t count = 0;
  std::size_t first_line = 0;
};

/// What a reader saw and what it did about it.
struct GraphReadReport {
  std::string path;
  GraphFormat format = GraphFormat::kG2o;
  std::size_t lines = 0;
  /// Records read, by tag ("EDGE_SE2", "FIX", ...).
  std::map<std::string, RecordCount> records;
  /// Records skipped because the reader does not know their tag ("EQUIV", "BR", ...).
  std::map<std::string, RecordCount> unknown_records;
  /// Information matrices that are not positive definite: indefinite ones (handled by
  /// `information_policy`) and singular positive semi-definite ones (kept, reported).
  std::size_t information_not_positive_definite = 0;
  std::size_t first_not_positive_definite_line = 0;
  std::size_t information_indefinite = 0;
  std::size_t first_indefinite_line = 0;
  std::size_t information_singular = 0;
  std::size_t first_singular_line = 0;
  InformationPolicy information_policy = InformationPolicy::kProject;
  /// TORO EDGE3 lines without an information matrix (identity assumed).
  std::size_t edges_without_information = 0;
  /// TORO 2D only: the order the EDGE2 information was read in ("toro" or "g2o").
  std::string toro_information_order;
  /// Quaternions whose norm differed from 1 by more than 1e-6 (all quaternions are normalised).
  std::size_t quaternions_not_unit = 0;
  /// Human-readable notes about anything above that a user should know.
  std::vector<std::string> warnings;
};

struct GraphFile {
  PoseGraph graph;
  GraphReadReport report;
};

/// Reads a g2o or TORO file (see GraphReadOptions::format). Throws ParseError.
GraphFile read_graph(const std::string& path, const GraphReadOptions& options = {});

/// Format for `path` from its extension, or by looking at its first record; nullopt if neither
/// tells.
std::optional<GraphFormat> detect_graph_format(const std::string& path);

/// Writes `graph`; returns warnings about what the format cannot hold (TORO has no FIX record).
/// Numbers are written in the shortest form that reads back to the same double.
std::vector<std::string> write_graph(std::ostream& out, const PoseGraph& graph, GraphFormat format);
/// Atomic file version: writes "<path>.tmp.<pid>" and renames it. Throws ParseError on failure.
std::vector<std::string> write_graph(const std::string& path, const PoseGraph& graph,
                                     GraphFormat format);

}  // namespace cairn::io
