// Property tests shared by SO2, SE2, SO3 and SE3: group axioms, exp/log, hat/vee, Adj and the
// four Jacobians, each over the hard cases of lie_test_utils.hpp plus kRandomSamples (10,000)
// random and kNearIdentitySamples (2,000) near-identity samples, with seeded RNGs. Tolerances
// and the error measure are explained at the top of lie_test_utils.hpp.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>
#include <vector>

#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {
namespace {

template <class G>
class LieGroupProperties : public ::testing::Test {};

using Groups = ::testing::Types<SO2, SE2, SO3, SE3>;

struct GroupNames {
  template <class G>
  static std::string GetName(int /*index*/) {
    if constexpr (std::is_same_v<G, SO2>) return "SO2";
    if constexpr (std::is_same_v<G, SE2>) return "SE2";
    if constexpr (std::is_same_v<G, SO3>) return "SO3";
    if constexpr (std::is_same_v<G, SE3>) return "SE3";
  }
};

TYPED_TEST_SUITE(LieGroupProperties, Groups, GroupNames);

// -- exp and log ------------------------------------------------------------------------------

TYPED_TEST(LieGroupProperties, ExpOfLogIsTheElement) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(101);
  const auto elements = test_elements<Traits>(rng);
  WorstCase round_trip("exp_log_error");
  WorstCase range("log_angle_out_of_range");
  for (const auto& g : elements) {
    const auto xi = Traits::log(g);
    round_trip.add(scaled_error(Traits::matrix(Traits::exp(xi)), Traits::matrix(g)),
                   [&] { return describe<Traits>(g); });
    // log returns the principal angle: exactly (-pi, pi] in the plane (the stored angle), and
    // |phi| in [0, pi] in space, where |phi| = |2 atan2(|v|, w) / |v| * v| may round to a few
    // ulp above pi.
    const double angle = Traits::angle(xi);
    const double outside =
        Traits::kPlanar ? (angle > -kPi && angle <= kPi ? 0.0 : 1.0) : std::max(0.0, angle - kPi);
    range.add(outside,
              [&] { return describe<Traits>(g) + " log " + describe_tangent<Traits>(xi); });
  }
  round_trip.expect_at_most(kAxiomTol, kRandomSamples);
  range.expect_at_most(4.0 * (std::nextafter(kPi, 4.0) - kPi), kRandomSamples);
}

TYPED_TEST(LieGroupProperties, LogOfExpIsTheTangent) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(102);
  WorstCase round_trip("log_exp_error");
  WorstCase rotation("log_exp_relative_rotation_error");
  WorstCase ambiguous("log_exp_at_pi_error");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto g = Traits::exp(xi);
    const auto xi2 = Traits::log(g);
    if (log_is_unique<Traits>(xi)) {
      round_trip.add(scaled_error(xi2, xi), [&] { return describe_tangent<Traits>(xi); });
      // The rotation part keeps its relative accuracy however small the angle is (observed
      // worst 4e-16; 1e-12 still fails a Taylor branch with a wrong second-order term).
      const double angle = Traits::angle(xi);
      const double rotation_difference = (xi2 - xi).template tail<Traits::kRotationDoF>().norm();
      const double rotation_error =
          angle == 0.0 ? rotation_difference : rotation_difference / std::abs(angle);
      rotation.add(rotation_error, [&] { return describe_tangent<Traits>(xi); });
    } else {
      // |angle| = pi: phi and -phi are both logs; the result must still map back to g.
      ambiguous.add(scaled_error(Traits::matrix(Traits::exp(xi2)), Traits::matrix(g)) +
                        std::abs(std::abs(Traits::angle(xi2)) - kPi),
                    [&] { return describe_tangent<Traits>(xi); });
    }
  }
  round_trip.expect_at_most(kAxiomTol, kRandomSamples);
  rotation.expect_at_most(1e-12, kRandomSamples);
  ambiguous.expect_at_most(kAxiomTol, 1);
}

TYPED_TEST(LieGroupProperties, ExpMatchesMatrixExponentialOfHat) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(103);
  WorstCase worst("exp_vs_matrix_exponential");
  // Angles up to 3 pi: exp is defined on the whole tangent space, not just the principal range.
  for (const auto& xi : test_tangents<Traits>(rng, 3.0 * kPi)) {
    worst.add(scaled_error(Traits::matrix(Traits::exp(xi)), matrix_exponential(Traits::hat(xi))),
              [&] { return describe_tangent<Traits>(xi); });
  }
  worst.expect_at_most(kReferenceTol, kRandomSamples);
}

// -- group axioms -----------------------------------------------------------------------------

TYPED_TEST(LieGroupProperties, InverseAxioms) {
  using Traits = LieTraits<TypeParam>;
  using GroupMatrix = typename Traits::GroupMatrix;
  Rng rng(104);
  WorstCase right("T_times_T_inverse");
  WorstCase left("T_inverse_times_T");
  WorstCase matrix("inverse_matrix");
  WorstCase twice("inverse_of_inverse");
  const GroupMatrix I = GroupMatrix::Identity();
  for (const auto& g : test_elements<Traits>(rng)) {
    const auto g_inv = g.inverse();
    const auto d = [&] { return describe<Traits>(g); };
    right.add(scaled_error(Traits::matrix(g * g_inv), I), d);
    left.add(scaled_error(Traits::matrix(g_inv * g), I), d);
    const GroupMatrix M_inv = Traits::matrix(g).inverse();
    matrix.add(scaled_error(Traits::matrix(g_inv), M_inv), d);
    twice.add(scaled_error(Traits::matrix(g_inv.inverse()), Traits::matrix(g)), d);
  }
  for (const auto* w : {&right, &left, &matrix, &twice})
    w->expect_at_most(kAxiomTol, kRandomSamples);
}

TYPED_TEST(LieGroupProperties, IdentityIsNeutral) {
  using Traits = LieTraits<TypeParam>;
  using G = TypeParam;
  Rng rng(105);
  WorstCase worst("identity_neutral");
  for (const auto& g : test_elements<Traits>(rng)) {
    const auto M = Traits::matrix(g);
    worst.add(scaled_error(Traits::matrix(G() * g), M) + scaled_error(Traits::matrix(g * G()), M),
              [&] { return describe<Traits>(g); });
  }
  worst.expect_at_most(kAxiomTol, kRandomSamples);
  EXPECT_EQ(Traits::matrix(G()), LieTraits<TypeParam>::GroupMatrix::Identity());
  EXPECT_EQ(Traits::log(G()), LieTraits<TypeParam>::Tangent::Zero());
}

TYPED_TEST(LieGroupProperties, CompositionIsAssociative) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(106);
  WorstCase worst("associativity");
  for (const auto& a : test_elements<Traits>(rng)) {
    const auto b = Traits::random_element(rng);
    const auto c = Traits::random_element(rng);
    worst.add(scaled_error(Traits::matrix((a * b) * c), Traits::matrix(a * (b * c))), [&] {
      return describe<Traits>(a) + ", " + describe<Traits>(b) + ", " + describe<Traits>(c);
    });
  }
  worst.expect_at_most(kAxiomTol, kRandomSamples);
}

TYPED_TEST(LieGroupProperties, MatrixOfProductIsProductOfMatrices) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(107);
  WorstCase worst("matrix_of_product");
  for (const auto& a : test_elements<Traits>(rng)) {
    const auto b = Traits::random_element(rng);
    worst.add(scaled_error(Traits::matrix(a * b), Traits::matrix(a) * Traits::matrix(b)),
              [&] { return describe<Traits>(a) + ", " + describe<Traits>(b); });
  }
  worst.expect_at_most(kAxiomTol, kRandomSamples);
}

TYPED_TEST(LieGroupProperties, ActionOnPointsMatchesMatrix) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(108);
  WorstCase action("action_vs_matrix");
  WorstCase composed("action_of_product");
  for (const auto& a : test_elements<Traits>(rng)) {
    const auto b = Traits::random_element(rng);
    const typename Traits::Point p = Traits::random_point(rng);
    const auto d = [&] { return describe<Traits>(a) + " p = " + to_string(p.transpose()); };
    action.add(scaled_error(a * p, Traits::act_matrix(Traits::matrix(a), p)), d);
    // p_a = T_a_b * p_b with inner frames cancelling: (T_a_b * T_b_c) * p_c = T_a_b * (T_b_c *
    // p_c).
    composed.add(scaled_error((a * b) * p, a * (b * p)), d);
  }
  action.expect_at_most(kAxiomTol, kRandomSamples);
  composed.expect_at_most(kAxiomTol, kRandomSamples);
}

// -- hat and vee ------------------------------------------------------------------------------

TYPED_TEST(LieGroupProperties, HatVeeRoundTrip) {
  using Traits = LieTraits<TypeParam>;
  using Tangent = typename Traits::Tangent;
  Rng rng(109);
  int exact = 0;
  int checked = 0;
  WorstCase linear("hat_linearity");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto X = Traits::hat(xi);
    // Both are pure copies of entries: exact, not approximate.
    exact += (Traits::vee(X) == xi && Traits::hat(Traits::vee(X)) == X) ? 1 : 0;
    ++checked;
    const Tangent eta = random_tangent<Traits>(rng);
    const double alpha = uniform(rng, -2.0, 2.0);
    linear.add(scaled_error(Traits::hat(alpha * xi + eta), alpha * X + Traits::hat(eta)),
               [&] { return describe_tangent<Traits>(xi); });
  }
  EXPECT_EQ(exact, checked);
  EXPECT_GE(checked, kRandomSamples);
  linear.expect_at_most(1e-14, kRandomSamples);
}

// -- adjoint ----------------------------------------------------------------------------------

TYPED_TEST(LieGroupProperties, AdjointConjugatesExp) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(110);
  WorstCase group("T_exp_T_inverse_vs_exp_Adj");
  WorstCase algebra("T_hat_T_inverse_vs_hat_Adj");
  const auto tangents = test_tangents<Traits>(rng);
  const auto elements = test_elements<Traits>(rng);
  for (std::size_t i = 0; i < std::max(tangents.size(), elements.size()); ++i) {
    const auto& xi = tangents[i % tangents.size()];
    const auto& g = elements[i % elements.size()];
    const auto d = [&] { return describe<Traits>(g) + " " + describe_tangent<Traits>(xi); };
    const auto adj = Traits::adj(g);
    group.add(scaled_error(Traits::matrix(g * Traits::exp(xi) * g.inverse()),
                           Traits::matrix(Traits::exp(adj * xi))),
              d);
    const auto M = Traits::matrix(g);
    algebra.add(scaled_error(Traits::hat(adj * xi), M * Traits::hat(xi) * M.inverse()), d);
  }
  group.expect_at_most(kAxiomTol, kRandomSamples);
  algebra.expect_at_most(kAxiomTol, kRandomSamples);
}

TYPED_TEST(LieGroupProperties, AdjointIsAHomomorphism) {
  using Traits = LieTraits<TypeParam>;
  using Square = typename Traits::Square;
  Rng rng(111);
  WorstCase product("Adj_of_product");
  WorstCase inverse("Adj_of_inverse");
  for (const auto& a : test_elements<Traits>(rng)) {
    const auto b = Traits::random_element(rng);
    const auto d = [&] { return describe<Traits>(a) + ", " + describe<Traits>(b); };
    product.add(scaled_error(Traits::adj(a * b), Traits::adj(a) * Traits::adj(b)), d);
    const Square adj_inv = Traits::adj(a).inverse();
    inverse.add(scaled_error(Traits::adj(a.inverse()), adj_inv), d);
  }
  product.expect_at_most(kAxiomTol, kRandomSamples);
  inverse.expect_at_most(kAxiomTol, kRandomSamples);
}

// -- Jacobians --------------------------------------------------------------------------------

// Jl(xi) = d/dd log(exp(xi + d) * exp(xi)^-1) and Jr(xi) = d/dd log(exp(xi)^-1 * exp(xi + d)),
// at d = 0 (the left and right Jacobians of Sola et al. 2018, Sec. IV), by central differences.
TYPED_TEST(LieGroupProperties, JacobiansMatchFiniteDifferences) {
  using Traits = LieTraits<TypeParam>;
  using Tangent = typename Traits::Tangent;
  Rng rng(112);
  WorstCase left("Jl_vs_finite_differences");
  WorstCase right("Jr_vs_finite_differences");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto g = Traits::exp(xi);
    const auto g_inv = g.inverse();
    const auto d = [&] { return describe_tangent<Traits>(xi); };
    const auto Jl = numeric_jacobian<Traits>(
        [&](const Tangent& delta) { return Traits::log(Traits::exp(xi + delta) * g_inv); });
    const auto Jr = numeric_jacobian<Traits>(
        [&](const Tangent& delta) { return Traits::log(g_inv * Traits::exp(xi + delta)); });
    left.add(scaled_error(Traits::jl(xi), Jl), d);
    right.add(scaled_error(Traits::jr(xi), Jr), d);
  }
  left.expect_at_most(kFiniteDifferenceTol, kRandomSamples);
  right.expect_at_most(kFiniteDifferenceTol, kRandomSamples);
}

// Jl^-1(xi) = d/dd log(exp(d) * exp(xi)) and Jr^-1(xi) = d/dd log(exp(xi) * exp(d)) at d = 0:
// the derivatives of log itself. Samples within 1e-4 of angle pi are left out because a step
// of 1e-6 may carry the log across its branch cut there; their inverses are checked against
// Jl and the series below.
TYPED_TEST(LieGroupProperties, InverseJacobiansMatchFiniteDifferencesOfLog) {
  using Traits = LieTraits<TypeParam>;
  using Tangent = typename Traits::Tangent;
  Rng rng(113);
  WorstCase left("Jl_inverse_vs_finite_differences");
  WorstCase right("Jr_inverse_vs_finite_differences");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    if (std::abs(Traits::angle(xi)) > kPi - 1e-4) continue;
    const auto g = Traits::exp(xi);
    const auto d = [&] { return describe_tangent<Traits>(xi); };
    const auto Jl_inv = numeric_jacobian<Traits>(
        [&](const Tangent& delta) { return Traits::log(Traits::exp(delta) * g); });
    const auto Jr_inv = numeric_jacobian<Traits>(
        [&](const Tangent& delta) { return Traits::log(g * Traits::exp(delta)); });
    left.add(scaled_error(Traits::jl_inverse(xi), Jl_inv), d);
    right.add(scaled_error(Traits::jr_inverse(xi), Jr_inv), d);
  }
  left.expect_at_most(kFiniteDifferenceTol, kRandomSamples);
  right.expect_at_most(kFiniteDifferenceTol, kRandomSamples);
}

// The closed forms against the power series Jl = sum ad^n / (n+1)!, Jr = sum (-ad)^n / (n+1)!
// and their matrix inverses. Unlike finite differences this resolves errors far below 1e-6, so
// it is the test that pins the Taylor branches on both sides of each small-angle switch.
TYPED_TEST(LieGroupProperties, JacobiansMatchSeries) {
  using Traits = LieTraits<TypeParam>;
  using Square = typename Traits::Square;
  Rng rng(114);
  WorstCase left("Jl_vs_series");
  WorstCase right("Jr_vs_series");
  WorstCase left_inverse("Jl_inverse_vs_inverse_of_series");
  WorstCase right_inverse("Jr_inverse_vs_inverse_of_series");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto d = [&] { return describe_tangent<Traits>(xi); };
    const Square Jl = series_left_jacobian<Traits>(xi);
    const Square Jr = series_left_jacobian<Traits>(-xi);
    const Square Jl_inv = Jl.inverse();
    const Square Jr_inv = Jr.inverse();
    left.add(scaled_error(Traits::jl(xi), Jl), d);
    right.add(scaled_error(Traits::jr(xi), Jr), d);
    left_inverse.add(scaled_error(Traits::jl_inverse(xi), Jl_inv), d);
    right_inverse.add(scaled_error(Traits::jr_inverse(xi), Jr_inv), d);
  }
  for (const auto* w : {&left, &right, &left_inverse, &right_inverse}) {
    w->expect_at_most(kReferenceTol, kRandomSamples);
  }
}

TYPED_TEST(LieGroupProperties, JacobianTimesItsInverseIsIdentity) {
  using Traits = LieTraits<TypeParam>;
  using Square = typename Traits::Square;
  Rng rng(115);
  const Square I = Square::Identity();
  WorstCase left("Jl_times_Jl_inverse");
  WorstCase right("Jr_times_Jr_inverse");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto d = [&] { return describe_tangent<Traits>(xi); };
    const Square Jl = Traits::jl(xi);
    const Square Jl_inv = Traits::jl_inverse(xi);
    const Square Jr = Traits::jr(xi);
    const Square Jr_inv = Traits::jr_inverse(xi);
    left.add(scaled_error(Jl * Jl_inv, I) + scaled_error(Jl_inv * Jl, I), d);
    right.add(scaled_error(Jr * Jr_inv, I) + scaled_error(Jr_inv * Jr, I), d);
  }
  left.expect_at_most(kAxiomTol, kRandomSamples);
  right.expect_at_most(kAxiomTol, kRandomSamples);
}

TYPED_TEST(LieGroupProperties, RightJacobianIsLeftJacobianOfNegative) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(116);
  WorstCase jacobian("Jr_vs_Jl_of_minus_xi");
  WorstCase inverse("Jr_inverse_vs_Jl_inverse_of_minus_xi");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    const auto d = [&] { return describe_tangent<Traits>(xi); };
    jacobian.add(scaled_error(Traits::jr(xi), Traits::jl(-xi)), d);
    inverse.add(scaled_error(Traits::jr_inverse(xi), Traits::jl_inverse(-xi)), d);
  }
  jacobian.expect_at_most(kAxiomTol, kRandomSamples);
  inverse.expect_at_most(kAxiomTol, kRandomSamples);
}

// Jl(xi) = Adj(exp(xi)) Jr(xi) (Sola et al. 2018, Sec. IV).
TYPED_TEST(LieGroupProperties, LeftJacobianIsAdjointTimesRightJacobian) {
  using Traits = LieTraits<TypeParam>;
  Rng rng(117);
  WorstCase worst("Jl_vs_Adj_Jr");
  for (const auto& xi : test_tangents<Traits>(rng)) {
    worst.add(scaled_error(Traits::jl(xi), Traits::adj(Traits::exp(xi)) * Traits::jr(xi)),
              [&] { return describe_tangent<Traits>(xi); });
  }
  worst.expect_at_most(kAxiomTol, kRandomSamples);
}

}  // namespace
}  // namespace cairn::core::testing
