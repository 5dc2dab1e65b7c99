#include "cairn/backend/pose_graph_report.hpp"

#include <cmath>

namespace cairn::backend {

nlohmann::json optimizer_summary_json(const OptimizerSummary& s) {
  nlohmann::json j;
  j["termination"] = to_string(s.termination);
  j["message"] = s.message;
  j["initial_cost"] = s.initial_cost;
  j["final_cost"] = s.final_cost;
  j["iterations"] = s.iterations;
  j["successful_iterations"] = s.successful_iterations;
  j["free_poses"] = s.free_poses;
  j["edges"] = s.edges;
  j["factor_nonzeros"] = s.factor_nonzeros;
  j["time_s"] = {{"total", s.total_s},   {"analyze", s.analyze_s}, {"linearize", s.linearize_s},
                 {"factorize", s.factorize_s}, {"solve", s.solve_s}};
  nlohmann::json log = nlohmann::json::array();
  for (const auto& it : s.iteration_log) {
    log.push_back({{"iteration", it.iteration},
                   {"cost", it.cost},
                   {"cost_change", it.cost_change},
                   {"gradient_max_norm", it.gradient_max_norm},
                   {"step_norm", it.step_norm},
                   {"relative_decrease", it.relative_decrease},
                   {"lambda_or_radius", it.lambda},
                   {"accepted", it.step_accepted},
                   {"cg_iterations", it.cg_iterations},
                   {"linearize_s", it.linearize_s},
                   {"factorize_s", it.factorize_s},
                   {"solve_s", it.solve_s},
                   {"iteration_s", it.iteration_s}});
  }
  j["iteration_log"] = log;
  return j;
}

namespace {

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

nlohmann::json certificate_json(const CertificateSummary& certificate, const CertificateOptions& options) {
  return {{"certified", certificate.certified},
          {"f", certificate.f},
          {"lambda_min_lower", finite_or_null(certificate.lambda_min_lower)},
          {"lambda_min_upper", finite_or_null(certificate.lambda_min_upper)},
          {"eigenvalue_tolerance", options.eigenvalue_tolerance},
          {"suboptimality_bound", finite_or_null(certificate.suboptimality_bound)},
          {"relative_suboptimality_bound", finite_or_null(certificate.relative_suboptimality_bound)},
          {"rank", certificate.rank},
          {"factorizations", certificate.factorizations},
          {"factor_nonzeros", certificate.factor_nonzeros},
          {"time_s", certificate.time_s},
          {"message", certificate.message}};
}

nlohmann::json staircase_json(const StaircaseSummary& staircase) {
  nlohmann::json levels = nlohmann::json::array();
  for (const auto& level : staircase.levels) {
    levels.push_back({{"rank", level.rank},
                      {"iterations", level.iterations},
                      {"f", level.f},
                      {"certified", level.certificate.certified},
                      {"lambda_min_lower", finite_or_null(level.certificate.lambda_min_lower)},
                      {"lambda_min_upper", finite_or_null(level.certificate.lambda_min_upper)},
                      {"time_s", level.certificate.time_s}});
  }
  return {{"levels", levels},
          {"f_initial", staircase.f_initial},
          {"f_final", staircase.f_final},
          {"time_s", staircase.time_s},
          {"interrupted", staircase.interrupted},
          {"message", staircase.message}};
}

nlohmann::json covariances_json(const std::vector<PoseCovariance>& covariances) {
  nlohmann::json poses = nlohmann::json::array();
  for (const auto& pose : covariances) {
    poses.push_back({{"id", pose.id}, {"covariance_row_major", pose.covariance_row_major}});
  }
  return {{"tangent", "right perturbation T exp(delta), translation first"}, {"poses", poses}};
}

nlohmann::json gnc_json(const GncSummary& gnc, const std::vector<RejectedEdge>& rejected_edges) {
  nlohmann::json rejected = nlohmann::json::array();
  for (const auto& edge : rejected_edges) {
    rejected.push_back({{"from", edge.from}, {"to", edge.to}, {"line", edge.line}, {"edge_index", edge.edge_index}});
  }
  return {{"outer_iterations", gnc.outer_iterations}, {"inner_iterations", gnc.inner_iterations},
          {"factorizations", gnc.factorizations},     {"analyses", gnc.analyses},
          {"threshold_chi2", gnc.threshold_chi2},     {"final_mu", gnc.final_mu},
          {"initial_threshold_chi2", gnc.initial_threshold_chi2},
          {"graduation_threshold_chi2", gnc.graduation_threshold_chi2},
          {"noise_variance_factor", gnc.noise_variance_factor},
          {"short_loop_variance_factor", gnc.short_loop_variance_factor},
          {"regraduated", gnc.regraduated},           {"solves", gnc.solves},
          {"restarted_from_chordal", gnc.restarted},
          {"reclassify_rounds", gnc.reclassify_rounds},
          {"groups_tried", gnc.groups_tried},         {"groups_readmitted", gnc.groups_readmitted},
          {"readmitted_by_innovation", gnc.readmitted_by_innovation},
          {"rejected_by_leave_one_out", gnc.rejected_by_leave_one_out},
          {"tls_cost", gnc.tls_cost},
          {"message", gnc.message},                   {"time_s", gnc.total_s},
          {"interrupted", gnc.interrupted},
          {"stage_time_s",
           {{"graduation", gnc.graduation_s},
            {"reclassification", gnc.reclassify_s},
            {"restart_from_chordal", gnc.restart_s},
            {"group_readmission", gnc.groups_s},
            {"innovation_readmission", gnc.innovation_s}}},
          {"rejected", rejected}};
}

}  // namespace

nlohmann::json pose_graph_report_json(const PoseGraphJobSummary& summary, const PoseGraphJobOptions& options) {
  nlohmann::json j;
  j["poses"] = summary.poses;
  j["edges"] = summary.edges;
  j["initialization"] = {{"method", to_string(summary.initialization)},
                         {"time_s", summary.initialization_summary.total_s}};
  j["solver"] = to_string(options.solver.algorithm);
  j["objective"] = to_string(options.solver.objective);
  j["robust"] = robust_cost_name(options);
  j["cost_after_initialization"] = summary.cost_after_initialization;
  j["summary"] = optimizer_summary_json(summary.solve);
  j["final_chi2_geodesic"] = summary.final_chi2_geodesic;
  j["final_f_chordal"] = summary.final_f_chordal;
  if (summary.staircase) {
    j["certificate"] = certificate_json(summary.staircase->certificate, options.certificate);
    j["staircase"] = staircase_json(*summary.staircase);
  }
  if (summary.polish) {
    j["geodesic_polish"] = optimizer_summary_json(*summary.polish);
    j["geodesic_polish"]["note"] =
        "g2o's chi2 minimised from the chordal solution; the certificate, if any, is that of the chordal point before it";
  }
  j["interrupted"] = summary.interrupted;
  if (summary.covariances) j["marginal_covariances"] = covariances_json(*summary.covariances);
  if (summary.gnc) j["gnc"] = gnc_json(*summary.gnc, summary.rejected_edges);
  return j;
}

}  // namespace cairn::backend
