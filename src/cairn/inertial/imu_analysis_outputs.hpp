#pragma once
/// \file
/// `cairn imu --out DIR`'s files: report.json (to_json of the analysis, plus what the run read),
/// allan.png (the Allan deviation of every gyro and accelerometer axis on log-log axes, with the
/// fitted white-noise line) and, with ground truth, preintegration.png (each window's rotation and
/// position error and NEES over time).

#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "cairn/inertial/imu_analysis.hpp"
#include "cairn/io/output_file.hpp"

namespace cairn::inertial {

/// Writes the files into `out`'s staging directory and returns their names. `inputs` goes into
/// report.json as "inputs" (what the command read).
std::vector<std::string> write_imu_analysis_outputs(io::OutputDirectory& out, const ImuAnalysis& analysis,
                                                    const nlohmann::json& inputs);

}  // namespace cairn::inertial
