// Sim(3) on the least-squares engine: the manifold (the pattern of manifold.cpp's SE(3)) and the
// relative and prior factors of sim3_factors.hpp.

#include "cairn/backend/sim3_factors.hpp"

#include <cmath>

#include "cairn/core/sim3.hpp"

namespace cairn::backend {
namespace {

using Tangent = core::Sim3::Tangent;
using RowMajor7 = Eigen::Matrix<double, 7, 7, Eigen::RowMajor>;

class Sim3Manifold final : public Manifold {
 public:
  int ambient_size() const override { return 8; }
  int tangent_size() const override { return 7; }
  void plus(const double* x, const double* delta, double* x_plus) const override {
    sim3_to_values(sim3_from_values(x) * core::Sim3::exp(Eigen::Map<const Tangent>(delta)), x_plus);
  }
  std::string_view name() const override { return "Sim(3)"; }
};

bool wants(const double* const* jacobians, int k) { return jacobians != nullptr && jacobians[k] != nullptr; }

constexpr double kMaxLogScale = 50.0;

bool is_valid_scale(const double* x) { return std::isfinite(x[7]) && x[7] > 0.0; }

}  // namespace

const Manifold& sim3_manifold() {
  static const Sim3Manifold manifold;
  return manifold;
}

core::Sim3 sim3_from_values(const double* x) {
  return core::Sim3(cairn::Quaternion(x[3], x[0], x[1], x[2]), cairn::Vector3(x[4], x[5], x[6]), x[7]);  // w first
}

void sim3_to_values(const core::Sim3& S, double* x) {
  const cairn::Quaternion& q = S.unit_quaternion();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  for (int i = 0; i < 3; ++i) x[4 + i] = S.translation()[i];
  x[7] = S.scale();
}

bool Sim3RelativeFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  // A scale <= 0 is outside the manifold (only a caller's bad start can produce it: plus keeps
  // s = s e^sigma > 0); report it as undefined rather than asserting.
  if (!is_valid_scale(values[0]) || !is_valid_scale(values[1])) return false;
  const core::Sim3 S_world_i = sim3_from_values(values[0]);
  const core::Sim3 S_world_j = sim3_from_values(values[1]);
  const core::Sim3 S_i_j = S_world_i.inverse() * S_world_j;
  const core::Sim3 E = S_i_j_.inverse() * S_i_j;
  Eigen::Map<Tangent> r(residual);
  const bool want_i = wants(jacobians, 0);
  const bool want_j = wants(jacobians, 1);
  if (!want_i && !want_j) {
    r = sqrt_information_ * E.log();
    return r.allFinite();
  }
  const Tangent e = E.log();
  // Jr^-1's coupling series needs |(sigma, phi)| < 60 (sim3.hpp): a relative scale of e^50 is
  // no step to take.
  if (!(std::abs(e(6)) < kMaxLogScale)) return false;
  const core::Sim3::Jacobian J_e = core::Sim3::right_jacobian_inverse(e);
  r = sqrt_information_ * e;
  // dr/d(delta_i) = -(dr/d(delta_j)) Adj(S_j^-1 S_i): the product L Jr^-1 once for both.
  const RowMajor7 J_r_j = sqrt_information_ * J_e;
  if (want_i) Eigen::Map<RowMajor7>(jacobians[0]).noalias() = -J_r_j * S_i_j.inverse().Adj();
  if (want_j) Eigen::Map<RowMajor7>{jacobians[1]} = J_r_j;
  return r.allFinite();
}

bool Sim3PriorFactor::evaluate(const double* const* values, double* residual, double* const* jacobians) const {
  if (!is_valid_scale(values[0])) return false;
  const core::Sim3 E = S_world_body_.inverse() * sim3_from_values(values[0]);
  Eigen::Map<Tangent> r(residual);
  if (!wants(jacobians, 0)) {
    r = sqrt_information_ * E.log();
    return r.allFinite();
  }
  const Tangent e = E.log();
  if (!(std::abs(e(6)) < kMaxLogScale)) return false;
  r = sqrt_information_ * e;
  Eigen::Map<RowMajor7>(jacobians[0]).noalias() = sqrt_information_ * core::Sim3::right_jacobian_inverse(e);
  return r.allFinite();
}

}  // namespace cairn::backend
