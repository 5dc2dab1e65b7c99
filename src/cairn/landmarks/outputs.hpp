#pragma once
/// \file
/// The files `cairn landmarks` writes, each atomically (io::OutputFile):
///
///   trajectory.tum   T_world_body at every step (z = 0, rotation about z), TUM
///   landmarks.csv    index,id,x_m,y_m,cov_xx_m2,cov_xy_m2,cov_yy_m2,observations
///                    (id: the true id the estimate stands for, -1 for one made from clutter)
///   report.json      LandmarkSlamReport (timings, associations, ATE, NEES with its chi^2 bands)
///   landmarks.png    estimated landmarks with 95% covariance ellipses, true landmarks,
///                    the estimated trajectory over the ground truth and dead reckoning

#include <string>

#include "cairn/landmarks/landmark_run.hpp"
#include "cairn/landmarks/landmark_slam.hpp"

namespace cairn::landmarks {

/// All throw io::ParseError when a file cannot be written.
void write_trajectory_tum(const std::string& path, const std::vector<TimedPose>& trajectory);
void write_landmark_estimates_csv(const std::string& path, const std::vector<LandmarkEstimate>& landmarks);
void write_report_json(const std::string& path, const LandmarkSlamReport& report);
/// The report as JSON text (for the CLI's stdout and for tests).
std::string report_json(const LandmarkSlamReport& report);
void write_landmarks_png(const std::string& path, const LandmarkRun& run, const LandmarkSlamResult& result);

}  // namespace cairn::landmarks
