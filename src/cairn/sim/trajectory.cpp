#include "cairn/sim/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "cairn/core/assert.hpp"

namespace cairn::sim {
namespace {

using core::SE2;

/// One piece of a stretch driven without stopping: a straight line (radius 0) or an arc.
struct Piece {
  Vector2 start = Vector2::Zero();
  double heading_rad = 0.0;
  double length_m = 0.0;
  /// 0 for a line; the arc's radius otherwise.
  double radius_m = 0.0;
  /// +1 turning left, -1 turning right (arcs only).
  double turn_sign = 0.0;
  /// Arc centre (arcs only).
  Vector2 center = Vector2::Zero();

  double curvature() const { return radius_m > 0.0 ? turn_sign / radius_m : 0.0; }

  SE2 pose_at(double s) const {
    if (radius_m == 0.0) {
      return SE2(start.x() + s * std::cos(heading_rad), start.y() + s * std::sin(heading_rad), heading_rad);
    }
    const double theta = heading_rad + turn_sign * s / radius_m;
    const Vector2 p = center + turn_sign * radius_m * Vector2(std::sin(theta), -std::cos(theta));
    return SE2(p.x(), p.y(), theta);
  }
};

/// A stretch driven between two stops, discretised for the speed profile: node k is at arc
/// length s[k], reached at time t[k] (from the stretch's start) with speed v[k].
struct Stretch {
  std::vector<Piece> pieces;
  std::vector<double> piece_end_s;
  std::vector<double> s;
  std::vector<double> v;
  std::vector<double> t;

  double duration() const { return t.empty() ? 0.0 : t.back(); }

  std::size_t piece_index(double arc) const {
    const auto it = std::upper_bound(piece_end_s.begin(), piece_end_s.end(), arc);
    return std::min<std::size_t>(static_cast<std::size_t>(it - piece_end_s.begin()), pieces.size() - 1);
  }

  TrajectorySample at(double time) const {
    time = std::clamp(time, 0.0, duration());
    auto it = std::upper_bound(t.begin(), t.end(), time);
    std::size_t k = it == t.begin() ? 0 : static_cast<std::size_t>(it - t.begin()) - 1;
    if (k + 1 >= t.size()) k = t.size() - 2;
    // Constant acceleration between nodes (the profile is built that way).
    const double dt = t[k + 1] - t[k];
    const double acceleration = dt > 0.0 ? (v[k + 1] - v[k]) / dt : 0.0;
    const double tau = time - t[k];
    const double arc = std::min(s[k] + v[k] * tau + 0.5 * acceleration * tau * tau, s.back());
    const double speed = v[k] + acceleration * tau;
    const std::size_t i = piece_index(arc);
    const double piece_start = i == 0 ? 0.0 : piece_end_s[i - 1];
    TrajectorySample sample;
    sample.T_world_body = pieces[i].pose_at(arc - piece_start);
    sample.speed_mps = speed;
    sample.yaw_rate_rad_s = speed * pieces[i].curvature();
    return sample;
  }
};

/// A turn on the spot by `angle_rad` (signed) with a trapezoidal yaw-rate profile.
struct Spin {
  Vector2 position = Vector2::Zero();
  double heading_rad = 0.0;
  double angle_rad = 0.0;
  double acceleration = 0.0;
  double ramp_s = 0.0;    // time to reach the peak rate
  double cruise_s = 0.0;  // time at the peak rate
  double peak_rate = 0.0;

  Spin(const Vector2& p, double heading, double angle, double rate, double accel)
      : position(p), heading_rad(heading), angle_rad(angle), acceleration(accel) {
    const double total = std::abs(angle);
    if (total >= rate * rate / accel) {
      peak_rate = rate;
      ramp_s = rate / accel;
      cruise_s = (total - rate * rate / accel) / rate;
    } else {
      peak_rate = std::sqrt(total * accel);
      ramp_s = peak_rate / accel;
      cruise_s = 0.0;
    }
  }

  double duration() const { return 2.0 * ramp_s + cruise_s; }

  TrajectorySample at(double time) const {
    time = std::clamp(time, 0.0, duration());
    double turned = 0.0;
    double rate = 0.0;
    if (time < ramp_s) {
      turned = 0.5 * acceleration * time * time;
      rate = acceleration * time;
    } else if (time < ramp_s + cruise_s) {
      turned = 0.5 * acceleration * ramp_s * ramp_s + peak_rate * (time - ramp_s);
      rate = peak_rate;
    } else {
      const double left = duration() - time;
      turned = std::abs(angle_rad) - 0.5 * acceleration * left * left;
      rate = acceleration * left;
    }
    const double sign = angle_rad >= 0.0 ? 1.0 : -1.0;
    TrajectorySample sample;
    sample.T_world_body = SE2(position.x(), position.y(), heading_rad + sign * turned);
    sample.yaw_rate_rad_s = sign * rate;
    return sample;
  }
};

/// Discretises the stretch (nodes at most 5 mm apart) and computes the speed profile.
void profile(Stretch& stretch, const TrajectoryOptions& options) {
  constexpr double kMaxStep = 0.005;
  double total = 0.0;
  for (const auto& piece : stretch.pieces) {
    total += piece.length_m;
    stretch.piece_end_s.push_back(total);
  }
  std::vector<double> limit;
  stretch.s.push_back(0.0);
  limit.push_back(0.0);
  double begin = 0.0;
  for (std::size_t i = 0; i < stretch.pieces.size(); ++i) {
    const Piece& piece = stretch.pieces[i];
    const int steps = std::max(1, static_cast<int>(std::ceil(piece.length_m / kMaxStep)));
    const double piece_limit = piece.radius_m > 0.0
                                   ? std::min(options.max_speed_mps, options.max_yaw_rate_rad_s * piece.radius_m)
                                   : options.max_speed_mps;
    // A node on a boundary obeys the slower of its two pieces.
    limit.back() = std::min(limit.back(), piece_limit);
    if (i == 0) limit.back() = 0.0;
    for (int k = 1; k <= steps; ++k) {
      stretch.s.push_back(k == steps ? stretch.piece_end_s[i] : begin + piece.length_m * k / steps);
      limit.push_back(piece_limit);
    }
    begin = stretch.piece_end_s[i];
  }
  limit.back() = 0.0;
  const std::size_t n = stretch.s.size();
  std::vector<double>& v = stretch.v;
  v = limit;
  const double a = options.max_acceleration_mps2;
  for (std::size_t k = 1; k < n; ++k) {
    v[k] = std::min(v[k], std::sqrt(v[k - 1] * v[k - 1] + 2.0 * a * (stretch.s[k] - stretch.s[k - 1])));
  }
  for (std::size_t k = n - 1; k-- > 0;) {
    v[k] = std::min(v[k], std::sqrt(v[k + 1] * v[k + 1] + 2.0 * a * (stretch.s[k + 1] - stretch.s[k])));
  }
  stretch.t.assign(n, 0.0);
  for (std::size_t k = 1; k < n; ++k) {
    const double ds = stretch.s[k] - stretch.s[k - 1];
    const double mean = 0.5 * (v[k] + v[k - 1]);
    stretch.t[k] = stretch.t[k - 1] + (mean > 0.0 ? ds / mean : 0.0);
  }
}

}  // namespace

bool TrajectoryOptions::is_valid(std::string* why) const {
  std::ostringstream problems;
  auto positive = [&](double value, const char* name) {
    if (!(value > 0.0) || !std::isfinite(value)) problems << name << " must be > 0 (found " << value << "); ";
  };
  positive(max_speed_mps, "max_speed_mps");
  positive(max_acceleration_mps2, "max_acceleration_mps2");
  positive(max_yaw_rate_rad_s, "max_yaw_rate_rad_s");
  positive(corner_radius_m, "corner_radius_m");
  positive(spin_yaw_rate_rad_s, "spin_yaw_rate_rad_s");
  positive(spin_yaw_acceleration_rad_s2, "spin_yaw_acceleration_rad_s2");
  positive(sample_period_s, "sample_period_s");
  if (!(max_arc_turn_rad > 0.0 && max_arc_turn_rad <= std::numbers::pi)) {
    problems << "max_arc_turn_rad must be in (0, pi] (found " << max_arc_turn_rad << "); ";
  }
  // Upper bounds keep a mistyped value from filling the memory (a lap is minutes of samples).
  if (laps < 1 || laps > 50) problems << "laps must be in [1, 50] (found " << laps << "); ";
  if (sample_period_s < 0.001) problems << "sample_period_s must be >= 0.001 (found " << sample_period_s << "); ";
  if (!(start_time_s >= 0.0 && start_time_s < 1e9)) problems << "start_time_s must be in [0, 1e9) (found " << start_time_s << "); ";
  const std::string text = problems.str();
  if (why != nullptr) *why = text.empty() ? "" : text.substr(0, text.size() - 2);
  return text.empty();
}

std::vector<TrajectorySample> generate_trajectory(const std::vector<Vector2>& route, const TrajectoryOptions& options,
                                                  bool closed_route, std::optional<double> start_heading_rad) {
  CAIRN_ASSERT(options.is_valid(nullptr), "generate_trajectory: invalid options (check is_valid first)");
  std::vector<Vector2> points;
  for (int lap = 0; lap < options.laps; ++lap) {
    for (const auto& p : route) {
      if (points.empty() || (p - points.back()).norm() > 1e-9) points.push_back(p);
    }
  }
  if (closed_route && (route.front() - points.back()).norm() > 1e-9) points.push_back(route.front());
  CAIRN_ASSERT(points.size() >= 2, "generate_trajectory: the route needs two distinct points");

  const std::size_t legs = points.size() - 1;
  std::vector<double> length(legs);
  std::vector<double> heading(legs);
  for (std::size_t i = 0; i < legs; ++i) {
    const Vector2 d = points[i + 1] - points[i];
    length[i] = d.norm();
    heading[i] = std::atan2(d.y(), d.x());
  }
  // Corner i sits at points[i], between leg i-1 and leg i.
  std::vector<double> turn(points.size(), 0.0);
  std::vector<double> radius(points.size(), 0.0);
  std::vector<double> cut(points.size(), 0.0);  // leg length eaten by the arc on each side
  std::vector<bool> spin(points.size(), false);
  for (std::size_t i = 1; i < legs; ++i) {
    turn[i] = core::wrap_angle(heading[i] - heading[i - 1]);
    const double magnitude = std::abs(turn[i]);
    if (magnitude < 1e-12) continue;
    if (magnitude > options.max_arc_turn_rad) {
      spin[i] = true;
      continue;
    }
    const double tangent = std::tan(0.5 * magnitude);
    radius[i] = std::min(options.corner_radius_m, 0.5 * std::min(length[i - 1], length[i]) / tangent);
    cut[i] = radius[i] * tangent;
  }

  // Alternate stretches and spins; every stretch starts and ends at rest.
  struct Phase {
    bool is_spin = false;
    std::size_t index = 0;  // into stretches or spins
    double start_time = 0.0;
  };
  std::vector<Stretch> stretches;
  std::vector<Spin> spins;
  std::vector<Phase> phases;
  double clock = 0.0;
  Stretch current;
  auto flush = [&] {
    if (current.pieces.empty()) return;
    profile(current, options);
    phases.push_back({false, stretches.size(), clock});
    clock += current.duration();
    stretches.push_back(std::move(current));
    current = Stretch{};
  };
  // A start facing elsewhere than the first leg: turn on the spot first.
  if (start_heading_rad) {
    const double initial_turn = core::wrap_angle(heading[0] - *start_heading_rad);
    if (std::abs(initial_turn) > 1e-12) {
      spins.emplace_back(points[0], *start_heading_rad, initial_turn, options.spin_yaw_rate_rad_s,
                         options.spin_yaw_acceleration_rad_s2);
      phases.push_back({true, spins.size() - 1, clock});
      clock += spins.back().duration();
    }
  }
  for (std::size_t i = 0; i < legs; ++i) {
    const Vector2 direction(std::cos(heading[i]), std::sin(heading[i]));
    const double begin = cut[i];
    const double end_cut = (i + 1 < legs) ? cut[i + 1] : 0.0;
    Piece line;
    line.start = points[i] + begin * direction;
    line.heading_rad = heading[i];
    line.length_m = length[i] - begin - end_cut;
    if (line.length_m > 0.0) current.pieces.push_back(line);
    const std::size_t corner = i + 1;
    if (corner >= legs) break;
    if (spin[corner]) {
      flush();
      spins.emplace_back(points[corner], heading[i], turn[corner], options.spin_yaw_rate_rad_s,
                         options.spin_yaw_acceleration_rad_s2);
      phases.push_back({true, spins.size() - 1, clock});
      clock += spins.back().duration();
    } else if (radius[corner] > 0.0) {
      Piece arc;
      arc.start = points[corner] - cut[corner] * direction;
      arc.heading_rad = heading[i];
      arc.radius_m = radius[corner];
      arc.turn_sign = turn[corner] > 0.0 ? 1.0 : -1.0;
      arc.length_m = radius[corner] * std::abs(turn[corner]);
      arc.center = arc.start + arc.turn_sign * radius[corner] * Vector2(-direction.y(), direction.x());
      current.pieces.push_back(arc);
    }
  }
  flush();

  const std::int64_t period_ns = static_cast<std::int64_t>(std::llround(options.sample_period_s * 1e9));
  const std::int64_t start_ns = static_cast<std::int64_t>(std::llround(options.start_time_s * 1e9));
  const auto count = static_cast<std::int64_t>(std::ceil(clock / options.sample_period_s - 1e-9)) + 1;
  std::vector<TrajectorySample> samples;
  samples.reserve(static_cast<std::size_t>(count));
  std::size_t phase = 0;
  for (std::int64_t j = 0; j < count; ++j) {
    const double time = static_cast<double>(j * period_ns) * 1e-9;
    while (phase + 1 < phases.size() && time >= phases[phase + 1].start_time) ++phase;
    const Phase& p = phases[phase];
    TrajectorySample sample = p.is_spin ? spins[p.index].at(time - p.start_time)
                                        : stretches[p.index].at(time - p.start_time);
    if (time >= clock) {  // arrived: at rest
      sample.speed_mps = 0.0;
      sample.yaw_rate_rad_s = 0.0;
    }
    sample.stamp = core::Timestamp::from_nanoseconds(start_ns + j * period_ns);
    samples.push_back(sample);
  }
  return samples;
}

double path_length(const std::vector<TrajectorySample>& samples) {
  double total = 0.0;
  for (std::size_t i = 1; i < samples.size(); ++i) {
    total += (samples[i].T_world_body.translation() - samples[i - 1].T_world_body.translation()).norm();
  }
  return total;
}

}  // namespace cairn::sim
