// Sim(3) property tests: group axioms, exp against the matrix exponential, exp/log round trips
// (near-zero and near-pi angles, near-zero sigma, and both sides of the series / closed-form
// switch at |(sigma, |phi|)| = 1), Adj, hat/vee/ad, action on points, the four Jacobians against
// their power series and central differences, and the reduction to SE(3) at scale 1. The shared
// helpers and tolerances are those of lie_test_utils.hpp.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "cairn/core/sim3.hpp"
#include "core/lie_test_utils.hpp"

namespace cairn::core::testing {

// The part of the traits interface that lie_test_utils' references (small_adjoint,
// series_left_jacobian, numeric_jacobian) use.
template <>
struct LieTraits<Sim3> {
  static constexpr int kDoF = 7;
  using Group = Sim3;
  using Tangent = Sim3::Tangent;
  using Square = Sim3::Jacobian;
  using GroupMatrix = Matrix4;
  static GroupMatrix hat(const Tangent& xi) { return Sim3::hat(xi); }
  static Tangent vee(const GroupMatrix& X) { return Sim3::vee(X); }
};

namespace {

using Traits = LieTraits<Sim3>;
using Tangent = Sim3::Tangent;
using Jacobian = Sim3::Jacobian;

Tangent make_tangent(const Vector3& rho, const Vector3& phi, double sigma) {
  Tangent xi;
  xi << rho, phi, sigma;
  return xi;
}

std::string describe_sim3(const Sim3& S) { return "S = " + to_string(S.matrix()); }
std::string describe_xi(const Tangent& xi) { return "xi = " + to_string(xi.transpose()); }

/// Log-scales where the implementation switches or could lose digits: 0 and tiny values (the
/// series branch of W), both sides of |(sigma, a)| = 1 at a = 0 (the closed form's a = 0 limit),
/// moderate and large scales (e^2 = 7.4).
std::vector<double> hard_sigmas() {
  std::vector<double> out;
  for (const double m : {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 0.1, 0.5, std::sqrt(0.5), 1.0 - 1e-12, 1.0,
                         1.0 + 1e-12, 1.5, 2.0}) {
    out.push_back(m);
    if (m != 0.0) out.push_back(-m);
  }
  return out;
}

/// SE(3)'s hard tangents (lie_test_utils: angles at every switch and approaching pi, several
/// axes and translations) each with every hard sigma, plus (sigma, a) on and around the circle
/// |(sigma, a)| = 1 where W's coefficients switch from their series to the closed forms.
std::vector<Tangent> hard_sim3_tangents() {
  std::vector<Tangent> out;
  const std::vector<double> sigmas = hard_sigmas();
  for (const Vector6& xi : hard_tangents<LieTraits<SE3>>()) {
    for (const double sigma : sigmas) out.push_back(make_tangent(xi.head<3>(), xi.tail<3>(), sigma));
  }
  Rng rng(0x5173);
  for (const double a : {0.0, 1e-8, 1e-4, 0.3, 0.6, std::sqrt(0.5), 0.8, 0.99, 1.0 - 1e-9}) {
    for (const double f : {1.0 - 1e-12, 1.0, 1.0 + 1e-12, 1.0 - 1e-6, 1.0 + 1e-6}) {
      const double sigma = std::sqrt(1.0 - a * a) * f;
      for (const double sign : {1.0, -1.0}) {
        // and the mirror case: a on the circle for small sigma
        out.push_back(make_tangent(random_translation(rng), a * f * random_unit_vector(rng), sign * sigma));
        out.push_back(make_tangent(random_translation(rng), sigma * random_unit_vector(rng), sign * a * f));
      }
    }
  }
  return out;
}

Tangent random_sim3_tangent(Rng& rng, double max_angle = kPi, double max_sigma = 2.0) {
  return make_tangent(random_translation(rng), uniform(rng, -max_angle, max_angle) * random_unit_vector(rng),
                      uniform(rng, -max_sigma, max_sigma));
}

/// Angle and sigma independently log-uniform in [1e-13, 3e-2] with random signs.
Tangent random_small_sim3_tangent(Rng& rng) {
  const auto small = [&] {
    return std::pow(10.0, uniform(rng, -13.0, -1.5)) * (uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0);
  };
  const double angle = small();
  return make_tangent(random_translation(rng), angle * random_unit_vector(rng), small());
}

/// Hard tangents, kRandomSamples random ones (angle up to max_angle, sigma in [-2, 2]) and
/// kNearIdentitySamples near the identity.
std::vector<Tangent> sim3_test_tangents(Rng& rng, double max_angle = kPi) {
  std::vector<Tangent> out = hard_sim3_tangents();
  for (int i = 0; i < kRandomSamples; ++i) out.push_back(random_sim3_tangent(rng, max_angle));
  for (int i = 0; i < kNearIdentitySamples; ++i) out.push_back(random_small_sim3_tangent(rng));
  return out;
}

Sim3 random_sim3(Rng& rng) {
  return Sim3(random_unit_quaternion(rng), random_translation(rng), std::exp(uniform(rng, -2.0, 2.0)));
}

/// exp of the hard tangents (with both signs of the quaternion), random elements, and elements
/// near the identity.
std::vector<Sim3> sim3_test_elements(Rng& rng) {
  std::vector<Sim3> out;
  for (const Tangent& xi : hard_sim3_tangents()) {
    const Sim3 S = Sim3::exp(xi);
    out.push_back(S);
    out.emplace_back(Quaternion(-S.unit_quaternion().coeffs()), S.translation(), S.scale());
  }
  for (int i = 0; i < kRandomSamples; ++i) out.push_back(random_sim3(rng));
  for (int i = 0; i < kNearIdentitySamples; ++i) out.push_back(Sim3::exp(random_small_sim3_tangent(rng)));
  return out;
}

double rotation_angle(const Tangent& xi) { return xi.segment<3>(3).norm(); }

// -- group structure ---------------------------------------------------------------------------

TEST(Sim3Test, GroupAxiomsAndMatrixRepresentation) {
  Rng rng(701);
  WorstCase associativity("sim3_associativity");
  WorstCase product("sim3_product_matches_matrices");
  WorstCase inverse("sim3_inverse");
  WorstCase action("sim3_action_matches_matrix");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Sim3 a = random_sim3(rng), b = random_sim3(rng), c = random_sim3(rng);
    const auto d = [&] { return describe_sim3(a) + " " + describe_sim3(b); };
    associativity.add(scaled_error(((a * b) * c).matrix(), (a * (b * c)).matrix()), d);
    product.add(scaled_error((a * b).matrix(), a.matrix() * b.matrix()), d);
    inverse.add(scaled_error((a * a.inverse()).matrix(), Matrix4::Identity()), d);
    inverse.add(scaled_error((a.inverse() * a).matrix(), Matrix4::Identity()), d);
    inverse.add(scaled_error(a.inverse().matrix(), Matrix4(a.matrix().inverse())), d);
    const Vector3 p = random_translation(rng);
    action.add(scaled_error(a * p, Vector3((a.matrix() * p.homogeneous()).head<3>())), d);
    action.add(scaled_error(a * p, Vector3(a.scale() * (a.rotation_matrix() * p) + a.translation())), d);
    // (a b) p = a (b p)
    action.add(scaled_error((a * b) * p, a * (b * p)), d);
    ASSERT_EQ((Sim3() * a).matrix(), a.matrix());
    ASSERT_EQ((a * Sim3()).matrix(), a.matrix());
    EXPECT_NEAR((a * b).scale(), a.scale() * b.scale(), 1e-15 * a.scale() * b.scale());
  }
  associativity.expect_at_most(kAxiomTol, kRandomSamples);
  product.expect_at_most(kAxiomTol, kRandomSamples);
  inverse.expect_at_most(kAxiomTol, kRandomSamples);
  action.expect_at_most(kAxiomTol, kRandomSamples);
}

TEST(Sim3Test, AccessorsAndConstructors) {
  const Quaternion q = Quaternion(Eigen::AngleAxisd(0.3, Vector3(1.0, 2.0, -1.0).normalized()));
  const Vector3 t(1.0, -2.0, 3.0);
  const Sim3 S(q, t, 2.5);
  EXPECT_EQ(S.scale(), 2.5);
  EXPECT_EQ(S.translation(), t);
  EXPECT_EQ(S.rotation_matrix(), S.so3().matrix());
  Matrix4 expected = Matrix4::Identity();
  expected.topLeftCorner<3, 3>() = 2.5 * q.toRotationMatrix();
  expected.topRightCorner<3, 1>() = t;
  EXPECT_LE((S.matrix() - expected).cwiseAbs().maxCoeff(), 1e-15);
  // From SE(3) and a scale, and back.
  const SE3 T(q, t);
  const Sim3 from_se3(T, 0.5);
  EXPECT_EQ(from_se3.scale(), 0.5);
  EXPECT_EQ(from_se3.to_se3().matrix(), T.matrix());
  EXPECT_EQ(Sim3(T).scale(), 1.0);
  // from_matrix recovers the scale, rotation and translation.
  const Sim3 M = Sim3::from_matrix(S.matrix());
  EXPECT_NEAR(M.scale(), 2.5, 1e-14);
  EXPECT_LE((M.matrix() - S.matrix()).cwiseAbs().maxCoeff(), 1e-14);
  // ORB-SLAM's conversion of a camera-from-world similarity: (R, t / s).
  const SE3 T_cw = S.inverse().to_se3().inverse();
  EXPECT_LE((T_cw.translation() - t / 2.5).norm(), 1e-15);
  EXPECT_LE((T_cw.rotation_matrix() - S.rotation_matrix()).norm(), 1e-15);
}

TEST(Sim3Test, TangentIsTranslationRotationLogScale) {
  // Pure log-scale: exp((0, 0, sigma)) scales about the origin by e^sigma.
  const Sim3 S = Sim3::exp(make_tangent(Vector3::Zero(), Vector3::Zero(), std::log(3.0)));
  EXPECT_NEAR(S.scale(), 3.0, 1e-15);
  EXPECT_EQ(S.translation(), Vector3::Zero());
  EXPECT_EQ(S.rotation_matrix(), Matrix3::Identity());
  // Pure translation.
  const Tangent xi = make_tangent(Vector3(1.0, 2.0, 3.0), Vector3::Zero(), 0.0);
  EXPECT_EQ(Sim3::exp(xi).translation(), Vector3(1.0, 2.0, 3.0));
  EXPECT_EQ(Sim3::exp(xi).log(), xi);
  // Translation and scale together: t = (e^sigma - 1) / sigma rho.
  const double sigma = 0.7;
  const Sim3 U = Sim3::exp(make_tangent(Vector3(1.0, 0.0, 0.0), Vector3::Zero(), sigma));
  EXPECT_NEAR(U.translation().x(), std::expm1(sigma) / sigma, 1e-15);
  // A screw about its own axis with scale: along the axis, W acts as (e^sigma - 1) / sigma.
  const Vector3 axis = Vector3(1.0, -2.0, 2.0).normalized();
  const Sim3 V = Sim3::exp(make_tangent(0.7 * axis, 2.0 * axis, -0.4));
  EXPECT_LE((V.translation() - 0.7 * std::expm1(-0.4) / -0.4 * axis).norm(), 1e-15);
}

// -- exp and log -----------------------------------------------------------------------------

TEST(Sim3Test, ExpMatchesTheMatrixExponential) {
  Rng rng(702);
  WorstCase worst("sim3_exp_vs_matrix_exponential");
  WorstCase w_inverse("sim3_W_times_W_inverse");
  const std::vector<Tangent> tangents = sim3_test_tangents(rng);
  for (const Tangent& xi : tangents) {
    const auto d = [&] { return describe_xi(xi); };
    worst.add(scaled_error(Sim3::exp(xi).matrix(), matrix_exponential(Sim3::hat(xi))), d);
    const Vector3 phi = xi.segment<3>(3);
    w_inverse.add(scaled_error(Sim3::W(xi(6), phi) * Sim3::W_inverse(xi(6), phi), Matrix3::Identity()), d);
  }
  worst.expect_at_most(kReferenceTol, static_cast<int>(tangents.size()));
  w_inverse.expect_at_most(kReferenceTol, static_cast<int>(tangents.size()));
}

// W's coefficients agree across the switch between the series and the closed forms: W just
// inside and just outside |(sigma, a)| = 1 against the matrix exponential, to 1e-14.
TEST(Sim3Test, WIsContinuousAcrossItsSeriesSwitch) {
  Rng rng(703);
  WorstCase worst("sim3_W_at_switch");
  for (int i = 0; i < 2000; ++i) {
    const double angle = uniform(rng, 0.0, 1.0);
    const double f = i % 2 == 0 ? 1.0 - 1e-13 : 1.0 + 1e-13;
    const double sigma = (i % 4 < 2 ? 1.0 : -1.0) * std::sqrt(1.0 - angle * angle) * f;
    const Vector3 phi = angle * f * random_unit_vector(rng);
    // exp([[A, I], [0, 0]]) = [[e^A, sum A^k / (k+1)!], [0, I]]: its top-right block is W.
    Eigen::Matrix<double, 6, 6> big = Eigen::Matrix<double, 6, 6>::Zero();
    big.topLeftCorner<3, 3>() = SO3::hat(phi) + sigma * Matrix3::Identity();
    big.topRightCorner<3, 3>() = Matrix3::Identity();
    const Matrix3 reference = matrix_exponential(big).topRightCorner<3, 3>();
    worst.add(scaled_error(Sim3::W(sigma, phi), reference),
              [&] { return "sigma " + to_string(sigma) + " phi " + to_string(phi.transpose()); });
  }
  worst.expect_at_most(1e-14, 2000);
}

TEST(Sim3Test, LogOfExpIsTheTangent) {
  Rng rng(704);
  WorstCase round_trip("sim3_log_exp_error");
  WorstCase rotation("sim3_log_exp_relative_rotation_error");
  WorstCase sigma_error("sim3_log_exp_relative_sigma_error");
  int checked = 0;
  for (const Tangent& xi : sim3_test_tangents(rng)) {
    if (rotation_angle(xi) >= kPi) continue;  // phi and -phi are both logs
    ++checked;
    const Tangent xi2 = Sim3::exp(xi).log();
    const auto d = [&] { return describe_xi(xi) + " log " + describe_xi(xi2); };
    round_trip.add(scaled_error(xi2, xi), d);
    // The rotation and the log-scale keep their relative accuracy however small they are.
    const double angle = rotation_angle(xi);
    const double dr = (xi2 - xi).segment<3>(3).norm();
    rotation.add(angle == 0.0 ? dr : dr / angle, d);
    const double ds = std::abs(xi2(6) - xi(6));
    sigma_error.add(xi(6) == 0.0 ? ds : ds / std::abs(xi(6)), d);
  }
  round_trip.expect_at_most(kAxiomTol, kRandomSamples);
  rotation.expect_at_most(1e-12, kRandomSamples);
  sigma_error.expect_at_most(1e-12, kRandomSamples);
  EXPECT_GE(checked, kRandomSamples);
}

TEST(Sim3Test, ExpOfLogIsTheElement) {
  Rng rng(705);
  WorstCase round_trip("sim3_exp_log_error");
  WorstCase range("sim3_log_angle_out_of_range");
  const std::vector<Sim3> elements = sim3_test_elements(rng);
  for (const Sim3& S : elements) {
    const Tangent xi = S.log();
    round_trip.add(scaled_error(Sim3::exp(xi).matrix(), S.matrix()), [&] { return describe_sim3(S); });
    range.add(std::max(0.0, rotation_angle(xi) - kPi), [&] { return describe_sim3(S); });
  }
  round_trip.expect_at_most(kAxiomTol, kRandomSamples);
  range.expect_at_most(4.0 * (std::nextafter(kPi, 4.0) - kPi), kRandomSamples);
}

// -- hat, vee, ad, Adj -------------------------------------------------------------------------

TEST(Sim3Test, HatVeeAndSmallAdjoint) {
  Rng rng(706);
  WorstCase hat_vee("sim3_vee_hat");
  WorstCase ad("sim3_ad_vs_commutator");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Tangent xi = random_sim3_tangent(rng);
    const auto d = [&] { return describe_xi(xi); };
    hat_vee.add(scaled_error(Sim3::vee(Sim3::hat(xi)), xi), d);
    ad.add(scaled_error(Sim3::ad(xi), small_adjoint<Traits>(xi)), d);
  }
  hat_vee.expect_at_most(1e-15, kRandomSamples);
  ad.expect_at_most(1e-15, kRandomSamples);
}

TEST(Sim3Test, AdjointIdentities) {
  Rng rng(707);
  WorstCase conjugation("sim3_adj_conjugation");
  WorstCase homomorphism("sim3_adj_homomorphism");
  WorstCase inverse("sim3_adj_inverse");
  for (int i = 0; i < kRandomSamples; ++i) {
    const Sim3 S = random_sim3(rng), U = random_sim3(rng);
    const Tangent xi = random_sim3_tangent(rng, 3.0, 1.0);
    const auto d = [&] { return describe_sim3(S) + " " + describe_xi(xi); };
    // S exp(xi) S^-1 = exp(Adj xi), as matrices, and S hat(xi) S^-1 = hat(Adj xi).
    conjugation.add(scaled_error((S * Sim3::exp(xi) * S.inverse()).matrix(), Sim3::exp(S.Adj() * xi).matrix()), d);
    conjugation.add(scaled_error(Matrix4(S.matrix() * Sim3::hat(xi) * S.inverse().matrix()), Sim3::hat(S.Adj() * xi)), d);
    homomorphism.add(scaled_error((S * U).Adj(), Jacobian(S.Adj() * U.Adj())), d);
    inverse.add(scaled_error(Jacobian(S.Adj() * S.inverse().Adj()), Jacobian::Identity()), d);
  }
  conjugation.expect_at_most(kAxiomTol, kRandomSamples);
  homomorphism.expect_at_most(kAxiomTol, kRandomSamples);
  inverse.expect_at_most(kAxiomTol, kRandomSamples);
}

// -- Jacobians --------------------------------------------------------------------------------

// Jl against its defining series sum ad^k / (k+1)! (built from hat and vee alone), Jr = Jl(-xi),
// and the inverses against the identity, on the hard, random and near-identity tangents.
TEST(Sim3Test, JacobiansMatchTheirSeriesAndInverses) {
  Rng rng(708);
  WorstCase left("sim3_jl_vs_series");
  WorstCase right("sim3_jr_vs_series");
  WorstCase left_inverse("sim3_jl_times_jl_inverse");
  WorstCase right_inverse("sim3_jr_times_jr_inverse");
  WorstCase with_log("sim3_log_with_jr_inverse");
  const std::vector<Tangent> tangents = sim3_test_tangents(rng, 3.0);
  for (const Tangent& xi : tangents) {
    const auto d = [&] { return describe_xi(xi); };
    const Jacobian Jl = Sim3::left_jacobian(xi);
    const Jacobian Jr = Sim3::right_jacobian(xi);
    left.add(scaled_error(Jl, series_left_jacobian<Traits>(xi)), d);
    right.add(scaled_error(Jr, series_left_jacobian<Traits>(Tangent(-xi))), d);
    left_inverse.add(scaled_error(Jacobian(Jl * Sim3::left_jacobian_inverse(xi)), Jacobian::Identity()), d);
    right_inverse.add(scaled_error(Jacobian(Jr * Sim3::right_jacobian_inverse(xi)), Jacobian::Identity()), d);
    if (rotation_angle(xi) < kPi) {
      const Sim3 S = Sim3::exp(xi);
      Jacobian K;
      const Tangent xi2 = S.log(K);
      with_log.add(scaled_error(K, Sim3::right_jacobian_inverse(xi2)), d);
    }
  }
  const int n = static_cast<int>(tangents.size());
  left.expect_at_most(kReferenceTol, n);
  right.expect_at_most(kReferenceTol, n);
  left_inverse.expect_at_most(kAxiomTol, n);
  right_inverse.expect_at_most(kAxiomTol, n);
  with_log.expect_at_most(0.0, kRandomSamples);
}

// The Jacobians as derivatives, by central differences on 3,000 random tangents (angle up to 3,
// sigma in [-2, 2]) plus 1,000 near the identity:
//   exp(xi + d) = exp(Jl d) exp(xi) = exp(xi) exp(Jr d),
//   log(exp(d) exp(xi)) = xi + Jl^-1 d,  log(exp(xi) exp(d)) = xi + Jr^-1 d   (to first order).
TEST(Sim3Test, JacobiansMatchCentralDifferences) {
  Rng rng(709);
  WorstCase left("sim3_jl_numeric");
  WorstCase right("sim3_jr_numeric");
  WorstCase left_inverse("sim3_jl_inverse_numeric");
  WorstCase right_inverse("sim3_jr_inverse_numeric");
  std::vector<Tangent> tangents;
  for (int i = 0; i < 3000; ++i) tangents.push_back(random_sim3_tangent(rng, 3.0));
  for (int i = 0; i < 1000; ++i) tangents.push_back(random_small_sim3_tangent(rng));
  for (const Tangent& xi : tangents) {
    const auto d = [&] { return describe_xi(xi); };
    const Sim3 S = Sim3::exp(xi);
    const Sim3 S_inv = S.inverse();
    left.add(scaled_error(numeric_jacobian<Traits>([&](const Tangent& e) {
                            return Tangent((Sim3::exp(Tangent(xi + e)) * S_inv).log());
                          }),
                          Sim3::left_jacobian(xi)),
             d);
    right.add(scaled_error(numeric_jacobian<Traits>([&](const Tangent& e) {
                             return Tangent((S_inv * Sim3::exp(Tangent(xi + e))).log());
                           }),
                           Sim3::right_jacobian(xi)),
              d);
    left_inverse.add(scaled_error(numeric_jacobian<Traits>([&](const Tangent& e) {
                                    return Tangent((Sim3::exp(e) * S).log() - xi);
                                  }),
                                  Sim3::left_jacobian_inverse(xi)),
                     d);
    right_inverse.add(scaled_error(numeric_jacobian<Traits>([&](const Tangent& e) {
                                     return Tangent((S * Sim3::exp(e)).log() - xi);
                                   }),
                                   Sim3::right_jacobian_inverse(xi)),
                      d);
  }
  const int n = static_cast<int>(tangents.size());
  left.expect_at_most(kFiniteDifferenceTol, n);
  right.expect_at_most(kFiniteDifferenceTol, n);
  left_inverse.expect_at_most(kFiniteDifferenceTol, n);
  right_inverse.expect_at_most(kFiniteDifferenceTol, n);
}

// -- scale 1 is SE(3) --------------------------------------------------------------------------

TEST(Sim3Test, ScaleOneReducesToSE3) {
  Rng rng(710);
  WorstCase exp_error("sim3_exp_vs_se3");
  WorstCase log_error("sim3_log_vs_se3");
  WorstCase jacobian_error("sim3_jacobians_vs_se3");
  WorstCase adj_error("sim3_adj_vs_se3");
  std::vector<Vector6> tangents = hard_tangents<LieTraits<SE3>>();
  for (int i = 0; i < kRandomSamples; ++i) tangents.push_back(random_tangent<LieTraits<SE3>>(rng));
  for (const Vector6& xi6 : tangents) {
    const auto d = [&] { return "xi = " + to_string(xi6.transpose()); };
    const Tangent xi = make_tangent(xi6.head<3>(), xi6.tail<3>(), 0.0);
    const Sim3 S = Sim3::exp(xi);
    const SE3 T = SE3::exp(xi6);
    EXPECT_EQ(S.scale(), 1.0);
    exp_error.add(scaled_error(S.matrix(), T.matrix()), d);
    const Tangent from_se3 = Sim3(T).log();
    log_error.add(scaled_error(from_se3.head<6>(), T.log()), d);
    log_error.add(std::abs(from_se3(6)), d);
    // The (rho, phi) blocks of the Sim(3) Jacobians are SE(3)'s at sigma = 0.
    jacobian_error.add(scaled_error(Sim3::left_jacobian(xi).topLeftCorner<6, 6>(), SE3::left_jacobian(xi6)), d);
    if (xi6.tail<3>().norm() < 3.0) {
      jacobian_error.add(
          scaled_error(Sim3::right_jacobian_inverse(xi).topLeftCorner<6, 6>(), SE3::right_jacobian_inverse(xi6)), d);
    }
    adj_error.add(scaled_error(S.Adj().topLeftCorner<6, 6>(), T.Adj()), d);
    // W(0, phi) is SO(3)'s left Jacobian.
    jacobian_error.add(scaled_error(Sim3::W(0.0, xi6.tail<3>()), SO3::left_jacobian(xi6.tail<3>())), d);
  }
  const int n = static_cast<int>(tangents.size());
  exp_error.expect_at_most(1e-13, n);
  log_error.expect_at_most(1e-12, n);
  jacobian_error.expect_at_most(kReferenceTol, n);
  adj_error.expect_at_most(1e-15, n);
}

}  // namespace
}  // namespace cairn::core::testing
