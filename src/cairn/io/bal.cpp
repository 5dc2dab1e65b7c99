#include "cairn/io/bal.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <string_view>

#include "cairn/io/compressed_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

/// TextTokens with BAL's checks: no binary bytes, numbers and indices parsed with errors.
class Tokens {
 public:
  Tokens(const std::string& path, const std::string& text) : path_(path), tokens_(text) {}

  /// The next token; empty at the end of the text. Throws on binary bytes.
  std::string_view next() {
    const std::string_view token = tokens_.next();
    for (const char byte : token) {
      const auto c = static_cast<unsigned char>(byte);
      if (c < 0x20 || c >= 0x7f) {
        fail_at_token("binary data (byte 0x" + hex(c) + "): expected BAL text (numbers separated by white space)");
      }
    }
    return token;
  }

  [[noreturn]] void fail(const std::string& detail) const { throw ParseError(path_, tokens_.position_line(), detail); }
  [[noreturn]] void fail_at_token(const std::string& detail) const { throw ParseError(path_, tokens_.line(), detail); }

  /// The next token as a number; `what` names it in errors ("truncated" at the end).
  double number(const std::string& what) {
    const std::string_view token = next();
    if (token.empty()) fail("file ends early: expected " + what + " (truncated file?)");
    double value = 0.0;
    const char* begin = token.data();
    const char* end = begin + token.size();
    if (*begin == '+') ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, value);
    if (ec != std::errc() || ptr != end || !std::isfinite(value)) {
      fail_at_token("expected a finite number for " + what + ", found " + quote_token(token));
    }
    return value;
  }

  /// The next token as an integer in [0, limit).
  long long index(const std::string& what, long long limit) {
    const std::string_view token = next();
    if (token.empty()) fail("file ends early: expected " + what + " (truncated file?)");
    long long value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size() || value < 0) {
      fail_at_token("expected a non-negative integer for " + what + ", found " + quote_token(token));
    }
    if (value >= limit) {
      fail_at_token(what + " " + std::string(token) + " is out of range: expected less than " + std::to_string(limit));
    }
    return value;
  }


 private:
  static std::string hex(unsigned char c) {
    char buffer[4];
    std::snprintf(buffer, sizeof(buffer), "%02x", c);
    return buffer;
  }
  const std::string& path_;
  TextTokens tokens_;
};

}  // namespace

BalProblem parse_bal(const std::string& path, const std::string& contents) {
  Tokens tokens(path, contents);
  if (contents.find_first_not_of(" \t\r\n") == std::string::npos) {
    throw ParseError(path, 0, "file is empty: expected a BAL header '<cameras> <points> <observations>'");
  }
  // Upper bounds from the file's size: each observation takes at least 8 bytes ("0 0 0 0\n"),
  // each camera 18 and each point 6, so a header claiming more than the file can hold is
  // rejected before anything is allocated.
  const long long bytes = static_cast<long long>(contents.size());
  const long long limit = std::numeric_limits<int>::max();
  const long long cameras = tokens.index("the number of cameras", limit);
  const long long points = tokens.index("the number of points", limit);
  const long long observations = tokens.index("the number of observations", limit);
  if (cameras == 0 || points == 0 || observations == 0) {
    tokens.fail_at_token("the header must give at least one camera, point and observation, found " +
                         std::to_string(cameras) + " " + std::to_string(points) + " " + std::to_string(observations));
  }
  if (observations * 8 + cameras * 18 + points * 6 > bytes + 1) {
    tokens.fail_at_token("the header announces " + std::to_string(cameras) + " cameras, " + std::to_string(points) +
                         " points and " + std::to_string(observations) + " observations, more than a file of " +
                         std::to_string(bytes) + " bytes can hold (truncated file?)");
  }
  BalProblem problem;
  problem.num_cameras = static_cast<int>(cameras);
  problem.num_points = static_cast<int>(points);
  problem.observations.resize(static_cast<std::size_t>(observations));
  for (long long i = 0; i < observations; ++i) {
    BalObservation& o = problem.observations[static_cast<std::size_t>(i)];
    const std::string which = " of observation " + std::to_string(i + 1) + " of " + std::to_string(observations);
    o.camera = static_cast<int>(tokens.index("the camera index" + which, cameras));
    o.point = static_cast<int>(tokens.index("the point index" + which, points));
    o.x = tokens.number("x" + which);
    o.y = tokens.number("y" + which);
  }
  static const char* const kCameraNames[9] = {"w_x", "w_y", "w_z", "t_x", "t_y", "t_z", "f", "k1", "k2"};
  problem.cameras.resize(static_cast<std::size_t>(cameras) * BalProblem::kCameraSize);
  for (long long c = 0; c < cameras; ++c) {
    for (int k = 0; k < BalProblem::kCameraSize; ++k) {
      problem.cameras[static_cast<std::size_t>(c) * BalProblem::kCameraSize + k] = tokens.number(
          std::string("camera ") + std::to_string(c) + " parameter " + kCameraNames[k] + " (9 numbers per camera)");
    }
  }
  problem.points.resize(static_cast<std::size_t>(points) * 3);
  for (long long p = 0; p < points; ++p) {
    for (int k = 0; k < 3; ++k) {
      problem.points[static_cast<std::size_t>(p) * 3 + k] =
          tokens.number(std::string("point ") + std::to_string(p) + " coordinate " + "xyz"[k] + " (3 numbers per point)");
    }
  }
  const std::string_view extra = tokens.next();
  if (!extra.empty()) {
    tokens.fail_at_token("unexpected data after the last point: " + quote_token(extra) + " (the header announces " +
                         std::to_string(cameras) + " cameras, " + std::to_string(points) + " points, " +
                         std::to_string(observations) + " observations)");
  }
  return problem;
}

BalProblem read_bal(const std::string& path) {
  if (path == "-") return parse_bal("standard input", standard_input());
  return parse_bal(path, read_maybe_compressed(path));
}

void write_bal(std::ostream& out, const BalProblem& problem) {
  char buffer[128];
  out << problem.num_cameras << ' ' << problem.num_points << ' ' << problem.observations.size() << '\n';
  for (const BalObservation& o : problem.observations) {
    std::snprintf(buffer, sizeof(buffer), "%d %d %.17g %.17g\n", o.camera, o.point, o.x, o.y);
    out << buffer;
  }
  for (const double value : problem.cameras) {
    std::snprintf(buffer, sizeof(buffer), "%.17g\n", value);
    out << buffer;
  }
  for (const double value : problem.points) {
    std::snprintf(buffer, sizeof(buffer), "%.17g\n", value);
    out << buffer;
  }
  if (!out) throw std::runtime_error("cannot write the BAL problem");
}

namespace {

/// The point of observation `o` in its camera's frame, P = R(w) X + t.
Eigen::Vector3d point_in_camera(const BalProblem& problem, const BalObservation& o) {
  const double* camera = problem.camera(o.camera);
  const Eigen::Vector3d w(camera[0], camera[1], camera[2]);
  const double angle = w.norm();
  const Eigen::Matrix3d R =
      angle > 0.0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  return R * Eigen::Vector3d(problem.point(o.point)) + Eigen::Vector3d(camera + 3);
}

}  // namespace

std::size_t count_points_behind_camera(const BalProblem& problem) {
  std::size_t behind = 0;
  for (const BalObservation& o : problem.observations) {
    if (point_in_camera(problem, o).z() >= 0.0) ++behind;
  }
  return behind;
}

long long first_observation_in_camera_plane(const BalProblem& problem) {
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    if (point_in_camera(problem, problem.observations[i]).z() == 0.0) return static_cast<long long>(i);
  }
  return -1;
}

}  // namespace cairn::io
