#include "cairn/io/trajectory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <ostream>
#include <system_error>

#include "cairn/core/assert.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/quaternion_input.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/number_format.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

using core::SE3;
using core::Timestamp;

constexpr const char* kTumLayout = "timestamp tx ty tz qx qy qz qw";
constexpr const char* kKittiLayout = "r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz";
constexpr const char* kEurocLayout = "timestamp_ns,px,py,pz,qw,qx,qy,qz";

std::string format_number(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.3g", value);
  return buffer;
}

// A token echoed in a message, cut short so a megabyte of digits stays readable.
std::string shorten(std::string_view token) {
  constexpr std::size_t kMax = 40;
  return token.size() > kMax ? std::string(token.substr(0, kMax)) + "..." : std::string(token);
}

// |stamp| beyond which a file is refused: the bound Timestamp::from_seconds and parse_seconds
// (with an exponent) keep, so any stamp read in one format can be written in every other and
// read back. 9.2e9 s after 1970 is the year 2261.
constexpr std::int64_t kMaxAbsStampNs = 9'200'000'000'000'000'000;

bool stamp_in_range(Timestamp stamp) {
  return stamp.nanoseconds() >= -kMaxAbsStampNs && stamp.nanoseconds() <= kMaxAbsStampNs;
}

// Rejects stamps out of range or decreasing: every consumer (association, interpolation, RPE
// over time deltas) assumes a strictly ordered time axis. A stamp equal to the previous one is
// refused too, except where `drop_repeats` is set (TUM, EuRoC): then the later pose is dropped,
// counted, and reported. TUM's own fr2/desk ground truth repeats 1311868229.5760 on lines
// 10862-10863 with two different poses; refusing the file would refuse the benchmark, silently
// keeping either pose would hide the problem. KITTI times files keep the strict rule because a
// dropped time would misalign every later pose.
class IncreasingStamps {
 public:
  explicit IncreasingStamps(bool drop_repeats = false) : drop_repeats_(drop_repeats) {}

  /// True to keep the pose of this line, false to drop it (a repeated stamp).
  bool check(const TextReader& reader, Timestamp stamp, std::string_view text) {
    if (!stamp_in_range(stamp)) {
      reader.fail("timestamp out of range: expected at most 9.2e9 s from the epoch, found " +
                  quote_token(text));
    }
    if (previous_ && stamp == *previous_ && drop_repeats_) {
      if (repeats_++ == 0) {
        first_repeat_line_ = reader.line_number();
        first_repeat_text_ = shorten(text);
        first_repeat_of_line_ = previous_line_;
      }
      return false;
    }
    if (previous_ && stamp <= *previous_) {
      reader.fail("timestamps must increase: " + shorten(text) + " follows " + previous_text_ +
                  " (line " + std::to_string(previous_line_) + ")");
    }
    previous_ = stamp;
    previous_text_ = shorten(text);
    previous_line_ = reader.line_number();
    return true;
  }

  void report(const std::string& path, TrajectoryReadReport& report) const {
    report.repeated_stamps_dropped = repeats_;
    if (repeats_ == 0) return;
    report.warnings.push_back(path + ":" + std::to_string(first_repeat_line_) + ": " +
                              std::to_string(repeats_) +
                              " pose(s) with a repeated timestamp dropped, the first pose of each "
                              "stamp kept (first: " + first_repeat_text_ + " repeats line " +
                              std::to_string(first_repeat_of_line_) + ")");
  }

 private:
  bool drop_repeats_ = false;
  std::optional<Timestamp> previous_;
  std::string previous_text_;
  std::size_t previous_line_ = 0;
  std::size_t repeats_ = 0;
  std::size_t first_repeat_line_ = 0;
  std::size_t first_repeat_of_line_ = 0;
  std::string first_repeat_text_;
};

// Counts quaternions far from unit norm; one warning summarises them all.
class QuaternionNorms {
 public:
  // Returns a quaternion SO3 can normalise without overflow or underflow (io/quaternion_input.hpp).
  Quaternion checked(const TextReader& reader, Quaternion q) {
    const double norm = make_normalisable(q);  // may be inf; only reported
    if (norm == 0.0) {
      reader.fail("quaternion has zero norm: expected a rotation quaternion, found (0, 0, 0, 0)");
    }
    if (!(std::abs(norm - 1.0) <= kQuaternionNormTolerance)) {
      if (count_ == 0) {
        first_line_ = reader.line_number();
        first_norm_ = norm;
      }
      ++count_;
    }
    return q;
  }

  void report(const std::string& path, TrajectoryReadReport& report) const {
    report.quaternions_normalised = count_;
    if (count_ == 0) return;
    report.warnings.push_back(path + ":" + std::to_string(first_line_) + ": " +
                              std::to_string(count_) + " quaternion(s) with |norm - 1| > " +
                              format_number(kQuaternionNormTolerance) + " (first: norm " +
                              format_number(first_norm_) + ") were normalised");
  }

 private:
  std::size_t count_ = 0;
  std::size_t first_line_ = 0;
  double first_norm_ = 0.0;
};

Vector3 parse_vector3(const TextReader& reader, std::string_view x, std::string_view y,
                      std::string_view z) {
  return {parse_double(reader, x, "tx"), parse_double(reader, y, "ty"),
          parse_double(reader, z, "tz")};
}

Timestamp parse_seconds(const TextReader& reader, std::string_view token) {
  const auto stamp = Timestamp::parse_seconds(token);
  if (!stamp) {
    reader.fail("expected a timestamp in seconds, found " + quote_token(token));
  }
  return *stamp;
}

[[noreturn]] void fail_no_poses(const std::string& path, const std::string& expected) {
  throw ParseError(path, 0, "no poses found: expected lines '" + expected + "'");
}

TrajectoryReadReport& report_or(TrajectoryReadReport* report, TrajectoryReadReport& local) {
  TrajectoryReadReport& chosen = report != nullptr ? *report : local;
  chosen = TrajectoryReadReport{};
  return chosen;
}

// max_ij |(R^T R - I)_ij|; NaN (from inf - inf in huge matrices) counts as infinite.
double orthonormality_error(const Matrix3& R) {
  const Matrix3 E = R.transpose() * R - Matrix3::Identity();
  double error = 0.0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double e = std::abs(E(i, j));
      error = std::isnan(e) ? std::numeric_limits<double>::infinity() : std::max(error, e);
      if (std::isinf(error)) return error;
    }
  }
  return error;
}

std::vector<Timestamp> read_kitti_times(const std::string& times_path, const std::string& poses_path,
                                        std::size_t pose_count, TrajectoryReadReport& report) {
  TextReader reader(times_path);
  std::vector<Timestamp> stamps;
  stamps.reserve(pose_count);
  IncreasingStamps order;
  while (reader.next_line()) {
    const std::string_view line = reader.line();
    if (is_blank_or_comment(line)) {
      ++report.comment_lines;
      continue;
    }
    const auto tokens = split_whitespace(line);
    if (tokens.size() != 1) {
      reader.fail("KITTI times line expects 1 number, found " + std::to_string(tokens.size()) +
                  ": one time in seconds per pose");
    }
    const Timestamp stamp = parse_seconds(reader, tokens[0]);
    order.check(reader, stamp, tokens[0]);
    stamps.push_back(stamp);
  }
  if (reader.last_line_unterminated()) report.warnings.push_back(reader.unterminated_last_line_warning());
  if (stamps.size() != pose_count) {
    throw ParseError(times_path, 0,
                     "times file has " + std::to_string(stamps.size()) + " times but pose file " +
                         poses_path + " has " + std::to_string(pose_count) +
                         " poses: expected one time per pose");
  }
  return stamps;
}

// ---------------------------------------------------------------------------------------------
// Writing


// What the readers would reject cannot be written: the file could not be read back.
void check_writable(const Trajectory& trajectory, const std::string& name, bool needs_stamps,
                    const char* format) {
  CAIRN_ASSERT(trajectory.stamps.empty() || trajectory.stamps.size() == trajectory.poses.size(),
               "Trajectory::stamps must be empty or hold one stamp per pose");
  const std::string prefix = std::string("cannot write ") + format + ": ";
  if (trajectory.poses.empty()) {
    throw ParseError(name, 0, prefix + "the trajectory has no poses (readers reject empty files)");
  }
  if (needs_stamps && !trajectory.has_stamps()) {
    throw ParseError(name, 0,
                     prefix + "the trajectory has no timestamps (KITTI poses read without times?)");
  }
  for (std::size_t i = 0; i < trajectory.stamps.size(); ++i) {
    if (!stamp_in_range(trajectory.stamps[i])) {
      throw ParseError(name, 0,
                       prefix + "timestamp of pose " + std::to_string(i) + " (" +
                           std::to_string(trajectory.stamps[i].nanoseconds()) +
                           " ns) is more than 9.2e9 s from the epoch");
    }
    if (i > 0 && trajectory.stamps[i] <= trajectory.stamps[i - 1]) {
      throw ParseError(name, 0,
                       prefix + "timestamps must increase: pose " + std::to_string(i) + " at " +
                           trajectory.stamps[i].to_seconds_string() + " s follows " +
                           trajectory.stamps[i - 1].to_seconds_string() + " s");
    }
  }
}

void emit_tum(std::ostream& out, const Trajectory& trajectory) {
  out << "# " << kTumLayout << '\n';
  std::string line;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const SE3& T = trajectory.poses[i];
    const Quaternion& q = T.unit_quaternion();
    line = trajectory.stamps[i].to_seconds_string();
    for (const double v : {T.translation().x(), T.translation().y(), T.translation().z(), q.x(),
                           q.y(), q.z(), q.w()}) {
      line += ' ';
      append_number(line, v);
    }
    line += '\n';
    out << line;
  }
}

void emit_kitti(std::ostream& out, const Trajectory& trajectory) {
  std::string line;
  for (const SE3& T : trajectory.poses) {
    const Eigen::Matrix<double, 3, 4> M = T.matrix3x4();
    line.clear();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 4; ++col) {
        if (row + col > 0) line += ' ';
        append_number(line, M(row, col));
      }
    }
    line += '\n';
    out << line;
  }
}

void emit_kitti_times(std::ostream& out, const Trajectory& trajectory) {
  for (const Timestamp& stamp : trajectory.stamps) out << stamp.to_seconds_string() << '\n';
}

void emit_euroc(std::ostream& out, const Trajectory& trajectory) {
  out << "#timestamp [ns],p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],"
         "q_RS_z []\n";
  std::string line;
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const SE3& T = trajectory.poses[i];
    const Quaternion& q = T.unit_quaternion();
    line = std::to_string(trajectory.stamps[i].nanoseconds());
    for (const double v : {T.translation().x(), T.translation().y(), T.translation().z(), q.w(),
                           q.x(), q.y(), q.z()}) {
      line += ',';
      append_number(line, v);
    }
    line += '\n';
    out << line;
  }
}

}  // namespace

std::string_view to_string(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "unknown";
}

std::optional<TrajectoryFormat> trajectory_format_from_name(std::string_view name) {
  for (const auto format : {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    if (name == to_string(format)) return format;
  }
  return std::nullopt;
}

namespace {

// One line of a stamped format (TUM, EuRoC).
struct StampedRow {
  Timestamp stamp;
  std::string_view stamp_text;
  Vector3 t;
  Quaternion q;
};

// The loop TUM and EuRoC share: skip comments, parse a row, keep stamps increasing (dropping
// repeats), check quaternion norms, report.
template <class ParseRow>
Trajectory read_stamped(const std::string& path, TrajectoryReadReport* report, const char* layout,
                        ParseRow&& parse_row) {
  TrajectoryReadReport local;
  TrajectoryReadReport& out = report_or(report, local);
  TextReader reader(path);
  Trajectory trajectory;
  IncreasingStamps order(/*drop_repeats=*/true);
  QuaternionNorms norms;
  while (reader.next_line()) {
    const std::string_view line = reader.line();
    if (is_blank_or_comment(line)) {
      ++out.comment_lines;
      continue;
    }
    const StampedRow row = parse_row(reader, line);
    if (!order.check(reader, row.stamp, row.stamp_text)) continue;
    trajectory.stamps.push_back(row.stamp);
    trajectory.poses.emplace_back(norms.checked(reader, row.q), row.t);
  }
  if (reader.last_line_unterminated()) out.warnings.push_back(reader.unterminated_last_line_warning());
  if (trajectory.poses.empty()) fail_no_poses(path, layout);
  out.poses = trajectory.size();
  order.report(path, out);
  norms.report(path, out);
  return trajectory;
}

}  // namespace

Trajectory read_tum(const std::string& path, TrajectoryReadReport* report) {
  return read_stamped(path, report, kTumLayout, [](const TextReader& reader, std::string_view line) {
    const auto tokens = split_whitespace(line);
    if (tokens.size() != 8) {
      reader.fail("TUM line expects 8 numbers, found " + std::to_string(tokens.size()) + ": " + kTumLayout);
    }
    StampedRow row;
    row.stamp = parse_seconds(reader, tokens[0]);
    row.stamp_text = tokens[0];
    row.t = parse_vector3(reader, tokens[1], tokens[2], tokens[3]);
    const double qx = parse_double(reader, tokens[4], "qx");
    const double qy = parse_double(reader, tokens[5], "qy");
    const double qz = parse_double(reader, tokens[6], "qz");
    const double qw = parse_double(reader, tokens[7], "qw");
    row.q = Quaternion(qw, qx, qy, qz);
    return row;
  });
}

Trajectory read_kitti(const std::string& path, const std::string& times_path,
                      TrajectoryReadReport* report) {
  static constexpr const char* kNames[12] = {"r11", "r12", "r13", "tx", "r21", "r22",
                                             "r23", "ty",  "r31", "r32", "r33", "tz"};
  TrajectoryReadReport local;
  TrajectoryReadReport& out = report_or(report, local);
  TextReader reader(path);
  Trajectory trajectory;
  while (reader.next_line()) {
    const std::string_view line = reader.line();
    if (is_blank_or_comment(line)) {
      ++out.comment_lines;
      continue;
    }
    const auto tokens = split_whitespace(line);
    if (tokens.size() != 12) {
      reader.fail("KITTI line expects 12 numbers, found " + std::to_string(tokens.size()) + ": " +
                  kKittiLayout);
    }
    Eigen::Matrix<double, 3, 4> T;
    for (int k = 0; k < 12; ++k) T(k / 4, k % 4) = parse_double(reader, tokens[k], kNames[k]);
    const Matrix3 R = T.leftCols<3>();
    const double error = orthonormality_error(R);
    if (!(error <= kMaxRotationOrthonormalityError)) {
      reader.fail("rotation block is not a rotation (|R^T R - I| = " + format_number(error) +
                  ", limit " + format_number(kMaxRotationOrthonormalityError) + ")");
    }
    // Orthonormal but det -1: projecting would silently pick a different rotation.
    if (R.determinant() < 0.0) {
      reader.fail("rotation block is a reflection (determinant " + format_number(R.determinant()) +
                  "): expected a rotation with determinant +1");
    }
    out.max_rotation_orthonormality_error = std::max(out.max_rotation_orthonormality_error, error);
    trajectory.poses.push_back(SE3::from_matrix3x4(T));
  }
  if (reader.last_line_unterminated()) out.warnings.push_back(reader.unterminated_last_line_warning());
  if (trajectory.poses.empty()) fail_no_poses(path, kKittiLayout);
  if (!times_path.empty()) {
    trajectory.stamps = read_kitti_times(times_path, path, trajectory.size(), out);
  }
  out.poses = trajectory.size();
  return trajectory;
}

Trajectory read_euroc(const std::string& path, TrajectoryReadReport* report) {
  return read_stamped(path, report, kEurocLayout, [](const TextReader& reader, std::string_view line) {
    // Columns past the 8th (velocity, IMU biases in ground-truth files) are not parsed: they
    // are not kept, so a bad value there cannot affect the result.
    const auto fields = split_fields(line, ',');
    if (fields.size() < 8) {
      reader.fail("EuRoC line expects at least 8 comma-separated fields, found " +
                  std::to_string(fields.size()) + ": " + kEurocLayout);
    }
    const auto stamp = Timestamp::parse_nanoseconds(fields[0]);
    if (!stamp) reader.fail("expected an integer timestamp in nanoseconds, found " + quote_token(fields[0]));
    StampedRow row;
    row.stamp = *stamp;
    row.stamp_text = fields[0];
    row.t = parse_vector3(reader, fields[1], fields[2], fields[3]);
    const double qw = parse_double(reader, fields[4], "qw");
    const double qx = parse_double(reader, fields[5], "qx");
    const double qy = parse_double(reader, fields[6], "qy");
    const double qz = parse_double(reader, fields[7], "qz");
    row.q = Quaternion(qw, qx, qy, qz);
    return row;
  });
}

void write_tum(std::ostream& out, const Trajectory& trajectory) {
  check_writable(trajectory, "<stream>", true, "TUM");
  emit_tum(out, trajectory);
}

void write_kitti(std::ostream& poses_out, const Trajectory& trajectory, std::ostream* times_out) {
  check_writable(trajectory, "<stream>", times_out != nullptr, "KITTI");
  emit_kitti(poses_out, trajectory);
  if (times_out != nullptr) emit_kitti_times(*times_out, trajectory);
}

void write_euroc(std::ostream& out, const Trajectory& trajectory) {
  check_writable(trajectory, "<stream>", true, "EuRoC");
  emit_euroc(out, trajectory);
}

void write_tum(const std::string& path, const Trajectory& trajectory) {
  check_writable(trajectory, path, true, "TUM");
  OutputFile file(path);
  file.write([&](std::ostream& out) { emit_tum(out, trajectory); });
  file.commit();
}

void write_kitti(const std::string& path, const Trajectory& trajectory, const std::string& times_path) {
  check_writable(trajectory, path, false, "KITTI");
  if (!times_path.empty()) check_writable(trajectory, times_path, true, "KITTI times");
  OutputFile poses_file(path);
  poses_file.write([&](std::ostream& out) { emit_kitti(out, trajectory); });
  if (times_path.empty()) {
    poses_file.commit();
    return;
  }
  // Both temporaries exist before either rename, so a failure writing the times leaves the old
  // pair of files untouched.
  OutputFile times_file(times_path);
  times_file.write([&](std::ostream& out) { emit_kitti_times(out, trajectory); });
  poses_file.commit();
  times_file.commit();
}

void write_euroc(const std::string& path, const Trajectory& trajectory) {
  check_writable(trajectory, path, true, "EuRoC");
  OutputFile file(path);
  file.write([&](std::ostream& out) { emit_euroc(out, trajectory); });
  file.commit();
}

}  // namespace cairn::io
