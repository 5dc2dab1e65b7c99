#include "cairn/lidar3d/gnss_anchoring.hpp"

#include <array>
#include <cmath>
#include <stdexcept>

#include "cairn/backend/least_squares.hpp"
#include "cairn/backend/relative_pose_factor.hpp"
#include "cairn/core/problems.hpp"
#include "cairn/core/timer.hpp"
#include "cairn/gnss/gnss_outliers.hpp"
#include "cairn/inertial/imu_factors.hpp"

namespace cairn::lidar3d {

bool GnssAnchoringOptions::is_valid(std::string* why) const {
  core::Problems problems;
  std::string nested;
  if (!factor.is_valid(&nested)) problems.add_all("factor: ", nested);
  nested.clear();
  if (!alignment.is_valid(&nested)) problems.add_all("alignment: ", nested);
  problems.require_positive(max_fix_gap_s, "max_fix_gap_s");
  if (solve_every_keyframes < 1) problems.add("solve_every_keyframes must be >= 1");
  problems.require_positive(world_tilt_sigma_rad, "world_tilt_sigma_rad");
  problems.require_positive(degenerate_edge_sigma_m, "degenerate_edge_sigma_m");
  if (!(outlier_probability > 0.0 && outlier_probability < 1.0)) problems.add("outlier_probability must be in (0, 1)");
  return problems.report(why);
}

namespace {

Matrix3 skew(const Vector3& v) {
  Matrix3 m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

/// The file comment's residual on (T_world_k, T_enu_world), both se3_manifold (right perturbation,
/// translation first): with q = T_world_k a and T exp(delta) x ~= T x + R (rho + phi x x),
///   dr/d(rho_k, phi_k) = S R_enu_world (R_k, -R_k [a]x),   dr/d(rho_w, phi_w) = S (R_enu_world, -R_enu_world [q]x).
class GnssKeyframeFactor final : public backend::Factor {
 public:
  GnssKeyframeFactor(const Vector3& p_enu, const Matrix3& S, const Vector3& antenna_keyframe)
      : p_enu_(p_enu), S_(S), a_(antenna_keyframe) {}
  int residual_size() const override { return 3; }
  bool evaluate(const double* const* values, double* residual, double* const* jacobians) const override {
    const core::SE3 T_world_k = backend::se3_from_values(values[0]);
    const core::SE3 T_enu_world = backend::se3_from_values(values[1]);
    const Vector3 q = T_world_k * a_;
    Eigen::Map<Vector3>{residual} = S_ * (T_enu_world * q - p_enu_);
    if (jacobians == nullptr) return true;
    using Rows = Eigen::Matrix<double, 3, 6, Eigen::RowMajor>;
    const Matrix3 R_ew = T_enu_world.so3().matrix();
    if (jacobians[0] != nullptr) {
      const Matrix3 R_k = T_world_k.so3().matrix();
      Rows J;
      J << S_ * R_ew * R_k, -S_ * R_ew * R_k * skew(a_);
      Eigen::Map<Rows>{jacobians[0]} = J;
    }
    if (jacobians[1] != nullptr) {
      Rows J;
      J << S_ * R_ew, -S_ * R_ew * skew(q);
      Eigen::Map<Rows>{jacobians[1]} = J;
    }
    return true;
  }

 private:
  Vector3 p_enu_;
  Matrix3 S_;
  Vector3 a_;
};

/// The pose at `time_s` between the scans around it (translation linearly, rotation on the
/// geodesic), and the index of the earlier scan; nullopt outside the scans or when both are
/// farther than max_gap_s.
std::optional<std::pair<core::SE3, std::size_t>> pose_at(const std::vector<double>& times, const std::vector<core::SE3>& poses,
                                                         double time_s, double max_gap_s) {
  const auto after = std::lower_bound(times.begin(), times.end(), time_s);
  if (after == times.end()) return std::nullopt;
  const std::size_t b = static_cast<std::size_t>(after - times.begin());
  if (*after == time_s) return std::make_pair(poses[b], b);
  if (b == 0) return std::nullopt;
  const std::size_t a = b - 1;
  if (std::min(time_s - times[a], times[b] - time_s) > max_gap_s) return std::nullopt;
  const double s = (time_s - times[a]) / (times[b] - times[a]);
  const core::SE3 T_a_b = poses[a].inverse() * poses[b];
  const core::SE3 T_a_t(core::SO3::exp(s * T_a_b.so3().log()), s * T_a_b.translation());
  return std::make_pair(poses[a] * T_a_t, a);
}

}  // namespace

GnssAnchoring::GnssAnchoring(const GnssAnchoringOptions& options) : options_(options) {
  std::string why;
  if (!options.is_valid(&why)) throw std::invalid_argument("invalid GNSS anchoring options: " + why);
  summary_.outlier_chi2 = gnss::chi_square_3_quantile(options.outlier_probability);
}

void GnssAnchoring::add_fix(const gnss::GnssFix& fix) {
  if (!fixes_.empty() && fix.stamp.seconds() < fixes_.back().time_s) {
    throw std::invalid_argument("GnssAnchoring::add_fix: fixes must come in time order");
  }
  if (!frame_) {
    frame_.emplace(gnss::GeodeticPosition{fix.latitude_deg, fix.longitude_deg, fix.altitude_m});
    summary_.enu_origin = frame_->origin();
  }
  GnssFixResult result;
  result.time_s = fix.stamp.seconds();
  result.p_enu_m = frame_->forward(fix);
  result.covariance_enu_m2 = gnss::factor_covariance_enu(fix, options_.factor);
  fixes_.push_back(result);
  ++summary_.fixes;
}

void GnssAnchoring::place_fixes(const std::vector<double>& scan_time_s, const std::vector<core::SE3>& T_odom_scan,
                                const std::vector<int>& scan_keyframe, const std::vector<core::SE3>& T_odom_keyframe) {
  if (scan_time_s.empty()) return;
  for (; next_to_place_ < fixes_.size() && fixes_[next_to_place_].time_s <= scan_time_s.back(); ++next_to_place_) {
    GnssFixResult& fix = fixes_[next_to_place_];
    const auto pose = pose_at(scan_time_s, T_odom_scan, fix.time_s, options_.max_fix_gap_s);
    if (!pose) {
      fix.not_placed = fix.time_s < scan_time_s.front() ? "before the first scan" : "no scan within max_fix_gap_s";
      continue;
    }
    const int k = scan_keyframe[pose->second];
    if (k < 0) {
      fix.not_placed = "before the first keyframe";
      continue;
    }
    fix.keyframe = k;
    fix.antenna_keyframe_m = T_odom_keyframe[static_cast<std::size_t>(k)].inverse() * (pose->first * options_.factor.lever_arm_body_m);
    ++summary_.placed;
  }
}

void GnssAnchoring::set_world_up(const Vector3& up_world) {
  if (up_world.allFinite() && up_world.norm() > 0.0) up_world_ = up_world.normalized();
}

// R_level: the smallest rotation taking the world's up to +z.
core::SO3 GnssAnchoring::level_rotation() const {
  const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(up_world_, Vector3::UnitZ());
  return core::SO3(q.normalized());
}

bool GnssAnchoring::try_align(const std::vector<core::SE3>& T_world_keyframe) {
  if (summary_.aligned) return true;
  const core::SO3 R_level = level_rotation();
  std::vector<Vector3> p_world, p_enu;
  double last_time_s = 0.0;
  for (const GnssFixResult& fix : fixes_) {
    if (fix.keyframe < 0 || fix.keyframe >= static_cast<int>(T_world_keyframe.size())) continue;
    p_world.push_back(R_level * (T_world_keyframe[static_cast<std::size_t>(fix.keyframe)] * fix.antenna_keyframe_m));
    p_enu.push_back(fix.p_enu_m);
    last_time_s = fix.time_s;
  }
  gnss::YawAlignment alignment = gnss::align_world_to_enu(p_world, p_enu, options_.alignment);
  if (!alignment.ok()) {
    summary_.alignment = alignment;  // why not yet
    return false;
  }
  summary_.aligned = true;
  summary_.alignment = alignment;
  summary_.alignment_time_s = last_time_s;
  T_enu_level_ = alignment.T_enu_world;
  summary_.T_enu_world = T_enu_level_ * core::SE3(R_level, Vector3::Zero());
  return true;
}

void GnssAnchoring::finish() {
  for (; next_to_place_ < fixes_.size(); ++next_to_place_) fixes_[next_to_place_].not_placed = "after the last scan";
}

bool GnssAnchoring::solve_due(std::size_t keyframes) const {
  return summary_.aligned && keyframes >= keyframes_at_last_solve_ + static_cast<std::size_t>(options_.solve_every_keyframes);
}

namespace {

/// The variables' storage of one solve: the keyframes' poses and T_enu_world.
struct GraphValues {
  std::vector<std::array<double, 7>> poses;
  std::array<double, 7> world{};
};

/// The keyframe graph with the GNSS factors of the `used` fixes under `loss`, on `values`; the
/// world's roll and pitch held at `T_enu_world_prior`'s within `tilt_sigma_rad`, its yaw and
/// translation free.
backend::LeastSquaresProblem gnss_graph_problem(const backend::Problem3D& graph, GraphValues& values,
                                                const std::vector<GnssFixResult>& fixes, const std::vector<std::size_t>& used,
                                                const core::SE3& T_enu_world_prior, double tilt_sigma_rad,
                                                const backend::FactorLoss& loss) {
  backend::LeastSquaresProblem problem;
  std::vector<int> ids;
  for (std::size_t k = 0; k < values.poses.size(); ++k) {
    ids.push_back(problem.add_variable(values.poses[k].data(), backend::se3_manifold()));
    if (graph.fixed[k]) problem.set_constant(ids.back());
  }
  const int world_id = problem.add_variable(values.world.data(), backend::se3_manifold());
  for (const backend::PoseEdge<core::SE3>& edge : graph.edges) {
    problem.add_factor(std::make_unique<backend::RelativePoseFactor>(edge),
                       {ids[static_cast<std::size_t>(edge.i)], ids[static_cast<std::size_t>(edge.j)]});
  }
  constexpr double kFree = 1e3;
  Eigen::Matrix<double, 6, 1> sigmas;
  sigmas << kFree, kFree, kFree, tilt_sigma_rad, tilt_sigma_rad, kFree;
  problem.add_factor(std::make_unique<inertial::PosePriorFactor>(T_enu_world_prior, Matrix6(sigmas.cwiseAbs2().asDiagonal())),
                     {world_id});
  for (const std::size_t i : used) {
    const GnssFixResult& fix = fixes[i];
    const Matrix3 S = backend::square_root_information<3>(Matrix3(fix.covariance_enu_m2.inverse()));
    problem.add_factor(std::make_unique<GnssKeyframeFactor>(fix.p_enu_m, S, fix.antenna_keyframe_m),
                       {ids[static_cast<std::size_t>(fix.keyframe)], world_id}, loss);
  }
  return problem;
}

}  // namespace

void GnssAnchoring::solve(backend::Problem3D& graph) {
  const auto start = core::Clock::now();
  GraphValues values{std::vector<std::array<double, 7>>(graph.T_world_pose.size()), {}};
  for (std::size_t k = 0; k < values.poses.size(); ++k) backend::se3_to_values(graph.T_world_pose[k], values.poses[k].data());
  backend::se3_to_values(summary_.T_enu_world, values.world.data());
  std::vector<std::size_t> used;
  for (std::size_t i = 0; i < fixes_.size(); ++i) {
    fixes_[i].used = fixes_[i].keyframe >= 0 && fixes_[i].keyframe < static_cast<int>(values.poses.size());
    if (fixes_[i].used) used.push_back(i);
  }
  // Huber (convex) first, then Cauchy from its solution (the file comment).
  const core::SE3 T_enu_world_prior = T_enu_level_ * core::SE3(level_rotation(), Vector3::Zero());
  backend::LeastSquaresOptions solve_options;
  solve_options.linear_solver = backend::LinearSolverType::kSparseNormalCholesky;
  solve_options.threads = 1;
  solve_options.max_iterations = 30;
  for (const backend::FactorLoss& loss : {backend::FactorLoss{backend::RobustKernel::kHuber, 1.345}, options_.factor.loss}) {
    backend::LeastSquaresProblem problem =
        gnss_graph_problem(graph, values, fixes_, used, T_enu_world_prior, options_.world_tilt_sigma_rad, loss);
    backend::solve(problem, solve_options);
  }
  for (std::size_t k = 0; k < values.poses.size(); ++k) graph.T_world_pose[k] = backend::se3_from_values(values.poses[k].data());
  summary_.T_enu_world = backend::se3_from_values(values.world.data());
  summary_.used = used.size();
  evaluate_fixes(graph, used);
  keyframes_at_last_solve_ = graph.T_world_pose.size();
  ++summary_.solves;
  summary_.solve_s += core::seconds_since(start);
}

// Every used fix's error and chi2 at the solution, and the outliers among them.
void GnssAnchoring::evaluate_fixes(const backend::Problem3D& graph, const std::vector<std::size_t>& used) {
  summary_.outliers = 0;
  for (const std::size_t i : used) {
    GnssFixResult& fix = fixes_[i];
    const core::SE3& T_world_k = graph.T_world_pose[static_cast<std::size_t>(fix.keyframe)];
    fix.error_enu_m = summary_.T_enu_world * (T_world_k * fix.antenna_keyframe_m) - fix.p_enu_m;
    fix.chi2 = fix.error_enu_m.dot(fix.covariance_enu_m2.ldlt().solve(fix.error_enu_m));
    fix.outlier = fix.chi2 > summary_.outlier_chi2;
    summary_.outliers += fix.outlier ? 1 : 0;
  }
}

}  // namespace cairn::lidar3d
