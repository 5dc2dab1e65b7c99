#include "cairn/io/graph_io.hpp"

#include <array>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/quaternion_input.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {

std::string_view to_string(GraphFormat format) {
  return format == GraphFormat::kG2o ? "g2o" : "toro";
}

std::optional<GraphFormat> graph_format_from_name(std::string_view name) {
  if (name == "g2o") return GraphFormat::kG2o;
  if (name == "toro") return GraphFormat::kToro;
  return std::nullopt;
}

namespace {

using Matrix3 = Eigen::Matrix3d;
using Matrix6 = Eigen::Matrix<double, 6, 6>;

// Tags each format knows. TORO's own reader also accepts plain VERTEX/EDGE for 2D.
bool is_g2o_tag(std::string_view tag) {
  return tag == "VERTEX_SE2" || tag == "EDGE_SE2" || tag == "VERTEX_SE3:QUAT" ||
         tag == "EDGE_SE3:QUAT" || tag == "FIX";
}
bool is_toro_tag(std::string_view tag) {
  return tag == "VERTEX2" || tag == "EDGE2" || tag == "VERTEX3" || tag == "EDGE3" ||
         tag == "VERTEX" || tag == "EDGE";
}

// Symmetric matrix from its upper triangle written row by row (g2o's order).
template <int N>
Eigen::Matrix<double, N, N> from_upper_triangle(const double* values) {
  Eigen::Matrix<double, N, N> M;
  int k = 0;
  for (int r = 0; r < N; ++r) {
    for (int c = r; c < N; ++c) {
      M(r, c) = values[k];
      M(c, r) = values[k];
      ++k;
    }
  }
  return M;
}

// TORO 2D order I_xx I_xy I_yy I_tt I_xt I_yt (TORO's treeoptimizer2 documentation; GTSAM
// dataset.cpp reads EDGE2 the same way) into the matrix over (x, y, theta).
Matrix3 from_toro_2d(const std::array<double, 6>& v) {
  Matrix3 M;
  M << v[0], v[1], v[4],  //
      v[1], v[2], v[5],   //
      v[4], v[5], v[3];
  return M;
}

bool valid_information(const Eigen::MatrixXd& M) {
  return check_information_diagonal(M).empty() && is_positive_definite(M);
}

struct RawToroEdge2 {
  std::array<double, 6> values{};
};

class GraphBuilder {
 public:
  GraphBuilder(TextReader& reader, const GraphReadOptions& options, GraphReadReport& report)
      : reader_(reader), options_(options), report_(report) {}

  void parse_line(std::string_view tag, const std::vector<std::string_view>& tokens) {
    if (report_.format == GraphFormat::kG2o ? is_g2o_tag(tag) : is_toro_tag(tag)) {
      auto& count = report_.records[std::string(tag)];
      if (count.count++ == 0) count.first_line = reader_.line_number();
    }
    if (report_.format == GraphFormat::kG2o) {
      if (tag == "VERTEX_SE2") return vertex2(tokens, false);
      if (tag == "EDGE_SE2") return edge2(tokens, false);
      if (tag == "VERTEX_SE3:QUAT") return vertex3(tokens, false);
      if (tag == "EDGE_SE3:QUAT") return edge3(tokens, false);
      if (tag == "FIX") return fix(tokens);
    } else {
      if (tag == "VERTEX2" || tag == "VERTEX") return vertex2(tokens, true);
      if (tag == "EDGE2" || tag == "EDGE") return edge2(tokens, true);
      if (tag == "VERTEX3") return vertex3(tokens, true);
      if (tag == "EDGE3") return edge3(tokens, true);
    }
    unknown(tag);
  }

  PoseGraph finish() {
    if (dimension_ == 0) {
      std::string what = "no pose records: expected ";
      what += report_.format == GraphFormat::kG2o ? "VERTEX_SE2/EDGE_SE2 or VERTEX_SE3:QUAT/EDGE_SE3:QUAT"
                                                  : "VERTEX2/EDGE2 or VERTEX3/EDGE3";
      what += " lines";
      if (!report_.unknown_records.empty()) {
        what += ", found only";
        for (const auto& [tag, count] : report_.unknown_records) {
          what += " " + tag + " x" + std::to_string(count.count);
        }
      } else if (reader_.line_number() == 0) {
        what = "empty file: " + what;
      }
      throw ParseError(reader_.path(), 0, what);
    }
    if (dimension_ == 2) {
      if (report_.format == GraphFormat::kToro) resolve_toro_order();
      check_information(graph2_);
      check_references(graph2_);
      return std::move(graph2_);
    }
    check_information(graph3_);
    check_references(graph3_);
    return std::move(graph3_);
  }

 private:
  [[noreturn]] void fail(const std::string& detail) const { reader_.fail(detail); }

  void expect_count(const std::vector<std::string_view>& tokens, std::size_t expected,
                    const char* fields) const {
    if (tokens.size() != expected + 1) {
      fail(std::string(tokens[0]) + " expects " + std::to_string(expected) + " values after the tag (" +
           fields + "), found " + std::to_string(tokens.size() - 1));
    }
  }

  void set_dimension(int dimension, std::string_view tag) {
    if (dimension_ == 0) {
      dimension_ = dimension;
      dimension_tag_ = std::string(tag);
      dimension_line_ = reader_.line_number();
    } else if (dimension_ != dimension) {
      fail(std::string(tag) + " is a " + std::to_string(dimension) + "D record, but the graph is " +
           std::to_string(dimension_) + "D (" + dimension_tag_ + " at line " +
           std::to_string(dimension_line_) + "): expected one dimension per file");
    }
  }

  double number(std::string_view token, const char* what) const { return parse_double(reader_, token, what); }
  std::int64_t id(std::string_view token, const char* what) const { return parse_id(reader_, token, what); }

  void register_vertex(std::int64_t vertex_id) {
    const auto [it, inserted] = vertex_lines_.emplace(vertex_id, reader_.line_number());
    if (!inserted) {
      fail("pose " + std::to_string(vertex_id) + " is defined twice (first at line " +
           std::to_string(it->second) + "): expected one VERTEX line per pose");
    }
  }

  core::SO3 quaternion(std::string_view qx, std::string_view qy, std::string_view qz, std::string_view qw) {
    Eigen::Quaterniond q(number(qw, "qw"), number(qx, "qx"), number(qy, "qy"), number(qz, "qz"));
    const double norm = make_normalisable(q);  // each number is finite, their squares need not be (1e200)
    if (!(norm > 1e-12)) fail("quaternion (qx qy qz qw) has zero norm: expected a rotation");
    if (std::abs(norm - 1.0) > 1e-6) ++report_.quaternions_not_unit;
    return core::SO3(q);
  }

  void vertex2(const std::vector<std::string_view>& t, bool /*toro*/) {
    expect_count(t, 4, "id x y theta");
    set_dimension(2, t[0]);
    const std::int64_t vertex_id = id(t[1], "the pose id");
    register_vertex(vertex_id);
    graph2_.vertices.push_back({vertex_id, core::SE2(number(t[2], "x"), number(t[3], "y"), number(t[4], "theta"))});
  }

  void edge2(const std::vector<std::string_view>& t, bool toro) {
    expect_count(t, 11, toro ? "id1 id2 dx dy dtheta I_xx I_xy I_yy I_tt I_xt I_yt"
                             : "id1 id2 dx dy dtheta I11 I12 I13 I22 I23 I33");
    set_dimension(2, t[0]);
    GraphEdge<core::SE2> edge;
    edge.from = id(t[1], "the first pose id");
    edge.to = id(t[2], "the second pose id");
    check_not_self_loop(edge.from, edge.to);
    edge.T_from_to = core::SE2(number(t[3], "dx"), number(t[4], "dy"), number(t[5], "dtheta"));
    std::array<double, 6> info{};
    for (std::size_t k = 0; k < 6; ++k) info[k] = number(t[6 + k], "an information entry");
    if (toro) {
      toro_raw_.push_back({info});
    } else {
      edge.information = from_upper_triangle<3>(info.data());
    }
    edge.line = reader_.line_number();
    graph2_.edges.push_back(edge);
  }

  void vertex3(const std::vector<std::string_view>& t, bool toro) {
    if (toro) {
      expect_count(t, 7, "id x y z roll pitch yaw");
    } else {
      expect_count(t, 8, "id x y z qx qy qz qw");
    }
    set_dimension(3, t[0]);
    const std::int64_t vertex_id = id(t[1], "the pose id");
    register_vertex(vertex_id);
    const Eigen::Vector3d position(number(t[2], "x"), number(t[3], "y"), number(t[4], "z"));
    const core::SO3 R = toro ? core::SO3::from_rpy(number(t[5], "roll"), number(t[6], "pitch"), number(t[7], "yaw"))
                             : quaternion(t[5], t[6], t[7], t[8]);
    graph3_.vertices.push_back({vertex_id, core::SE3(R, position)});
  }

  void edge3(const std::vector<std::string_view>& t, bool toro) {
    std::size_t first_info = 0;
    if (toro) {
      if (t.size() != 9 && t.size() != 30) {
        fail(std::string(t[0]) +
             " expects 8 values after the tag (id1 id2 x y z roll pitch yaw) or 29 (with the 21 "
             "upper-triangular information entries), found " +
             std::to_string(t.size() - 1));
      }
      first_info = 9;
    } else {
      expect_count(t, 30, "id1 id2 x y z qx qy qz qw and 21 information entries I11..I66");
      first_info = 10;
    }
    set_dimension(3, t[0]);
    GraphEdge<core::SE3> edge;
    edge.from = id(t[1], "the first pose id");
    edge.to = id(t[2], "the second pose id");
    check_not_self_loop(edge.from, edge.to);
    const Eigen::Vector3d translation(number(t[3], "x"), number(t[4], "y"), number(t[5], "z"));
    const core::SO3 R = toro ? core::SO3::from_rpy(number(t[6], "roll"), number(t[7], "pitch"), number(t[8], "yaw"))
                             : quaternion(t[6], t[7], t[8], t[9]);
    edge.T_from_to = core::SE3(R, translation);
    if (t.size() > first_info) {
      std::array<double, 21> info{};
      for (std::size_t k = 0; k < 21; ++k) info[k] = number(t[first_info + k], "an information entry");
      edge.information = from_upper_triangle<6>(info.data());
    } else {
      ++report_.edges_without_information;
      edge.information = Matrix6::Identity();
    }
    edge.line = reader_.line_number();
    graph3_.edges.push_back(edge);
  }

  void fix(const std::vector<std::string_view>& t) {
    if (t.size() < 2) fail("FIX expects at least one pose id after the tag, found none");
    for (std::size_t k = 1; k < t.size(); ++k) {
      fixed_.push_back({id(t[k], "a fixed pose id"), reader_.line_number()});
    }
  }

  void unknown(std::string_view tag) {
    if (options_.reject_unknown_records) {
      fail("unknown record type " + quote_token(tag) + ": expected one of " +
           (report_.format == GraphFormat::kG2o ? "VERTEX_SE2, EDGE_SE2, VERTEX_SE3:QUAT, EDGE_SE3:QUAT, FIX"
                                                : "VERTEX2, EDGE2, VERTEX3, EDGE3") +
           " (unknown records are refused in strict mode)");
    }
    auto& count = report_.unknown_records[std::string(tag.substr(0, 40))];
    if (count.count++ == 0) count.first_line = reader_.line_number();
  }

  void check_not_self_loop(std::int64_t from, std::int64_t to) const {
    if (from == to) {
      fail("edge from pose " + std::to_string(from) + " to itself: expected two different poses");
    }
  }

  // TORO EDGE2 information order (see ToroInformationOrder::kAuto).
  void resolve_toro_order() {
    bool use_g2o = options_.toro_information_order == ToroInformationOrder::kG2o;
    if (options_.toro_information_order == ToroInformationOrder::kAuto && !toro_raw_.empty()) {
      bool all_invalid_toro = true;
      bool all_valid_g2o = true;
      for (const auto& raw : toro_raw_) {
        all_invalid_toro = all_invalid_toro && !valid_information(from_toro_2d(raw.values));
        all_valid_g2o = all_valid_g2o && valid_information(from_upper_triangle<3>(raw.values.data()));
        if (!all_invalid_toro && !all_valid_g2o) break;
      }
      use_g2o = all_invalid_toro && all_valid_g2o;
      if (use_g2o) {
        report_.warnings.push_back(
            "EDGE2 information read in g2o order (I11 I12 I13 I22 I23 I33): in TORO order (I_xx I_xy "
            "I_yy I_tt I_xt I_yt) none of the " + std::to_string(toro_raw_.size()) +
            " matrices is positive definite, in g2o order all are (override with the TORO "
            "information order option)");
      }
    }
    report_.toro_information_order = use_g2o ? "g2o" : "toro";
    for (std::size_t k = 0; k < toro_raw_.size(); ++k) {
      graph2_.edges[k].information = use_g2o ? from_upper_triangle<3>(toro_raw_[k].values.data())
                                             : from_toro_2d(toro_raw_[k].values);
    }
  }

  template <class Graph>
  void check_information(Graph& graph) {
    report_.information_policy = options_.information_policy;
    for (auto& edge : graph.edges) {
      const std::string diagonal = check_information_diagonal(edge.information);
      if (!diagonal.empty()) throw ParseError(reader_.path(), edge.line, diagonal);
      const Definiteness definiteness = classify_information(edge.information);
      if (definiteness == Definiteness::kPositiveDefinite) continue;
      if (report_.information_not_positive_definite++ == 0) report_.first_not_positive_definite_line = edge.line;
      if (definiteness == Definiteness::kSemiDefinite) {
        if (report_.information_singular++ == 0) report_.first_singular_line = edge.line;
        continue;
      }
      if (report_.information_indefinite++ == 0) report_.first_indefinite_line = edge.line;
      if (options_.information_policy == InformationPolicy::kReject) {
        throw ParseError(reader_.path(), edge.line,
                         "information matrix is indefinite (a negative eigenvalue): expected a positive "
                         "definite matrix (strict mode refuses it; by default it is projected to the "
                         "nearest positive semi-definite matrix)");
      }
      if (options_.information_policy == InformationPolicy::kProject) {
        edge.information = nearest_positive_semidefinite(edge.information);
      }
    }
    const std::string of_edges = " of " + std::to_string(graph.edges.size()) + " information matrices ";
    if (report_.information_indefinite > 0) {
      report_.warnings.push_back(
          std::to_string(report_.information_indefinite) + of_edges + "are indefinite (first at line " +
          std::to_string(report_.first_indefinite_line) + "); " +
          (options_.information_policy == InformationPolicy::kProject
               ? "projected to the nearest positive semi-definite matrix"
               : "kept as written: the cost is unbounded below along some directions"));
    }
    if (report_.information_singular > 0) {
      report_.warnings.push_back(std::to_string(report_.information_singular) + of_edges +
                                 "are singular (positive semi-definite, first at line " +
                                 std::to_string(report_.first_singular_line) + "); kept as written");
    }
  }

  template <class Graph>
  void check_references(Graph& graph) {
    const bool has_vertices = !graph.vertices.empty();
    std::unordered_set<std::int64_t> edge_ids;
    for (const auto& edge : graph.edges) {
      for (const std::int64_t pose : {edge.from, edge.to}) {
        if (has_vertices && !vertex_lines_.contains(pose)) {
          throw ParseError(reader_.path(), edge.line,
                           "edge refers to pose " + std::to_string(pose) +
                               ", which has no VERTEX line: expected every pose of an edge to be "
                               "defined when the file has VERTEX lines");
        }
        if (!has_vertices) edge_ids.insert(pose);
      }
    }
    for (const auto& [pose, line] : fixed_) {
      const bool known = has_vertices ? vertex_lines_.contains(pose) : edge_ids.contains(pose);
      if (!known) {
        throw ParseError(reader_.path(), line,
                         "FIX refers to pose " + std::to_string(pose) + ", which is not in the graph");
      }
      graph.fixed.push_back(pose);
    }
    if (report_.quaternions_not_unit > 0) {
      report_.warnings.push_back(std::to_string(report_.quaternions_not_unit) +
                                 " quaternions had a norm differing from 1 by more than 1e-6 and "
                                 "were normalised");
    }
    if (report_.edges_without_information > 0) {
      report_.warnings.push_back(std::to_string(report_.edges_without_information) +
                                 " EDGE3 lines carry no information matrix: identity assumed");
    }
    for (const auto& [tag, count] : report_.unknown_records) {
      report_.warnings.push_back("skipped " + std::to_string(count.count) + " unknown " + tag +
                                 " record(s), first at line " + std::to_string(count.first_line));
    }
  }

  TextReader& reader_;
  const GraphReadOptions& options_;
  GraphReadReport& report_;
  int dimension_ = 0;
  std::string dimension_tag_;
  std::size_t dimension_line_ = 0;
  PoseGraph2D graph2_;
  PoseGraph3D graph3_;
  std::vector<RawToroEdge2> toro_raw_;
  std::unordered_map<std::int64_t, std::size_t> vertex_lines_;
  std::vector<std::pair<std::int64_t, std::size_t>> fixed_;
};

std::optional<GraphFormat> sniff_format(const std::string& path) {
  TextReader reader(path);
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const auto tokens = split_whitespace(reader.line());
    if (is_g2o_tag(tokens[0])) return GraphFormat::kG2o;
    if (is_toro_tag(tokens[0])) return GraphFormat::kToro;
    return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

std::optional<GraphFormat> detect_graph_format(const std::string& path) {
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension == ".g2o") return GraphFormat::kG2o;
  if (extension == ".graph" || extension == ".toro") return GraphFormat::kToro;
  return sniff_format(path);
}

GraphFile read_graph(const std::string& path, const GraphReadOptions& options) {
  GraphFile file;
  GraphReadReport& report = file.report;
  report.path = path;
  const std::optional<GraphFormat> format = options.format ? options.format : detect_graph_format(path);
  if (!format) {
    throw ParseError(path, 0,
                     "cannot tell the graph format: expected a .g2o or .graph extension or a first "
                     "record VERTEX_SE2/EDGE_SE2/VERTEX_SE3:QUAT/EDGE_SE3:QUAT (g2o) or "
                     "VERTEX2/EDGE2/VERTEX3/EDGE3 (TORO); name the format explicitly");
  }
  report.format = *format;
  TextReader reader(path);
  GraphBuilder builder(reader, options, report);
  while (reader.next_line()) {
    if (is_blank_or_comment(reader.line())) continue;
    const auto tokens = split_whitespace(reader.line());
    builder.parse_line(tokens[0], tokens);
  }
  report.lines = reader.line_number();
  file.graph = builder.finish();
  if (reader.last_line_unterminated()) report.warnings.push_back(reader.unterminated_last_line_warning());
  return file;
}

namespace {

void append_id(std::string& out, std::int64_t value) { out += std::to_string(value); }

void append_numbers(std::string& out, std::initializer_list<double> values) {
  for (double v : values) {
    out += ' ';
    append_number(out, v);
  }
}

template <int N>
void append_upper_triangle(std::string& out, const Eigen::Matrix<double, N, N>& M) {
  for (int r = 0; r < N; ++r) {
    for (int c = r; c < N; ++c) {
      out += ' ';
      append_number(out, M(r, c));
    }
  }
}

void append_quaternion(std::string& out, const core::SO3& R) {
  const auto& q = R.unit_quaternion();
  append_numbers(out, {q.x(), q.y(), q.z(), q.w()});
}

// g2o's FIX line; TORO cannot say that a pose is fixed, so the writer warns instead.
void write_fixed(std::ostream& out, const std::vector<std::int64_t>& fixed, GraphFormat format,
                 std::vector<std::string>& warnings) {
  if (fixed.empty()) return;
  if (format == GraphFormat::kToro) {
    warnings.push_back("TORO has no FIX record: " + std::to_string(fixed.size()) + " fixed pose(s) not written");
    return;
  }
  std::string line = "FIX";
  for (const auto id : fixed) line += " " + std::to_string(id);
  out << line << '\n';
}

std::vector<std::string> write_2d(std::ostream& out, const PoseGraph2D& graph, GraphFormat format) {
  const bool g2o = format == GraphFormat::kG2o;
  std::vector<std::string> warnings;
  std::string line;
  for (const auto& v : graph.vertices) {
    line = g2o ? "VERTEX_SE2 " : "VERTEX2 ";
    append_id(line, v.id);
    append_numbers(line, {v.T_world_pose.x(), v.T_world_pose.y(), v.T_world_pose.angle()});
    out << line << '\n';
  }
  for (const auto& e : graph.edges) {
    line = g2o ? "EDGE_SE2 " : "EDGE2 ";
    append_id(line, e.from);
    line += ' ';
    append_id(line, e.to);
    append_numbers(line, {e.T_from_to.x(), e.T_from_to.y(), e.T_from_to.angle()});
    const auto& I = e.information;
    if (g2o) {
      append_upper_triangle<3>(line, I);
    } else {
      append_numbers(line, {I(0, 0), I(0, 1), I(1, 1), I(2, 2), I(0, 2), I(1, 2)});
    }
    out << line << '\n';
  }
  write_fixed(out, graph.fixed, format, warnings);
  return warnings;
}

std::vector<std::string> write_3d(std::ostream& out, const PoseGraph3D& graph, GraphFormat format) {
  const bool g2o = format == GraphFormat::kG2o;
  std::vector<std::string> warnings;
  std::string line;
  for (const auto& v : graph.vertices) {
    line = g2o ? "VERTEX_SE3:QUAT " : "VERTEX3 ";
    append_id(line, v.id);
    const auto& t = v.T_world_pose.translation();
    append_numbers(line, {t.x(), t.y(), t.z()});
    if (g2o) {
      append_quaternion(line, v.T_world_pose.so3());
    } else {
      const auto rpy = v.T_world_pose.so3().to_rpy();
      append_numbers(line, {rpy.x(), rpy.y(), rpy.z()});
    }
    out << line << '\n';
  }
  for (const auto& e : graph.edges) {
    line = g2o ? "EDGE_SE3:QUAT " : "EDGE3 ";
    append_id(line, e.from);
    line += ' ';
    append_id(line, e.to);
    const auto& t = e.T_from_to.translation();
    append_numbers(line, {t.x(), t.y(), t.z()});
    if (g2o) {
      append_quaternion(line, e.T_from_to.so3());
    } else {
      const auto rpy = e.T_from_to.so3().to_rpy();
      append_numbers(line, {rpy.x(), rpy.y(), rpy.z()});
    }
    append_upper_triangle<6>(line, e.information);
    out << line << '\n';
  }
  write_fixed(out, graph.fixed, format, warnings);
  return warnings;
}

}  // namespace

std::vector<std::string> write_graph(std::ostream& out, const PoseGraph& graph, GraphFormat format) {
  if (const auto* g2 = std::get_if<PoseGraph2D>(&graph)) return write_2d(out, *g2, format);
  return write_3d(out, std::get<PoseGraph3D>(graph), format);
}

std::vector<std::string> write_graph(const std::string& path, const PoseGraph& graph, GraphFormat format) {
  std::vector<std::string> warnings;
  write_output(path, [&](std::ostream& out) { warnings = write_graph(out, graph, format); });
  return warnings;
}

}  // namespace cairn::io
