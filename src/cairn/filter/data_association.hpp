#pragma once
/// \file
/// Data association for range-bearing observations against the landmarks of an EkfSlam state.
///
/// * Individual compatibility (IC): observation i and landmark j are compatible when the squared
///   Mahalanobis distance of the innovation, nu^T S^-1 nu, is below chi2inv(gate_probability, 2).
/// * Nearest neighbour (NN): each observation takes its individually compatible landmark with the
///   smallest distance; pairs are taken in order of distance so no landmark is used twice.
/// * Joint compatibility branch and bound (JCBB, Neira & Tardos 2001, "Data association in
///   stochastic mapping using the joint compatibility test", IEEE T-RA 17(6), Sec. III):
///   the largest hypothesis H (most pairings; ties: smallest joint distance) whose joint
///   innovation nu_H, with joint covariance S_H = H_H P H_H^T + R_H, has
///   D^2_H = nu_H^T S_H^-1 nu_H <= chi2inv(gate_probability, 2 |H|).
///
/// An observation left unpaired (nullopt) is either a new landmark or a spurious observation;
/// the caller decides (see landmarks::LandmarkPipeline's tentative landmarks).

#include <cstddef>
#include <optional>
#include <vector>

#include "cairn/filter/ekf_slam.hpp"

namespace cairn::filter {

enum class AssociationMethod { kNearestNeighbour, kJcbb };

struct AssociationOptions {
  /// Probability mass inside the gate, (0, 1): 0.99 gives chi2inv(0.99, 2) = 9.21 for one pair.
  double gate_probability = 0.99;
  /// JCBB stops expanding after this many nodes (the best hypothesis so far is returned and
  /// AssociationResult::search_truncated is set), >= 1.
  std::size_t max_jcbb_nodes = 200000;
  /// Landmarks whose predicted range exceeds this are not considered, metres (> 0; infinity:
  /// all landmarks).
  double max_candidate_range_m = 1e9;
};

struct AssociationResult {
  /// landmark_of_observation[i]: the landmark paired with observation i, or nullopt.
  std::vector<std::optional<std::size_t>> landmark_of_observation;
  std::size_t pairings = 0;
  /// Joint squared Mahalanobis distance of the chosen hypothesis (JCBB), or the sum of the
  /// individual ones (NN).
  double joint_distance_squared = 0.0;
  /// JCBB nodes expanded (0 for NN).
  std::size_t nodes = 0;
  bool search_truncated = false;
};

/// Nearest neighbour with the IC gate. Invalid observations (EkfSlam::is_valid_observation) stay unpaired.
AssociationResult associate_nearest_neighbour(const EkfSlam& ekf, const std::vector<Vector2>& observations,
                                              const AssociationOptions& options = {});

/// JCBB. Invalid observations stay unpaired.
AssociationResult associate_jcbb(const EkfSlam& ekf, const std::vector<Vector2>& observations,
                                 const AssociationOptions& options = {});

}  // namespace cairn::filter
