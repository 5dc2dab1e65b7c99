#pragma once
/// \file
/// The JSON report of a pose-graph job (pose_graph_job.hpp): sizes, initialisation, solver,
/// objective and robust cost, the solve's summary with its per-iteration log and timings, final
/// costs, and what ran of GNC, the certificate and staircase, the geodesic polish and the
/// marginal covariances. The caller adds what the job does not know: input and output names,
/// the reader's warnings, the interrupting signal (`cairn optimize`).

#include <nlohmann/json.hpp>

#include "cairn/backend/optimizer.hpp"
#include "cairn/backend/pose_graph_job.hpp"

namespace cairn::backend {

/// An optimiser's summary: termination, message, costs, iterations, sizes, time per phase in
/// seconds and the per-iteration log.
nlohmann::json optimizer_summary_json(const OptimizerSummary& summary);

/// The report of a job run with `options`; JSON has no infinity, so an unknown end of a
/// certificate's bracket is null.
nlohmann::json pose_graph_report_json(const PoseGraphJobSummary& summary, const PoseGraphJobOptions& options);

}  // namespace cairn::backend
