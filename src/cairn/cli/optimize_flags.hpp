#pragma once
/// \file
/// The flags of `cairn optimize` (cmd_optimize.cpp): their definitions, the combinations refused
/// before any work, and the pose-graph job options they stand for (backend/pose_graph_job.hpp).

#include <CLI/CLI.hpp>
#include <cstdint>
#include <string>
#include <vector>

#include "cairn/backend/pose_graph_job.hpp"
#include "cairn/cli/commands.hpp"

namespace cairn::cli {

struct OptimizeFlags {
  std::string input;
  std::string output;
  std::string format;
  std::string init = "auto";
  std::string solver = "lm";
  std::string objective = "geodesic";
  std::string robust = "none";
  double robust_scale = 1.0;
  double gnc_threshold = 0.0;
  int gnc_inner_iterations = 15;
  double gnc_mu_factor = 1.4;
  double gnc_final_factor = backend::GncOptions{}.final_threshold_factor;
  std::vector<std::int64_t> covariance_ids;
  int threads = 0;
  int max_iterations = 100;
  double initial_radius = backend::OptimizerOptions{}.initial_trust_region_radius;
  bool exact_steps = false;
  bool gauss_newton_hessian = false;
  bool certify = false;
  bool polish_geodesic = false;
  double certify_tolerance = backend::CertificateOptions{}.eigenvalue_tolerance;
  std::string report;
  bool quiet = false;
  GraphReadFlags graph;
  const CLI::App* command = nullptr;  // which flags were given
};

/// Defines the flags of `app` into `flags` (which must outlive it).
void add_optimize_flags(CLI::App& app, OptimizeFlags& flags);

/// Flags that would do nothing with the others given are refused before any work (UsageError).
void check_optimize_flags(const OptimizeFlags& flags);

/// The job the flags ask for; without callbacks (progress, stage_finished) and stop request.
backend::PoseGraphJobOptions optimize_job_options(const OptimizeFlags& flags);

}  // namespace cairn::cli
