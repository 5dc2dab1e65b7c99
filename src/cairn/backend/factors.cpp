#include "cairn/backend/factors.hpp"

namespace cairn::backend {
namespace {

// Rotation block R and translation t of either group, as fixed-size matrices.
template <class Group>
auto rotation(const Group& T) {
  if constexpr (Group::kDoF == 3) {
    return T.so2().matrix();
  } else {
    return T.rotation_matrix();
  }
}

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
  using VectorD = Eigen::Matrix<double, d, 1>;
  const MatrixD R_i = rotation(T_world_i);
  const MatrixD R_j = rotation(T_world_j);
  const MatrixD R_ij = rotation(edge.T_i_j);
  const VectorD t_ij = edge.T_i_j.translation();
  const double sk = std::sqrt(edge.kappa);
  const double st = std::sqrt(edge.tau);
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

template struct GeodesicFactor<core::SE2>;
template struct GeodesicFactor<core::SE3>;
template struct ChordalFactor<core::SE2>;
template struct ChordalFactor<core::SE3>;
template core::SE2::Tangent between_error(const core::SE2&, const core::SE2&, const core::SE2&);
template core::SE3::Tangent between_error(const core::SE3&, const core::SE3&, const core::SE3&);

}  // namespace cairn::backend
