// The manifolds of least_squares.hpp: R^n, SE(3) and SE(2) with the right-multiplied
// retraction T <- T exp(delta) of core/se3.hpp and core/se2.hpp.

#include <array>
#include <string>

#include "cairn/backend/least_squares.hpp"
#include "cairn/core/assert.hpp"
#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"

namespace cairn::backend {
namespace {

class Euclidean final : public Manifold {
 public:
  explicit Euclidean(int n) : n_(n), name_("R^" + std::to_string(n)) {}
  int ambient_size() const override { return n_; }
  int tangent_size() const override { return n_; }
  void plus(const double* x, const double* delta, double* x_plus) const override {
    for (int i = 0; i < n_; ++i) x_plus[i] = x[i] + delta[i];
  }
  std::string_view name() const override { return name_; }

 private:
  int n_;
  std::string name_;
};

class SE3Manifold final : public Manifold {
 public:
  int ambient_size() const override { return 7; }
  int tangent_size() const override { return 6; }
  void plus(const double* x, const double* delta, double* x_plus) const override {
    se3_to_values(se3_from_values(x) * core::SE3::exp(Eigen::Map<const cairn::Vector6>(delta)), x_plus);
  }
  std::string_view name() const override { return "SE(3)"; }
};

class SE2Manifold final : public Manifold {
 public:
  int ambient_size() const override { return 3; }
  int tangent_size() const override { return 3; }
  void plus(const double* x, const double* delta, double* x_plus) const override {
    se2_to_values(se2_from_values(x) * core::SE2::exp(cairn::Vector3(delta[0], delta[1], delta[2])), x_plus);
  }
  std::string_view name() const override { return "SE(2)"; }
};

constexpr int kMaxEuclidean = 32;

}  // namespace

const Manifold& euclidean_manifold(int n) {
  CAIRN_ASSERT(n >= 1 && n <= kMaxEuclidean, "euclidean_manifold: size must be in [1, 32]");
  static const auto manifolds = [] {
    std::array<const Euclidean*, kMaxEuclidean + 1> all{};
    for (int i = 1; i <= kMaxEuclidean; ++i) all[i] = new Euclidean(i);  // NOLINT: program lifetime
    return all;
  }();
  return *manifolds[n];
}

core::SE3 se3_from_values(const double* x) {
  return core::SE3(cairn::Quaternion(x[3], x[0], x[1], x[2]), cairn::Vector3(x[4], x[5], x[6]));  // w first
}

void se3_to_values(const core::SE3& T, double* x) {
  const cairn::Quaternion& q = T.unit_quaternion();
  x[0] = q.x();
  x[1] = q.y();
  x[2] = q.z();
  x[3] = q.w();
  for (int i = 0; i < 3; ++i) x[4 + i] = T.translation()[i];
}

core::SE2 se2_from_values(const double* x) { return core::SE2(x[0], x[1], x[2]); }

void se2_to_values(const core::SE2& T, double* x) {
  x[0] = T.translation().x();
  x[1] = T.translation().y();
  x[2] = T.angle();
}

const Manifold& se3_manifold() {
  static const SE3Manifold manifold;
  return manifold;
}

const Manifold& se2_manifold() {
  static const SE2Manifold manifold;
  return manifold;
}

}  // namespace cairn::backend
