#include "cairn/eval/alignment.hpp"

#include <Eigen/SVD>
#include <limits>
#include <string>

#include "cairn/eval/matrix_trajectory.hpp"

namespace cairn::eval {

std::string_view to_string(AlignmentMethod method) {
  switch (method) {
    case AlignmentMethod::kNone: return "none";
    case AlignmentMethod::kSE3: return "se3";
    case AlignmentMethod::kSim3: return "sim3";
    case AlignmentMethod::kSE2: return "se2";
    case AlignmentMethod::kFirstPose: return "first";
  }
  return "none";
}

std::optional<AlignmentMethod> alignment_method_from_name(std::string_view name) {
  for (AlignmentMethod m : {AlignmentMethod::kNone, AlignmentMethod::kSE3, AlignmentMethod::kSim3,
                            AlignmentMethod::kSE2, AlignmentMethod::kFirstPose}) {
    if (name == to_string(m)) return m;
  }
  return std::nullopt;
}

Matrix4 Alignment::apply(const Matrix4& T_world_body) const {
  Matrix4 out = Matrix4::Identity();
  out.topLeftCorner<3, 3>() = R * T_world_body.topLeftCorner<3, 3>();
  out.topRightCorner<3, 1>() = R * (scale * T_world_body.topRightCorner<3, 1>()) + t;
  return out;
}

UmeyamaResult umeyama(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, bool with_scale) {
  UmeyamaResult result;
  const Eigen::Index m = x.rows();
  const Eigen::Index n = x.cols();
  if (n == 0 || x.rows() != y.rows() || x.cols() != y.cols()) {
    result.outcome = {Status::kEmpty, "Umeyama alignment needs two equally sized, non-empty point sets"};
    return result;
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  // eq. 34, 35
  const Eigen::VectorXd mean_x = x.rowwise().mean();
  const Eigen::VectorXd mean_y = y.rowwise().mean();
  const Eigen::MatrixXd x_centred = x.colwise() - mean_x;
  const Eigen::MatrixXd y_centred = y.colwise() - mean_y;
  // eq. 36
  const double sigma_x = inv_n * x_centred.squaredNorm();
  // eq. 38
  const Eigen::MatrixXd cov_xy = inv_n * (y_centred * x_centred.transpose());
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(cov_xy, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::VectorXd& d = svd.singularValues();
  Eigen::Index rank = 0;
  for (Eigen::Index i = 0; i < d.size(); ++i) rank += d[i] > std::numeric_limits<double>::epsilon() ? 1 : 0;
  if (rank < m - 1) {
    result.outcome = {Status::kDegenerate,
                      "degenerate point covariance (rank " + std::to_string(rank) + " < " + std::to_string(m - 1) +
                          "): the positions are coincident or on a line, so the alignment rotation is not determined"};
    return result;
  }
  // eq. 43: S = diag(1, ..., 1, -1) when U V^T would be a reflection.
  Eigen::VectorXd s = Eigen::VectorXd::Ones(m);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s[m - 1] = -1.0;
  // eq. 40
  result.R = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  // eq. 42, 41
  result.scale = with_scale ? (d.array() * s.array()).sum() / sigma_x : 1.0;
  result.t = mean_y - result.scale * (result.R * mean_x);
  return result;
}

Alignment align(const std::vector<Matrix4>& reference, const std::vector<Matrix4>& estimate,
                const AlignmentOptions& options) {
  Alignment a;
  a.method = options.method;
  if (reference.size() != estimate.size()) {
    a.outcome = {Status::kSizeMismatch, "alignment needs paired poses: " + std::to_string(reference.size()) +
                                            " reference and " + std::to_string(estimate.size()) + " estimated"};
    return a;
  }
  if (reference.empty()) {
    a.outcome = {Status::kEmpty, "alignment needs at least one pose pair"};
    return a;
  }
  const std::size_t n = options.num_poses == 0 ? reference.size() : std::min(options.num_poses, reference.size());
  a.pairs_used = n;
  switch (options.method) {
    case AlignmentMethod::kNone: a.pairs_used = 0; return a;
    case AlignmentMethod::kFirstPose: {
      // evo align_origin: T = T_ref[0] * se3_inverse(T_est[0]).
      const Matrix4 T = reference.front() * se3_inverse(estimate.front());
      a.R = T.topLeftCorner<3, 3>();
      a.t = T.topRightCorner<3, 1>();
      a.pairs_used = 1;
      return a;
    }
    case AlignmentMethod::kSE3:
    case AlignmentMethod::kSim3: {
      Eigen::MatrixXd x(3, static_cast<Eigen::Index>(n));
      Eigen::MatrixXd y(3, static_cast<Eigen::Index>(n));
      for (std::size_t i = 0; i < n; ++i) {
        x.col(static_cast<Eigen::Index>(i)) = estimate[i].topRightCorner<3, 1>();
        y.col(static_cast<Eigen::Index>(i)) = reference[i].topRightCorner<3, 1>();
      }
      const UmeyamaResult u = umeyama(x, y, options.method == AlignmentMethod::kSim3);
      if (!u.outcome.ok()) {
        a.outcome = u.outcome;
        return a;
      }
      a.R = u.R;
      a.t = u.t;
      a.scale = u.scale;
      return a;
    }
    case AlignmentMethod::kSE2: {
      Eigen::MatrixXd x(2, static_cast<Eigen::Index>(n));
      Eigen::MatrixXd y(2, static_cast<Eigen::Index>(n));
      for (std::size_t i = 0; i < n; ++i) {
        x.col(static_cast<Eigen::Index>(i)) = estimate[i].block<2, 1>(0, 3);
        y.col(static_cast<Eigen::Index>(i)) = reference[i].block<2, 1>(0, 3);
      }
      const UmeyamaResult u = umeyama(x, y, false);
      if (!u.outcome.ok()) {
        a.outcome = u.outcome;
        return a;
      }
      a.R.topLeftCorner<2, 2>() = u.R;
      a.t = Vector3(u.t[0], u.t[1], 0.0);
      return a;
    }
  }
  return a;
}

std::vector<Matrix4> apply_alignment(const Alignment& alignment, const std::vector<Matrix4>& poses) {
  std::vector<Matrix4> out;
  out.reserve(poses.size());
  for (const Matrix4& pose : poses) out.push_back(alignment.apply(pose));
  return out;
}

}  // namespace cairn::eval
