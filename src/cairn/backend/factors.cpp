#include "cairn/backend/factors.hpp"

#include <array>
#include <cmath>

namespace cairn::backend {
namespace {

// Generators of so(2) / so(3).
template <int d>
Eigen::Matrix<double, d, d> generator(int k) {
  if constexpr (d == 2) {
    (void)k;
    Eigen::Matrix2d G;
    G << 0.0, -1.0, 1.0, 0.0;
    return G;
  } else {
    return core::SO3::hat(Eigen::Vector3d::Unit(k));
  }
}

// [v]x in the chordal translation Jacobian: d(R exp(phi) v)/d phi = -R [v]x for SO(3);
// for SO(2), d(R exp(theta) v)/d theta = R G v.
template <int d>
Eigen::Matrix<double, d, d == 2 ? 1 : 3> rotate_derivative(const Eigen::Matrix<double, d, d>& R,
                                                           const Eigen::Matrix<double, d, 1>& v) {
  if constexpr (d == 2) {
    return R * generator<2>(0) * v;
  } else {
    return -R * core::SO3::hat(v);
  }
}

// What the chordal residual and its derivatives read of an edge and its two poses.
template <class Group>
struct ChordalTerms {
  static constexpr int d = kRotationDim<Group>;
  Eigen::Matrix<double, d, d> R_i, R_j, R_ij;
  Eigen::Matrix<double, d, 1> t_ij;
  double sqrt_kappa, sqrt_tau;
  ChordalTerms(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge)
      : R_i(rotation_matrix_of(T_world_i)),
        R_j(rotation_matrix_of(T_world_j)),
        R_ij(rotation_matrix_of(edge.T_i_j)),
        t_ij(edge.T_i_j.translation()),
        sqrt_kappa(std::sqrt(edge.kappa)),
        sqrt_tau(std::sqrt(edge.tau)) {}
};

}  // namespace

template <class Group>
typename Group::Tangent between_error(const Group& T_world_i, const Group& T_world_j, const Group& T_i_j) {
  return (T_i_j.inverse() * (T_world_i.inverse() * T_world_j)).log();
}

template <class Group>
typename GeodesicFactor<Group>::Residual GeodesicFactor<Group>::evaluate(const Group& T_world_i,
                                                                         const Group& T_world_j,
                                                                         const PoseEdge<Group>& edge,
                                                                         Jacobian* J_r_i, Jacobian* J_r_j) {
  const Group T_i_j = T_world_i.inverse() * T_world_j;
  const Group E = edge.T_i_j.inverse() * T_i_j;
  if (J_r_i == nullptr && J_r_j == nullptr) return edge.sqrt_information * E.log();
  Jacobian J_e_j;  // Jr^-1(e)
  const typename Group::Tangent e = E.log(J_e_j);
  const Jacobian J_r_j_value = edge.sqrt_information * J_e_j;
  // dr/d(delta_i) = -(dr/d(delta_j)) Adj(T_j^-1 T_i): the product S Jr^-1 once for both.
  if (J_r_i != nullptr) J_r_i->noalias() = -J_r_j_value * T_i_j.inverse().Adj();
  if (J_r_j != nullptr) *J_r_j = J_r_j_value;
  return edge.sqrt_information * e;
}

template <class Group>
typename ChordalFactor<Group>::Residual ChordalFactor<Group>::evaluate(const Group& T_world_i,
                                                                       const Group& T_world_j,
                                                                       const PoseEdge<Group>& edge,
                                                                       Jacobian* J_r_i, Jacobian* J_r_j) {
  using MatrixD = Eigen::Matrix<double, d, d>;
  const ChordalTerms<Group> terms(T_world_i, T_world_j, edge);
  const auto& [R_i, R_j, R_ij, t_ij, sk, st] = terms;
  Residual r;
  const MatrixD rotation_error = R_j - R_i * R_ij;
  r.template head<d * d>() = sk * Eigen::Map<const Eigen::Matrix<double, d * d, 1>>(rotation_error.data());
  r.template tail<d>() = st * (T_world_j.translation() - T_world_i.translation() - R_i * t_ij);
  if (J_r_i != nullptr) {
    J_r_i->setZero();
    for (int k = 0; k < kDoF - d; ++k) {
      const MatrixD dR = -R_i * generator<d>(k) * R_ij;
      J_r_i->template block<d * d, 1>(0, d + k) = sk * Eigen::Map<const Eigen::Matrix<double, d * d, 1>>(dR.data());
    }
    J_r_i->template block<d, d>(d * d, 0) = -st * R_i;
    J_r_i->template block<d, kDoF - d>(d * d, d) = -st * rotate_derivative<d>(R_i, t_ij);
  }
  if (J_r_j != nullptr) {
    J_r_j->setZero();
    for (int k = 0; k < kDoF - d; ++k) {
      const MatrixD dR = R_j * generator<d>(k);
      J_r_j->template block<d * d, 1>(0, d + k) = sk * Eigen::Map<const Eigen::Matrix<double, d * d, 1>>(dR.data());
    }
    J_r_j->template block<d, d>(d * d, 0) = st * R_j;
  }
  return r;
}

template <class Group>
void ChordalFactor<Group>::second_order(const Group& T_world_i, const Group& T_world_j, const PoseEdge<Group>& edge,
                                        const Residual& r, Hessian* S_ii, Hessian* S_jj) {
  using MatrixD = Eigen::Matrix<double, d, d>;
  using VectorD = Eigen::Matrix<double, d, 1>;
  constexpr int kRot = kDoF - d;  // rotation parameters
  const ChordalTerms<Group> terms(T_world_i, T_world_j, edge);
  const auto& [R_i, R_j, R_ij, t_ij, sk, st] = terms;
  const Eigen::Map<const MatrixD> r_R(r.data());  // vec() is column-major, as in evaluate()
  const VectorD r_t = r.template tail<d>();
  S_ii->setZero();
  S_jj->setZero();
  std::array<MatrixD, kRot> G;
  for (int a = 0; a < kRot; ++a) G[static_cast<std::size_t>(a)] = generator<d>(a);
  for (int a = 0; a < kRot; ++a) {
    for (int b = a; b < kRot; ++b) {
      const MatrixD sym = 0.5 * (G[static_cast<std::size_t>(a)] * G[static_cast<std::size_t>(b)] +
                                 G[static_cast<std::size_t>(b)] * G[static_cast<std::size_t>(a)]);
      const double ii = -sk * r_R.cwiseProduct(R_i * sym * R_ij).sum() - st * r_t.dot(R_i * sym * t_ij);
      const double jj = sk * r_R.cwiseProduct(R_j * sym).sum();
      (*S_ii)(d + a, d + b) = (*S_ii)(d + b, d + a) = ii;
      (*S_jj)(d + a, d + b) = (*S_jj)(d + b, d + a) = jj;
    }
  }
  for (int a = 0; a < d; ++a) {
    for (int b = 0; b < kRot; ++b) {
      const VectorD Ge = G[static_cast<std::size_t>(b)].col(a);  // G_b e_a
      (*S_ii)(a, d + b) = (*S_ii)(d + b, a) = -0.5 * st * r_t.dot(R_i * Ge);
      (*S_jj)(a, d + b) = (*S_jj)(d + b, a) = 0.5 * st * r_t.dot(R_j * Ge);
    }
  }
}

template struct GeodesicFactor<core::SE2>;
template struct GeodesicFactor<core::SE3>;
template struct ChordalFactor<core::SE2>;
template struct ChordalFactor<core::SE3>;
template core::SE2::Tangent between_error(const core::SE2&, const core::SE2&, const core::SE2&);
template core::SE3::Tangent between_error(const core::SE3&, const core::SE3&, const core::SE3&);

}  // namespace cairn::backend
