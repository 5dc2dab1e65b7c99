#include "cairn/io/information.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <sstream>

namespace cairn::io {

std::string_view to_string(InformationPolicy policy) {
  switch (policy) {
    case InformationPolicy::kProject: return "project";
    case InformationPolicy::kKeep: return "keep";
    case InformationPolicy::kReject: return "reject";
  }
  return "?";
}

bool is_positive_definite(const Eigen::MatrixXd& information) {
  const Eigen::LLT<Eigen::MatrixXd> llt(information);
  return llt.info() == Eigen::Success;
}

Definiteness classify_information(const Eigen::MatrixXd& information) {
  if (is_positive_definite(information)) return Definiteness::kPositiveDefinite;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(information, Eigen::EigenvaluesOnly);
  const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
  return eigen.eigenvalues().minCoeff() >= -kSemiDefiniteTolerance * largest ? Definiteness::kSemiDefinite
                                                                               : Definiteness::kIndefinite;
}

Eigen::MatrixXd nearest_positive_semidefinite(const Eigen::MatrixXd& information) {
  const Eigen::MatrixXd symmetric = 0.5 * (information + information.transpose());
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(symmetric);
  const Eigen::VectorXd clamped = eigen.eigenvalues().cwiseMax(0.0);
  Eigen::MatrixXd result = eigen.eigenvectors() * clamped.asDiagonal() * eigen.eigenvectors().transpose();
  return 0.5 * (result + result.transpose());  // exact symmetry for writers and Cholesky
}

std::string check_information_diagonal(const Eigen::MatrixXd& information) {
  for (Eigen::Index i = 0; i < information.rows(); ++i) {
    const double d = information(i, i);
    if (!(d > 0.0) || !std::isfinite(d)) {
      std::ostringstream message;
      message.precision(17);
      message << "information diagonal entry I(" << i + 1 << "," << i + 1 << ") is " << d
              << ": expected > 0";
      return message.str();
    }
  }
  return {};
}

}  // namespace cairn::io
