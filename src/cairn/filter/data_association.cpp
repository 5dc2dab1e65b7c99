#include "cairn/filter/data_association.hpp"

#include <algorithm>
#include <limits>
#include <tuple>

#include <Eigen/Cholesky>

#include "cairn/filter/chi_square.hpp"

namespace cairn::filter {
namespace {

struct Candidate {
  std::size_t landmark = 0;
  double distance_squared = 0.0;
};

// Individually compatible landmarks per observation, nearest first.
std::vector<std::vector<Candidate>> individually_compatible(const EkfSlam& ekf,
                                                            const std::vector<PredictedObservation>& predictions,
                                                            const std::vector<bool>& considered,
                                                            const std::vector<Vector2>& observations,
                                                            double gate) {
  std::vector<std::vector<Candidate>> candidates(observations.size());
  for (std::size_t i = 0; i < observations.size(); ++i) {
    if (!ekf.is_valid_observation(observations[i])) continue;
    for (std::size_t j = 0; j < predictions.size(); ++j) {
      if (!considered[j]) continue;
      const Vector2 nu = innovation(observations[i], predictions[j].z);
      const double d2 = nu.dot(predictions[j].S.ldlt().solve(nu));
      if (d2 <= gate) candidates[i].push_back({j, d2});
    }
    std::sort(candidates[i].begin(), candidates[i].end(),
              [](const Candidate& a, const Candidate& b) { return a.distance_squared < b.distance_squared; });
  }
  return candidates;
}

void predict_all(const EkfSlam& ekf, const AssociationOptions& options, std::vector<PredictedObservation>* predictions,
                 std::vector<bool>* considered) {
  const std::size_t n = ekf.landmark_count();
  predictions->resize(n);
  considered->assign(n, false);
  const Vector2 t_world_body = ekf.pose().head<2>();
  for (std::size_t j = 0; j < n; ++j) {
    const double range_m = (ekf.landmark(j) - t_world_body).norm();
    if (range_m <= ekf.options().min_range_m || range_m > options.max_candidate_range_m) continue;
    (*predictions)[j] = ekf.predict_observation(j);
    (*considered)[j] = true;
  }
}

// Joint compatibility of a hypothesis (Neira & Tardos 2001, Sec. III). S_H is assembled
// from 2x2 blocks S_ab = J_a P_(a,b) J_b^T + delta_ab R, J_a = [J_z_pose  J_z_landmark] over
// (pose, landmark_a).
class JointCompatibility {
 public:
  JointCompatibility(const EkfSlam& ekf, const std::vector<PredictedObservation>& predictions,
                     const std::vector<Vector2>& observations)
      : ekf_(ekf), predictions_(predictions), observations_(observations) {}

  double distance_squared(const std::vector<std::pair<std::size_t, std::size_t>>& pairs) const {
    const auto k = static_cast<Eigen::Index>(pairs.size());
    Eigen::MatrixXd S(2 * k, 2 * k);
    Eigen::VectorXd nu(2 * k);
    const Matrix3 P_pp = ekf_.pose_covariance();
    for (Eigen::Index a = 0; a < k; ++a) {
      const auto [obs_a, lm_a] = pairs[static_cast<std::size_t>(a)];
      const PredictedObservation& pa = predictions_[lm_a];
      nu.segment<2>(2 * a) = innovation(observations_[obs_a], pa.z);
      const Matrix23 P_ap = ekf_.landmark_pose_covariance(lm_a);
      for (Eigen::Index b = a; b < k; ++b) {
        const auto [obs_b, lm_b] = pairs[static_cast<std::size_t>(b)];
        const PredictedObservation& pb = predictions_[lm_b];
        const Matrix23 P_bp = ekf_.landmark_pose_covariance(lm_b);
        const Matrix2 P_ab = ekf_.landmark_landmark_covariance(lm_a, lm_b);
        Matrix2 block = pa.J_z_pose * P_pp * pb.J_z_pose.transpose() +
                              pa.J_z_pose * P_bp.transpose() * pb.J_z_landmark.transpose() +
                              pa.J_z_landmark * P_ap * pb.J_z_pose.transpose() +
                              pa.J_z_landmark * P_ab * pb.J_z_landmark.transpose();
        if (a == b) block += ekf_.measurement_covariance();
        S.block<2, 2>(2 * a, 2 * b) = block;
        S.block<2, 2>(2 * b, 2 * a) = block.transpose();
      }
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(S);
    return nu.dot(ldlt.solve(nu));
  }

 private:
  const EkfSlam& ekf_;
  const std::vector<PredictedObservation>& predictions_;
  const std::vector<Vector2>& observations_;
};

struct JcbbSearch {
  const std::vector<std::vector<Candidate>>& candidates;
  const JointCompatibility& joint;
  const std::vector<double>& gates;  // gates[k] = chi2inv(p, 2k)
  std::size_t max_nodes;

  std::vector<std::pair<std::size_t, std::size_t>> current;
  std::vector<bool> used;
  std::vector<std::pair<std::size_t, std::size_t>> best;
  double best_distance = std::numeric_limits<double>::infinity();
  double current_distance = 0.0;
  std::size_t nodes = 0;
  bool truncated = false;

  // Neira & Tardos 2001, the JCBB recursion, observations taken in order.
  void search(std::size_t i) {
    if (nodes >= max_nodes) {
      truncated = true;
      return;
    }
    ++nodes;
    const std::size_t m = candidates.size();
    if (i == m) {
      if (current.size() > best.size() || (current.size() == best.size() && current_distance < best_distance)) {
        best = current;
        best_distance = current_distance;
      }
      return;
    }
    for (const Candidate& candidate : candidates[i]) {
      if (used[candidate.landmark]) continue;
      current.emplace_back(i, candidate.landmark);
      const double d2 = joint.distance_squared(current);
      if (d2 <= gates[current.size()]) {
        used[candidate.landmark] = true;
        const double saved = current_distance;
        current_distance = d2;
        search(i + 1);
        current_distance = saved;
        used[candidate.landmark] = false;
      }
      current.pop_back();
    }
    // The star branch (observation i unpaired) only when it can still beat the best (their
    // "pairings(H) + m - i > pairings(Best)", 0-based here).
    if (current.size() + (m - i - 1) > best.size()) search(i + 1);
  }
};

}  // namespace

AssociationResult associate_nearest_neighbour(const EkfSlam& ekf, const std::vector<Vector2>& observations,
                                              const AssociationOptions& options) {
  std::vector<PredictedObservation> predictions;
  std::vector<bool> considered;
  predict_all(ekf, options, &predictions, &considered);
  const double gate = chi_square_quantile(options.gate_probability, 2.0);
  const auto candidates = individually_compatible(ekf, predictions, considered, observations, gate);
  std::vector<std::tuple<double, std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    for (const Candidate& c : candidates[i]) pairs.emplace_back(c.distance_squared, i, c.landmark);
  }
  std::sort(pairs.begin(), pairs.end());
  AssociationResult result;
  result.landmark_of_observation.assign(observations.size(), std::nullopt);
  std::vector<bool> used(ekf.landmark_count(), false);
  for (const auto& [d2, i, j] : pairs) {
    if (result.landmark_of_observation[i] || used[j]) continue;
    result.landmark_of_observation[i] = j;
    used[j] = true;
    ++result.pairings;
    result.joint_distance_squared += d2;
  }
  return result;
}

AssociationResult associate_jcbb(const EkfSlam& ekf, const std::vector<Vector2>& observations,
                                 const AssociationOptions& options) {
  std::vector<PredictedObservation> predictions;
  std::vector<bool> considered;
  predict_all(ekf, options, &predictions, &considered);
  const double gate = chi_square_quantile(options.gate_probability, 2.0);
  const auto candidates = individually_compatible(ekf, predictions, considered, observations, gate);
  std::vector<double> gates(observations.size() + 1, 0.0);
  for (std::size_t k = 1; k < gates.size(); ++k) {
    gates[k] = chi_square_quantile(options.gate_probability, 2.0 * static_cast<double>(k));
  }
  const JointCompatibility joint(ekf, predictions, observations);
  JcbbSearch search{candidates, joint, gates, options.max_jcbb_nodes, {}, {}, {}, 0.0, 0.0, 0, false};
  search.used.assign(ekf.landmark_count(), false);
  search.search(0);

  AssociationResult result;
  result.landmark_of_observation.assign(observations.size(), std::nullopt);
  for (const auto& [i, j] : search.best) result.landmark_of_observation[i] = j;
  result.pairings = search.best.size();
  result.joint_distance_squared = search.best.empty() ? 0.0 : search.best_distance;
  result.nodes = search.nodes;
  result.search_truncated = search.truncated;
  return result;
}

}  // namespace cairn::filter
