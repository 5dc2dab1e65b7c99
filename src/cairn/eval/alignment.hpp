#pragma once
/// \file
/// Aligning an estimated trajectory to its reference before the absolute error is measured.
///
/// Umeyama, "Least-squares estimation of transformation parameters between two point
/// patterns", IEEE PAMI 13(4), 1991, as evo implements it (evo/core/geometry.py,
/// umeyama_alignment; evo/core/trajectory.py, PosePath3D.align): with x_i the estimated and
/// y_i the reference positions (n pairs),
///   mu_x, mu_y                     means (eq. 34, 35)
///   sigma_x^2 = 1/n sum |x_i - mu_x|^2                                  (eq. 36)
///   Sigma_xy  = 1/n sum (y_i - mu_y)(x_i - mu_x)^T = U D V^T (SVD)      (eq. 38)
///   S = I, or diag(1, ..., 1, -1) when det(U) det(V) < 0                (eq. 43)
///   R = U S V^T                                                        (eq. 40)
///   c = trace(D S) / sigma_x^2   (Sim(3) only; 1 otherwise)             (eq. 42)
///   t = mu_y - c R mu_x                                                (eq. 41)
/// and every estimated pose T becomes (R R_T, c R t_T + t): scaled first, then moved, as
/// evo's align(correct_scale=True) scales and then transforms. Like evo, the alignment fails
/// when fewer than m - 1 singular values of Sigma_xy exceed machine epsilon (all points on a
/// line for m = 3).
///
/// kSE2 is cairn's planar variant (evo has none): Umeyama with m = 2 on the (x, y) positions,
/// i.e. a rotation about z and a translation in x, y; z is left as it is.
/// kFirstPose moves the estimate so that its first pose equals the reference's first pose
/// (evo's align_origin: T = T_ref[0] * T_est[0]^-1, applied on the left).

#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "cairn/core/se3.hpp"
#include "cairn/eval/status.hpp"

namespace cairn::eval {

enum class AlignmentMethod {
  kNone,
  /// Rotation and translation (evo `-a`).
  kSE3,
  /// Rotation, translation and scale (evo `-as`); for monocular estimates.
  kSim3,
  /// Rotation about z and translation in x, y (planar robots).
  kSE2,
  /// First estimated pose onto the first reference pose (evo `--align_origin`).
  kFirstPose,
};

/// "none", "se3", "sim3", "se2", "first".
std::string_view to_string(AlignmentMethod method);
std::optional<AlignmentMethod> alignment_method_from_name(std::string_view name);

struct AlignmentOptions {
  AlignmentMethod method = AlignmentMethod::kNone;
  /// Use only the first `num_poses` pairs to estimate the alignment (evo `--n_to_align`);
  /// 0 = all. The alignment is applied to every pose.
  std::size_t num_poses = 0;
};

/// p_reference = scale * R * p_estimate + t.
struct Alignment {
  Outcome outcome;
  AlignmentMethod method = AlignmentMethod::kNone;
  /// (R, t) above; R is an exact rotation (from the SVD).
  Matrix3 R = Matrix3::Identity();
  Vector3 t = Vector3::Zero();
  double scale = 1.0;
  /// Pairs the alignment was estimated from.
  std::size_t pairs_used = 0;

  /// The estimated pose moved into the reference frame: (R R_T, scale R t_T + t), as evo's
  /// scale() then transform() (left multiplication).
  Matrix4 apply(const Matrix4& T_world_body) const;
  /// (R, t) as a rigid motion, for reports.
  core::SE3 T_reference_estimate() const { return core::SE3(core::SO3::from_matrix(R), t); }
};

/// Umeyama (eq. 34-43) on m-dimensional points (m = 2 or 3, columns are points).
/// Returns kDegenerate when the points do not fix the rotation.
struct UmeyamaResult {
  Outcome outcome;
  Eigen::MatrixXd R;
  Eigen::VectorXd t;
  double scale = 1.0;
};
UmeyamaResult umeyama(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y, bool with_scale);

/// Estimates the alignment of `estimate` onto `reference` (same length, paired by index).
Alignment align(const std::vector<Matrix4>& reference, const std::vector<Matrix4>& estimate,
                const AlignmentOptions& options);

/// Applies `alignment` to every pose.
std::vector<Matrix4> apply_alignment(const Alignment& alignment, const std::vector<Matrix4>& poses);

}  // namespace cairn::eval
