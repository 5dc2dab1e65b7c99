#pragma once
/// \file
/// Initial guesses for pose-graph optimisation, for graphs without VERTEX lines (several
/// benchmark graphs) or with poor ones.

#include <string_view>

#include "cairn/backend/problem.hpp"

namespace cairn::backend {

enum class Initialization {
  kFile,      ///< keep the file's VERTEX poses
  kOdometry,  ///< compose measurements along a breadth-first spanning tree from the fixed poses,
              ///< odometry edges first
  kChordal,   ///< chordal relaxation: rotations, then translations (Carlone et al., ICRA 2015)
};
std::string_view to_string(Initialization initialization);

struct InitializationSummary {
  double total_s = 0.0;
  int poses_reached = 0;  ///< odometry: poses reached by the spanning tree
};

/// Breadth-first spanning tree from every fixed pose over the edges (either direction),
/// composing T_world_j = T_world_i * T_i_j. Fixed poses keep their value.
template <class Group>
InitializationSummary initialize_odometry(PoseGraphProblem<Group>& problem);

/// Chordal relaxation (Martinec & Pajdla, CVPR 2007; Carlone, Rosen et al., "Initialization
/// techniques for 3D SLAM", ICRA 2015, sec. IV): (1) rotations as unconstrained d x d matrices
/// minimising sum kappa ||R_j - R_i R~_ij||_F^2 with the fixed poses' rotations held, a linear
/// least-squares problem that separates into d systems (one per row of R) sharing one sparse
/// matrix; each result projected onto SO(d) by SVD; (2) translations minimising
/// sum tau ||t_j - t_i - R_i t~_ij||^2 with those rotations, again linear. Both solved by
/// CHOLMOD. kappa and tau are SE-Sync's isotropic weights.
template <class Group>
InitializationSummary initialize_chordal(PoseGraphProblem<Group>& problem);

}  // namespace cairn::backend
