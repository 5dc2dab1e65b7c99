#pragma once
/// \file
/// Shared machinery for the Lie group property tests (test_lie_groups.cpp and the per-group
/// files): a traits adapter that gives SO2, SE2, SO3 and SE3 one vector-valued interface, seeded
/// samplers, the hand-made hard cases, independent numeric references (matrix exponential,
/// Jacobian power series, central differences) and a tracker that reports the worst sample.
///
/// Tolerances (all on the max-abs entry of a difference, divided by max(1, max-abs entry of the
/// reference): relative for big quantities, absolute below 1). Translations are at most 10 per
/// coordinate, so every quantity is O(10) and double rounding alone gives errors ~1e-14.
///   kAxiomTol      1e-9   group axioms, exp/log round trips, Adj identities, J * J^-1 = I.
///                         Observed worst 2e-14; the slack is for the conditioning of log near
///                         pi, and still catches any wrong formula or sign.
///   kReferenceTol  1e-11  closed forms against the matrix exponential of hat(xi) and against
///                         the power series of the Jacobians (both accurate to ~1e-14 here).
///                         Observed worst 2e-12 (SE2's (theta - sin theta) / theta^2 term just
///                         above its switch). This is the check that resolves the Taylor branches
///                         and the switch points, where finite differences cannot.
///   kFiniteDifferenceTol 1e-7, central differences with step kFiniteDifferenceStep = 1e-6:
///                         truncation error ~h^2 |d3f| ~ 1e-11, rounding ~eps |T| / h ~ 4e-9.
///                         Observed worst 2e-9.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iomanip>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/core/se2.hpp"
#include "cairn/core/se3.hpp"
#include "cairn/core/so2.hpp"
#include "cairn/core/so3.hpp"

namespace cairn::core::testing {

inline constexpr double kPi = std::numbers::pi;
inline constexpr int kRandomSamples = 10'000;

inline constexpr double kAxiomTol = 1e-9;
inline constexpr double kReferenceTol = 1e-11;
inline constexpr double kFiniteDifferenceStep = 1e-6;
inline constexpr double kFiniteDifferenceTol = 1e-7;

/// Translations are drawn from [-kTranslationRange, kTranslationRange] per coordinate.
inline constexpr double kTranslationRange = 10.0;

using Rng = std::mt19937_64;

inline double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// Uniformly distributed unit vector.
inline Vector3 random_unit_vector(Rng& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Vector3 v;
  do {
    v = Vector3(normal(rng), normal(rng), normal(rng));
  } while (v.norm() < 1e-3);
  return v.normalized();
}

inline Vector3 random_translation(Rng& rng) {
  return Vector3(uniform(rng, -kTranslationRange, kTranslationRange),
                 uniform(rng, -kTranslationRange, kTranslationRange),
                 uniform(rng, -kTranslationRange, kTranslationRange));
}

/// Matrix with entries uniform in [-scale, scale].
template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> random_matrix(Rng& rng, double scale) {
  Eigen::Matrix<double, Rows, Cols> M;
  for (int i = 0; i < Rows; ++i) {
    for (int j = 0; j < Cols; ++j) M(i, j) = uniform(rng, -scale, scale);
  }
  return M;
}

/// Uniformly distributed unit quaternion (normalised Gaussian 4-vector), both signs of w.
inline Quaternion random_unit_quaternion(Rng& rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector4d v;
  do {
    v = Eigen::Vector4d(normal(rng), normal(rng), normal(rng), normal(rng));
  } while (v.norm() < 1e-3);
  v.normalize();
  return Quaternion(v(0), v(1), v(2), v(3));
}

/// Max-abs entry of (actual - expected) over max(1, max-abs entry of expected). NaN maps to +inf
/// so that it can never hide behind a comparison.
template <class A, class B>
double scaled_error(const Eigen::MatrixBase<A>& actual, const Eigen::MatrixBase<B>& expected) {
  const double diff = (actual - expected).cwiseAbs().maxCoeff();
  const double scale = std::max(1.0, expected.cwiseAbs().maxCoeff());
  const double e = diff / scale;
  return std::isnan(e) ? std::numeric_limits<double>::infinity() : e;
}

template <class M>
std::string to_string(const Eigen::MatrixBase<M>& m) {
  std::ostringstream out;
  out << std::setprecision(17) << "[";
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    for (Eigen::Index j = 0; j < m.cols(); ++j) out << (j == 0 ? "" : " ") << m(i, j);
    out << (i + 1 < m.rows() ? "; " : "");
  }
  out << "]";
  return out.str();
}

inline std::string to_string(double x) {
  std::ostringstream out;
  out << std::setprecision(17) << x;
  return out.str();
}

/// Keeps the largest error seen and a description of the sample that produced it, so a failing
/// property reports one line (the worst sample) instead of ten thousand. The worst error is also
/// recorded as a test property named `key` (visible with --gtest_output=xml), so the margins under
/// each tolerance can be read off a run.
class WorstCase {
 public:
  /// `key` names the checked quantity; letters, digits and underscores only (it becomes an XML
  /// attribute name).
  explicit WorstCase(std::string key) : key_(std::move(key)) {}

  /// `describe` is called only when `error` is a new worst.
  void add(double error, const std::function<std::string()>& describe) {
    ++count_;
    if (std::isnan(error)) error = std::numeric_limits<double>::infinity();
    if (count_ == 1 || error > worst_) {
      worst_ = error;
      sample_ = describe();
    }
  }

  /// Fails unless at least `min_samples` were checked and every error was <= tol.
  void expect_at_most(double tol, int min_samples) const {
    std::ostringstream worst;
    worst << std::setprecision(3) << worst_ << " (tol " << tol << ", " << count_ << " samples)";
    ::testing::Test::RecordProperty(key_, worst.str());
    EXPECT_GE(count_, min_samples) << key_ << ": too few samples were checked";
    EXPECT_LE(worst_, tol) << key_ << ": worst error over " << count_ << " samples at " << sample_;
  }

  double worst() const { return worst_; }
  int count() const { return count_; }

 private:
  std::string key_;
  int count_ = 0;
  double worst_ = 0.0;
  std::string sample_;
};

// ---------------------------------------------------------------------------------------------
// Traits: one interface over the four groups. Tangents are Eigen column vectors for all of them
// (SO2's scalar tangent is wrapped in a 1-vector).

template <class G>
struct LieTraits;

template <>
struct LieTraits<SO2> {
  static constexpr int kDoF = 1;
  static constexpr int kRotationDoF = 1;  // rotation is the last kRotationDoF tangent entries
  static constexpr int kDim = 2;          // size of matrix()
  static constexpr bool kPlanar = true;
  using Group = SO2;
  using Tangent = Eigen::Matrix<double, 1, 1>;
  using Square = Eigen::Matrix<double, 1, 1>;  // Adj and Jacobians
  using GroupMatrix = Matrix2;
  using Point = Vector2;

  static Tangent make_tangent(double angle, const Vector3& /*axis*/, const Vector3& /*t*/) {
    return Tangent::Constant(angle);
  }
  static Group exp(const Tangent& xi) { return SO2::exp(xi(0)); }
  static Tangent log(const Group& g) { return Tangent::Constant(g.log()); }
  static GroupMatrix matrix(const Group& g) { return g.matrix(); }
  static Point act_matrix(const GroupMatrix& M, const Point& p) { return M * p; }
  static Square adj(const Group& /*g*/) { return Square::Constant(SO2::Adj()); }
  static GroupMatrix hat(const Tangent& xi) { return SO2::hat(xi(0)); }
  static Tangent vee(const GroupMatrix& X) { return Tangent::Constant(SO2::vee(X)); }
  // SO(2) is abelian: every Jacobian is 1. The finite-difference and series tests check the
  // functions against exp and log like those of the other groups.
  static Square jl(const Tangent& xi) { return Square::Constant(SO2::left_jacobian(xi(0))); }
  static Square jr(const Tangent& xi) { return Square::Constant(SO2::right_jacobian(xi(0))); }
  static Square jl_inverse(const Tangent& xi) { return Square::Constant(SO2::left_jacobian_inverse(xi(0))); }
  static Square jr_inverse(const Tangent& xi) { return Square::Constant(SO2::right_jacobian_inverse(xi(0))); }
  /// Signed angle for the planar groups, |phi| for the spatial ones.
  static double angle(const Tangent& xi) { return xi(0); }
  static Group random_element(Rng& rng) { return SO2(uniform(rng, -kPi, kPi)); }
  static Point random_point(Rng& rng) { return random_translation(rng).head<2>(); }
  /// Elements with more than one representation worth testing (none for SO2).
  static std::vector<Group> variants(const Group& g) { return {g}; }
};

template <>
struct LieTraits<SE2> {
  static constexpr int kDoF = 3;
  static constexpr int kRotationDoF = 1;
  static constexpr int kDim = 3;
  static constexpr bool kPlanar = true;
  using Group = SE2;
  using Tangent = Vector3;
  using Square = Matrix3;
  using GroupMatrix = Matrix3;
  using Point = Vector2;

  static Tangent make_tangent(double angle, const Vector3& /*axis*/, const Vector3& t) {
    return Tangent(t.x(), t.y(), angle);
  }
  static Group exp(const Tangent& xi) { return SE2::exp(xi); }
  static Tangent log(const Group& g) { return g.log(); }
  static GroupMatrix matrix(const Group& g) { return g.matrix(); }
  static Point act_matrix(const GroupMatrix& M, const Point& p) {
    return (M * p.homogeneous()).head<2>();
  }
  static Square adj(const Group& g) { return g.Adj(); }
  static GroupMatrix hat(const Tangent& xi) { return SE2::hat(xi); }
  static Tangent vee(const GroupMatrix& X) { return SE2::vee(X); }
  static Square jl(const Tangent& xi) { return SE2::left_jacobian(xi); }
  static Square jr(const Tangent& xi) { return SE2::right_jacobian(xi); }
  static Square jl_inverse(const Tangent& xi) { return SE2::left_jacobian_inverse(xi); }
  static Square jr_inverse(const Tangent& xi) { return SE2::right_jacobian_inverse(xi); }
  static double angle(const Tangent& xi) { return xi(2); }
  static Group random_element(Rng& rng) {
    const Vector3 t = random_translation(rng);
    return SE2(t.x(), t.y(), uniform(rng, -kPi, kPi));
  }
  static Point random_point(Rng& rng) { return random_translation(rng).head<2>(); }
  static std::vector<Group> variants(const Group& g) { return {g}; }
};

template <>
struct LieTraits<SO3> {
  static constexpr int kDoF = 3;
  static constexpr int kRotationDoF = 3;
  static constexpr int kDim = 3;
  static constexpr bool kPlanar = false;
  using Group = SO3;
  using Tangent = Vector3;
  using Square = Matrix3;
  using GroupMatrix = Matrix3;
  using Point = Vector3;

  static Tangent make_tangent(double angle, const Vector3& axis, const Vector3& /*t*/) {
    return angle * axis;
  }
  static Group exp(const Tangent& xi) { return SO3::exp(xi); }
  static Tangent log(const Group& g) { return g.log(); }
  static GroupMatrix matrix(const Group& g) { return g.matrix(); }
  static Point act_matrix(const GroupMatrix& M, const Point& p) { return M * p; }
  static Square adj(const Group& g) { return g.Adj(); }
  static GroupMatrix hat(const Tangent& xi) { return SO3::hat(xi); }
  static Tangent vee(const GroupMatrix& X) { return SO3::vee(X); }
  static Square jl(const Tangent& xi) { return SO3::left_jacobian(xi); }
  static Square jr(const Tangent& xi) { return SO3::right_jacobian(xi); }
  static Square jl_inverse(const Tangent& xi) { return SO3::left_jacobian_inverse(xi); }
  static Square jr_inverse(const Tangent& xi) { return SO3::right_jacobian_inverse(xi); }
  static double angle(const Tangent& xi) { return xi.norm(); }
  /// Uniform over SO(3), both signs of the quaternion's w.
  static Group random_element(Rng& rng) { return SO3(random_unit_quaternion(rng)); }
  static Point random_point(Rng& rng) { return random_translation(rng); }
  /// q and -q are the same rotation; log must not care which one is stored.
  static std::vector<Group> variants(const Group& g) {
    return {g, SO3(Quaternion(-g.unit_quaternion().coeffs()))};
  }
};

template <>
struct LieTraits<SE3> {
  static constexpr int kDoF = 6;
  static constexpr int kRotationDoF = 3;
  static constexpr int kDim = 4;
  static constexpr bool kPlanar = false;
  using Group = SE3;
  using Tangent = Vector6;
  using Square = Matrix6;
  using GroupMatrix = Matrix4;
  using Point = Vector3;

  static Tangent make_tangent(double angle, const Vector3& axis, const Vector3& t) {
    Tangent xi;
    xi << t, angle * axis;
    return xi;
  }
  static Group exp(const Tangent& xi) { return SE3::exp(xi); }
  static Tangent log(const Group& g) { return g.log(); }
  static GroupMatrix matrix(const Group& g) { return g.matrix(); }
  static Point act_matrix(const GroupMatrix& M, const Point& p) {
    return (M * p.homogeneous()).head<3>();
  }
  static Square adj(const Group& g) { return g.Adj(); }
  static GroupMatrix hat(const Tangent& xi) { return SE3::hat(xi); }
  static Tangent vee(const GroupMatrix& X) { return SE3::vee(X); }
  static Square jl(const Tangent& xi) { return SE3::left_jacobian(xi); }
  static Square jr(const Tangent& xi) { return SE3::right_jacobian(xi); }
  static Square jl_inverse(const Tangent& xi) { return SE3::left_jacobian_inverse(xi); }
  static Square jr_inverse(const Tangent& xi) { return SE3::right_jacobian_inverse(xi); }
  static double angle(const Tangent& xi) { return xi.tail<3>().norm(); }
  static Group random_element(Rng& rng) {
    return SE3(random_unit_quaternion(rng), random_translation(rng));
  }
  static Point random_point(Rng& rng) { return random_translation(rng); }
  static std::vector<Group> variants(const Group& g) {
    return {g, SE3(Quaternion(-g.unit_quaternion().coeffs()), g.translation())};
  }
};

/// True when log(exp(xi)) must give xi back: the angle lies in the range log returns,
/// (-pi, pi] for the planar groups and [0, pi) in norm for the spatial ones (at |phi| = pi both
/// phi and -phi are valid logs).
template <class Traits>
bool log_is_unique(const typename Traits::Tangent& xi) {
  const double angle = Traits::angle(xi);
  if constexpr (Traits::kPlanar) {
    return angle > -kPi && angle <= kPi;
  } else {
    return angle < kPi;
  }
}

// ---------------------------------------------------------------------------------------------
// Samples.

/// Signed angles at which the implementations switch branches or lose digits:
/// 0 and tiny angles, both sides of every small-angle switch (1e-4 in so2/se2/so3 exp, log and
/// Jacobians; 2 asin(5e-5), where SO3::log switches on |q.vec| < 5e-5; 1e-3 in se3's Q), and the
/// approach to pi.
inline std::vector<double> hard_angles() {
  std::vector<double> magnitudes = {0.0, 1e-12, 1e-8, 1e-5};
  for (const double threshold : {1e-4, 2.0 * std::asin(5e-5), 1e-3}) {
    magnitudes.push_back(std::nextafter(threshold, 0.0));
    magnitudes.push_back(threshold);
    magnitudes.push_back(std::nextafter(threshold, 1.0));
    magnitudes.push_back(threshold * (1.0 - 1e-12));
    magnitudes.push_back(threshold * (1.0 + 1e-12));
    magnitudes.push_back(threshold * (1.0 - 1e-6));
    magnitudes.push_back(threshold * (1.0 + 1e-6));
  }
  magnitudes.insert(magnitudes.end(), {0.1, 1.0, kPi / 2.0, kPi - 1e-3, kPi - 1e-6, kPi - 1e-9});
  std::vector<double> angles;
  for (const double m : magnitudes) {
    angles.push_back(m);
    if (m != 0.0) angles.push_back(-m);
  }
  // -pi itself: exp must accept it, and log answers pi (planar) or the opposite axis (spatial).
  angles.insert(angles.end(), {kPi, -kPi, -kPi + 1e-12, std::nextafter(-kPi, 0.0)});
  return angles;
}

/// Axes aligned with the coordinate axes and a diagonal, plus three random ones (seeded).
inline std::vector<Vector3> hard_axes() {
  Rng rng(0xA7E5);
  return {Vector3::UnitX(),        Vector3::UnitY(),
          Vector3::UnitZ(),        Vector3(1.0, 1.0, 1.0).normalized(),
          random_unit_vector(rng), random_unit_vector(rng),
          random_unit_vector(rng)};
}

/// Every hard angle along every hard axis (the planar groups ignore the axis), each with zero,
/// small and random translation.
template <class Traits>
std::vector<typename Traits::Tangent> hard_tangents() {
  Rng rng(0x4A2D);
  const std::vector<Vector3> axes =
      Traits::kPlanar ? std::vector<Vector3>{Vector3::UnitZ()} : hard_axes();
  std::vector<Vector3> translations = {Vector3::Zero(), Vector3(1e-9, -2e-9, 3e-9)};
  for (int i = 0; i < 3; ++i) translations.push_back(random_translation(rng));
  std::vector<typename Traits::Tangent> out;
  for (const double angle : hard_angles()) {
    for (const Vector3& axis : axes) {
      for (const Vector3& t : translations) out.push_back(Traits::make_tangent(angle, axis, t));
    }
  }
  // The rotation-only groups need no translations: drop the duplicates.
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// Random tangent: angle uniform in [-max_angle, max_angle) along a uniform axis, translation
/// uniform in [-10, 10]^n.
template <class Traits>
typename Traits::Tangent random_tangent(Rng& rng, double max_angle = kPi) {
  const double angle = uniform(rng, -max_angle, max_angle);
  const Vector3 axis = random_unit_vector(rng);
  return Traits::make_tangent(angle, axis, random_translation(rng));
}

/// Random tangent near the identity: |angle| log-uniform in [1e-13, 3e-2], so that the Taylor
/// branches get random samples too (as manif's near-identity tests do).
template <class Traits>
typename Traits::Tangent random_small_tangent(Rng& rng) {
  const double angle =
      std::pow(10.0, uniform(rng, -13.0, -1.5)) * (uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0);
  const Vector3 axis = random_unit_vector(rng);
  return Traits::make_tangent(angle, axis, random_translation(rng));
}

inline constexpr int kNearIdentitySamples = 2'000;

/// The hard tangents, then kRandomSamples random ones (see random_tangent), then
/// kNearIdentitySamples near the identity.
template <class Traits>
std::vector<typename Traits::Tangent> test_tangents(Rng& rng, double max_angle = kPi) {
  std::vector<typename Traits::Tangent> out = hard_tangents<Traits>();
  for (int i = 0; i < kRandomSamples; ++i) out.push_back(random_tangent<Traits>(rng, max_angle));
  for (int i = 0; i < kNearIdentitySamples; ++i) out.push_back(random_small_tangent<Traits>(rng));
  return out;
}

/// exp of every hard tangent (in every stored representation), then kRandomSamples random
/// elements (uniform rotation, translation in [-10, 10]^n), then kNearIdentitySamples near the
/// identity.
template <class Traits>
std::vector<typename Traits::Group> test_elements(Rng& rng) {
  std::vector<typename Traits::Group> out;
  for (const auto& xi : hard_tangents<Traits>()) {
    for (const auto& g : Traits::variants(Traits::exp(xi))) out.push_back(g);
  }
  for (int i = 0; i < kRandomSamples; ++i) out.push_back(Traits::random_element(rng));
  for (int i = 0; i < kNearIdentitySamples; ++i) {
    for (const auto& g : Traits::variants(Traits::exp(random_small_tangent<Traits>(rng)))) {
      out.push_back(g);
    }
  }
  return out;
}

template <class Traits>
std::string describe(const typename Traits::Group& g) {
  return "T = " + to_string(Traits::matrix(g));
}

template <class Traits>
std::string describe_tangent(const typename Traits::Tangent& xi) {
  return "xi = " + to_string(xi.transpose());
}

// ---------------------------------------------------------------------------------------------
// Independent references.

/// Matrix exponential by scaling and squaring of a 30-term Taylor series (accurate to ~1e-14 for
/// the matrices used here).
template <class M>
M matrix_exponential(const M& X) {
  double norm = X.cwiseAbs().rowwise().sum().maxCoeff();
  int squarings = 0;
  while (norm > 0.5) {
    norm /= 2.0;
    ++squarings;
  }
  const M A = X * std::ldexp(1.0, -squarings);
  M sum = M::Identity();
  M term = M::Identity();
  for (int n = 1; n <= 30; ++n) {
    term = (term * A) / static_cast<double>(n);
    sum += term;
  }
  for (int i = 0; i < squarings; ++i) sum = (sum * sum).eval();
  return sum;
}

/// ad_xi (eta) = vee(hat(xi) hat(eta) - hat(eta) hat(xi)), built column by column from hat and
/// vee alone.
template <class Traits>
typename Traits::Square small_adjoint(const typename Traits::Tangent& xi) {
  using Tangent = typename Traits::Tangent;
  typename Traits::Square ad;
  const auto X = Traits::hat(xi);
  for (int j = 0; j < Traits::kDoF; ++j) {
    const auto E = Traits::hat(Tangent::Unit(j));
    ad.col(j) = Traits::vee(X * E - E * X);
  }
  return ad;
}

/// Jl(xi) = sum_n ad_xi^n / (n+1)!  (the series definition of the left Jacobian), summed
/// until the terms vanish. For |angle| <= pi and |rho| <= 20 the largest term is < 1e3, so the
/// series is accurate to ~1e-13 relative.
template <class Traits>
typename Traits::Square series_left_jacobian(const typename Traits::Tangent& xi) {
  using Square = typename Traits::Square;
  const Square ad = small_adjoint<Traits>(xi);
  Square sum = Square::Identity();
  Square term = Square::Identity();
  for (int n = 1; n < 200; ++n) {
    term = (term * ad) / static_cast<double>(n + 1);
    sum += term;
    if (term.cwiseAbs().maxCoeff() < 1e-18 * sum.cwiseAbs().maxCoeff()) break;
  }
  return sum;
}

/// Central-difference Jacobian of f: Tangent -> Tangent at d = 0.
template <class Traits, class F>
typename Traits::Square numeric_jacobian(const F& f) {
  using Tangent = typename Traits::Tangent;
  constexpr double h = kFiniteDifferenceStep;
  typename Traits::Square J;
  for (int j = 0; j < Traits::kDoF; ++j) {
    const Tangent d = h * Tangent::Unit(j);
    J.col(j) = (f(d) - f(-d)) / (2.0 * h);
  }
  return J;
}

}  // namespace cairn::core::testing
