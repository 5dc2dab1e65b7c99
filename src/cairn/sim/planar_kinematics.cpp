#include "cairn/sim/planar_kinematics.hpp"

#include <algorithm>
#include <cmath>

#include "cairn/core/assert.hpp"

namespace cairn::sim {
namespace {

/// The quintic Hermite basis at s for (p0, h v0, h^2 a0, h^2 a1, h v1, p1), and its first and
/// second derivatives in s.
struct Hermite {
  double value[6];
  double first[6];
  double second[6];

  explicit Hermite(double s) {
    const double s2 = s * s, s3 = s2 * s, s4 = s3 * s, s5 = s4 * s;
    const double v[6] = {1.0 - 10.0 * s3 + 15.0 * s4 - 6.0 * s5, s - 6.0 * s3 + 8.0 * s4 - 3.0 * s5,
                         0.5 * s2 - 1.5 * s3 + 1.5 * s4 - 0.5 * s5, 0.5 * s3 - s4 + 0.5 * s5,
                         -4.0 * s3 + 7.0 * s4 - 3.0 * s5, 10.0 * s3 - 15.0 * s4 + 6.0 * s5};
    const double d[6] = {-30.0 * s2 + 60.0 * s3 - 30.0 * s4, 1.0 - 18.0 * s2 + 32.0 * s3 - 15.0 * s4,
                         s - 4.5 * s2 + 6.0 * s3 - 2.5 * s4, 1.5 * s2 - 4.0 * s3 + 2.5 * s4,
                         -12.0 * s2 + 28.0 * s3 - 15.0 * s4, 30.0 * s2 - 60.0 * s3 + 30.0 * s4};
    const double dd[6] = {-60.0 * s + 180.0 * s2 - 120.0 * s3, -36.0 * s + 96.0 * s2 - 60.0 * s3,
                          1.0 - 9.0 * s + 18.0 * s2 - 10.0 * s3, 3.0 * s - 12.0 * s2 + 10.0 * s3,
                          -24.0 * s + 84.0 * s2 - 60.0 * s3, 60.0 * s - 180.0 * s2 + 120.0 * s3};
    std::copy(v, v + 6, value);
    std::copy(d, d + 6, first);
    std::copy(dd, dd + 6, second);
  }

  /// sum of basis[i] * coefficient[i] for the six end conditions.
  template <typename T>
  static T combine(const double* basis, const T& p0, const T& hv0, const T& hha0, const T& hha1, const T& hv1,
                   const T& p1) {
    return basis[0] * p0 + basis[1] * hv0 + basis[2] * hha0 + basis[3] * hha1 + basis[4] * hv1 + basis[5] * p1;
  }
};

Vector2 velocity_of(const TrajectorySample& sample) {
  const double theta = sample.T_world_body.angle();
  return sample.speed_mps * Vector2(std::cos(theta), std::sin(theta));
}

BodyKinematics lift(const Vector2& p, const Vector2& v, const Vector2& a, double theta, double yaw_rate) {
  BodyKinematics out;
  out.T_world_body = core::SE3(Quaternion(Eigen::AngleAxisd(theta, Vector3::UnitZ())), Vector3(p.x(), p.y(), 0.0));
  out.v_world_mps = Vector3(v.x(), v.y(), 0.0);
  out.a_world_mps2 = Vector3(a.x(), a.y(), 0.0);
  out.omega_body_rad_s = Vector3(0.0, 0.0, yaw_rate);
  return out;
}

}  // namespace

PlanarKinematics::PlanarKinematics(std::vector<TrajectorySample> samples) : samples_(std::move(samples)) {
  CAIRN_ASSERT(samples_.size() >= 2, "PlanarKinematics needs at least two samples");
  for (std::size_t k = 1; k < samples_.size(); ++k) {
    CAIRN_ASSERT(samples_[k].stamp > samples_[k - 1].stamp, "PlanarKinematics: stamps must increase strictly");
  }
}

double PlanarKinematics::rate_of_change(std::size_t k, double (*value)(const TrajectorySample&)) const {
  const std::size_t before = k == 0 ? 0 : k - 1;
  const std::size_t after = std::min(k + 1, samples_.size() - 1);
  const double dt = static_cast<double>(samples_[after].stamp.nanoseconds() - samples_[before].stamp.nanoseconds()) * 1e-9;
  return (value(samples_[after]) - value(samples_[before])) / dt;
}

Vector2 PlanarKinematics::acceleration_at(std::size_t k) const {
  const TrajectorySample& s = samples_[k];
  const double theta = s.T_world_body.angle();
  const Vector2 forward(std::cos(theta), std::sin(theta));
  const Vector2 left(-forward.y(), forward.x());
  const double along = rate_of_change(k, [](const TrajectorySample& x) { return x.speed_mps; });
  return along * forward + s.speed_mps * s.yaw_rate_rad_s * left;
}

double PlanarKinematics::yaw_acceleration_at(std::size_t k) const {
  return rate_of_change(k, [](const TrajectorySample& x) { return x.yaw_rate_rad_s; });
}

BodyKinematics PlanarKinematics::operator()(double t_s) const {
  const TrajectorySample& first = samples_.front();
  const TrajectorySample& last = samples_.back();
  const auto at_rest = [](const TrajectorySample& s) {
    return lift(s.T_world_body.translation(), Vector2::Zero(), Vector2::Zero(), s.T_world_body.angle(), 0.0);
  };
  if (t_s < first.stamp.seconds()) return at_rest(first);
  if (t_s > last.stamp.seconds()) return at_rest(last);
  // The interval [k, k+1] holding t (the later one at a sample time, the last at the end).
  const auto after = std::upper_bound(samples_.begin(), samples_.end(), t_s,
                                      [](double t, const TrajectorySample& s) { return t < s.stamp.seconds(); });
  const std::size_t k = std::min(static_cast<std::size_t>(after - samples_.begin()), samples_.size() - 1) - 1;
  const TrajectorySample& a = samples_[k];
  const TrajectorySample& b = samples_[k + 1];
  const double h = static_cast<double>(b.stamp.nanoseconds() - a.stamp.nanoseconds()) * 1e-9;
  const double s = std::clamp((t_s - a.stamp.seconds()) / h, 0.0, 1.0);
  const Hermite H(s);

  const Vector2 p0 = a.T_world_body.translation();
  const Vector2 p1 = b.T_world_body.translation();
  const Vector2 hv0 = h * velocity_of(a);
  const Vector2 hv1 = h * velocity_of(b);
  const Vector2 hha0 = h * h * acceleration_at(k);
  const Vector2 hha1 = h * h * acceleration_at(k + 1);
  const Vector2 p = Hermite::combine(H.value, p0, hv0, hha0, hha1, hv1, p1);
  const Vector2 v = Hermite::combine(H.first, p0, hv0, hha0, hha1, hv1, p1) / h;
  const Vector2 acc = Hermite::combine(H.second, p0, hv0, hha0, hha1, hv1, p1) / (h * h);

  // Heading unwrapped across the interval (a step turns far less than pi).
  const double theta0 = a.T_world_body.angle();
  const double theta1 = theta0 + core::wrap_angle(b.T_world_body.angle() - theta0);
  const double hw0 = h * a.yaw_rate_rad_s;
  const double hw1 = h * b.yaw_rate_rad_s;
  const double hhy0 = h * h * yaw_acceleration_at(k);
  const double hhy1 = h * h * yaw_acceleration_at(k + 1);
  const double theta = Hermite::combine(H.value, theta0, hw0, hhy0, hhy1, hw1, theta1);
  const double yaw_rate = Hermite::combine(H.first, theta0, hw0, hhy0, hhy1, hw1, theta1) / h;
  return lift(p, v, acc, theta, yaw_rate);
}

}  // namespace cairn::sim
