#include "cairn/lidar3d/registration.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <Eigen/Eigenvalues>
#include <cmath>

namespace cairn::lidar3d {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;
using Vector6 = Eigen::Matrix<double, 6, 1>;

struct LinearSystem {
  Matrix6 H = Matrix6::Zero();        // of the chosen metric
  Vector6 g = Vector6::Zero();
  Matrix6 H_plane = Matrix6::Zero();  // point-to-plane, for the degeneracy analysis
  Eigen::Matrix3d normal_moment = Eigen::Matrix3d::Zero();  // sum w n n^T
  double plane_weight_sum = 0.0;
  double plane_squared_range_sum = 0.0;
  double squared_distance_sum = 0.0;
  std::size_t correspondences = 0;
  std::size_t planar = 0;

  LinearSystem& operator+=(const LinearSystem& other) {
    H += other.H;
    g += other.g;
    H_plane += other.H_plane;
    plane_weight_sum += other.plane_weight_sum;
    normal_moment += other.normal_moment;
    plane_squared_range_sum += other.plane_squared_range_sum;
    squared_distance_sum += other.squared_distance_sum;
    correspondences += other.correspondences;
    planar += other.planar;
    return *this;
  }
};

// Geman-McClure weight as KISS-ICP: kappa^2 / (kappa + r^2)^2, on the squared residual used.
double geman_mcclure_weight(double kernel, double squared_residual) {
  const double denominator = kernel + squared_residual;
  return kernel * kernel / (denominator * denominator);
}

// d(exp(delta) p) / d(rotation part of delta) at delta = 0: -[p]x.
Eigen::Matrix3d minus_hat(const Eigen::Vector3d& p) {
  Eigen::Matrix3d m;
  m << 0.0, p.z(), -p.y(), -p.z(), 0.0, p.x(), p.y(), -p.x(), 0.0;
  return m;
}

// Sums add(p_map, system) over the source points moved into the map frame by T_map_sensor, in
// fixed chunks reduced in a fixed tree (parallel_deterministic_reduce with its default
// simple_partitioner): the same sums whatever the number of threads.
template <class AddPoint>
LinearSystem accumulate(const std::vector<Eigen::Vector3d>& source_sensor, const core::SE3& T_map_sensor,
                        const AddPoint& add) {
  constexpr std::size_t kGrain = 512;
  const Eigen::Matrix3d R = T_map_sensor.rotation_matrix();
  const Eigen::Vector3d t = T_map_sensor.translation();
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, source_sensor.size(), kGrain), LinearSystem{},
      [&](const tbb::blocked_range<std::size_t>& range, LinearSystem system) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) add(Eigen::Vector3d(R * source_sensor[i] + t), system);
        return system;
      },
      [](LinearSystem a, const LinearSystem& b) { return a += b; });
}

LinearSystem build_system(const VoxelHashMap& map, const std::vector<Eigen::Vector3d>& source_sensor,
                          const core::SE3& T_map_sensor, double max_squared_distance, double kernel,
                          IcpMetric metric, bool point_to_point_fallback = true) {
  const Eigen::Vector3d origin = T_map_sensor.translation();
  return accumulate(source_sensor, T_map_sensor, [&](const Eigen::Vector3d& p, LinearSystem& system) {
    Eigen::Vector3d q, n;
    double d2 = 0.0;
    if (!map.nearest(p, &q, &d2, &n) || d2 > max_squared_distance) return;
    const bool planar = n.squaredNorm() > 0.0;
    if (!point_to_point_fallback && !planar) return;
    const Eigen::Vector3d r = p - q;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>().setIdentity();
    J.rightCols<3>() = minus_hat(p);
    system.squared_distance_sum += d2;
    ++system.correspondences;
    if (planar) {
      const Eigen::Matrix<double, 1, 6> Jn = n.transpose() * J;
      const double e = n.dot(r);
      const double w = geman_mcclure_weight(kernel, e * e);
      system.H_plane.noalias() += w * Jn.transpose() * Jn;
      system.plane_weight_sum += w;
      system.normal_moment.noalias() += w * n * n.transpose();
      system.plane_squared_range_sum += w * (p - origin).squaredNorm();
      ++system.planar;
      if (metric == IcpMetric::kPointToPlane) {
        system.H.noalias() += w * Jn.transpose() * Jn;
        system.g.noalias() += (w * e) * Jn.transpose();
        return;
      }
    }
    const double w = geman_mcclure_weight(kernel, d2);
    system.H.noalias() += w * J.transpose() * J;
    system.g.noalias() += w * J.transpose() * r;
  });
}

// LOAM's edge residual (Zhang & Singh 2014, eq. 2): the distance from the point to the map's
// line through q along d, e = (I - d d^T)(p - q), J = (I - d d^T) [I, -[p]x]. Points whose nearest
// map voxel is not linear are skipped. A line tells about the two directions across it: its
// information share for the degeneracy test is (I - d d^T) / 2.
LinearSystem build_edge_system(const VoxelHashMap& map, const std::vector<Eigen::Vector3d>& source_sensor,
                               const core::SE3& T_map_sensor, double max_squared_distance, double kernel) {
  const Eigen::Vector3d origin = T_map_sensor.translation();
  return accumulate(source_sensor, T_map_sensor, [&](const Eigen::Vector3d& p, LinearSystem& system) {
    Eigen::Vector3d q, d;
    double d2 = 0.0;
    if (!map.nearest(p, &q, &d2, nullptr, &d) || d2 > max_squared_distance || d.squaredNorm() == 0.0) return;
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - d * d.transpose();
    const Eigen::Vector3d e = P * (p - q);
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = P;
    J.rightCols<3>() = P * minus_hat(p);
    const double e2 = e.squaredNorm();
    const double w = geman_mcclure_weight(kernel, e2);
    system.H.noalias() += w * J.transpose() * J;
    system.g.noalias() += w * J.transpose() * e;
    system.H_plane.noalias() += w * J.transpose() * J;
    system.normal_moment.noalias() += (0.5 * w) * P;
    system.plane_weight_sum += w;
    system.plane_squared_range_sum += w * (p - origin).squaredNorm();
    system.squared_distance_sum += e2;
    ++system.correspondences;
    ++system.planar;
  });
}

// Gauss-Newton with the degeneracy analysis, on whatever `build(T)` linearises.
template <class Build>
RegistrationResult solve(const Build& build, std::size_t source_points, const core::SE3& T_map_sensor_guess,
                         const RegistrationOptions& options) {
  RegistrationResult result;
  result.T_map_sensor = T_map_sensor_guess;
  result.source_points = source_points;
  Vector6 previous_delta = Vector6::Zero();
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    const LinearSystem system = build(result.T_map_sensor);
    result.iterations = iteration + 1;
    result.correspondences = system.correspondences;
    result.planar_correspondences = system.planar;
    result.hessian = system.H;
    result.rms_m = system.correspondences > 0
                       ? std::sqrt(system.squared_distance_sum / static_cast<double>(system.correspondences))
                       : 0.0;
    if (system.correspondences < 6) {
      result.degeneracy = 0.0;
      result.eigenvalues.setZero();
      break;
    }
    // Degeneracy (Zhang et al. 2016) of the surfaces: the 6-DoF normalised point-to-plane matrix
    // H_s = S H_plane S / sum w (reported), and the weighted mean N = sum w n n^T / sum w of the
    // planar correspondences' normals, whose eigenvalues (in [0, 1/3] for the smallest) say how
    // much the surfaces constrain each translation direction (decides). Without enough planar
    // correspondences there is nothing to judge: the full step is taken.
    Vector6 delta = Vector6::Zero();
    result.degenerate_directions = 0;
    result.degeneracy = 0.0;
    result.translation_degeneracy = 0.0;
    result.eigenvalues.setZero();
    if (system.planar >= 6 && system.plane_weight_sum > 0.0) {
      const double L = std::sqrt(system.plane_squared_range_sum / system.plane_weight_sum);
      result.characteristic_length_m = L;
      Vector6 scale;
      scale << 1.0, 1.0, 1.0, 1.0 / L, 1.0 / L, 1.0 / L;
      const Matrix6 H_s = scale.asDiagonal() * system.H_plane * scale.asDiagonal() / system.plane_weight_sum;
      const Eigen::SelfAdjointEigenSolver<Matrix6> eigen(H_s);
      result.eigenvalues = eigen.eigenvalues();
      result.degeneracy = std::max(0.0, result.eigenvalues(0));
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> normals(system.normal_moment / system.plane_weight_sum);
      const Eigen::Vector3d nu = normals.eigenvalues();
      const Eigen::Matrix3d& W = normals.eigenvectors();
      result.translation_degeneracy = std::max(0.0, nu(0));
      result.weakest_direction << W.col(0), Eigen::Vector3d::Zero();
      // Solution remapping (Zhang et al. 2016, Sec. V): keep the prior along the degenerate
      // translation directions by solving the step within the span B of the others (and every
      // rotation): delta = B y, (B^T H B) y = -B^T g. It stays finite where H itself is singular
      // (a tunnel seen only by planes).
      int well = 0;
      Eigen::Matrix<double, 6, 6> B = Eigen::Matrix<double, 6, 6>::Zero();
      for (int k = 0; k < 3; ++k) {
        if (nu(k) > options.degenerate_min_eigenvalue) {
          B.block<3, 1>(0, well++) = W.col(k);
        } else {
          ++result.degenerate_directions;
        }
      }
      if (result.degenerate_directions > 0 && options.remap_degenerate_directions) {
        for (int k = 0; k < 3; ++k) B(3 + k, well++) = 1.0;
        const Eigen::MatrixXd Bw = B.leftCols(well);
        const Eigen::MatrixXd reduced = Bw.transpose() * system.H * Bw;
        const Eigen::VectorXd y = reduced.ldlt().solve(-(Bw.transpose() * system.g));
        delta = Bw * y;
      }
    }
    if (result.degenerate_directions == 0 || !options.remap_degenerate_directions) {
      delta = system.H.ldlt().solve(-system.g);
    }
    if (!delta.allFinite()) break;
    // A point whose nearest neighbour flips between two voxels at every step makes a two-cycle
    // (delta, -delta, delta, ...) that never meets the step criterion: when a step undoes the
    // previous one to within the tolerance, stop half-way between the two poses.
    if (iteration > 0 && (delta + previous_delta).norm() < options.convergence_step) {
      result.T_map_sensor = core::SE3::exp(0.5 * delta) * result.T_map_sensor;
      result.converged = true;
      break;
    }
    result.T_map_sensor = core::SE3::exp(delta) * result.T_map_sensor;
    previous_delta = delta;
    if (delta.norm() < options.convergence_step) {
      result.converged = true;
      break;
    }
  }
  return result;
}

}  // namespace

RegistrationResult register_scan(const VoxelHashMap& map, const std::vector<Eigen::Vector3d>& source_sensor,
                                 const core::SE3& T_map_sensor_guess, double max_correspondence_m,
                                 double kernel_scale_m, const RegistrationOptions& options) {
  const double max_squared = max_correspondence_m * max_correspondence_m;
  return solve(
      [&](const core::SE3& T) {
        return build_system(map, source_sensor, T, max_squared, kernel_scale_m, options.metric);
      },
      source_sensor.size(), T_map_sensor_guess, options);
}

RegistrationResult register_features(const VoxelHashMap& edge_map, const VoxelHashMap& plane_map,
                                     const std::vector<Eigen::Vector3d>& edges_sensor,
                                     const std::vector<Eigen::Vector3d>& planes_sensor,
                                     const core::SE3& T_map_sensor_guess, double max_correspondence_m,
                                     double kernel_scale_m, const RegistrationOptions& options) {
  const double max_squared = max_correspondence_m * max_correspondence_m;
  return solve(
      [&](const core::SE3& T) {
        LinearSystem system = build_system(plane_map, planes_sensor, T, max_squared, kernel_scale_m,
                                           IcpMetric::kPointToPlane, /*point_to_point_fallback=*/false);
        system += build_edge_system(edge_map, edges_sensor, T, max_squared, kernel_scale_m);
        return system;
      },
      edges_sensor.size() + planes_sensor.size(), T_map_sensor_guess, options);
}

std::string name_direction(const Eigen::Matrix<double, 6, 1>& direction_map, const core::SO3& R_map_sensor,
                           double length_m) {
  const Eigen::Matrix3d R_sensor_map = R_map_sensor.matrix().transpose();
  const Eigen::Vector3d translation = R_sensor_map * direction_map.head<3>();
  const Eigen::Vector3d rotation = R_sensor_map * direction_map.tail<3>() * length_m;
  Eigen::Index axis = 0;
  if (translation.cwiseAbs().maxCoeff() >= rotation.cwiseAbs().maxCoeff()) {
    translation.cwiseAbs().maxCoeff(&axis);
    static const char* const kNames[] = {"x (forward)", "y (left)", "z (up)"};
    return kNames[axis];
  }
  rotation.cwiseAbs().maxCoeff(&axis);
  static const char* const kNames[] = {"roll", "pitch", "yaw"};
  return kNames[axis];
}

}  // namespace cairn::lidar3d
