#pragma once
/// \file
/// `cairn vslam`'s input: which images (a dataset folder, or a bag's image topics through
/// vslam/bag_images.hpp) and which camera (the dataset's, the bag's CameraInfo, --calib or
/// --camera), with the checks made before any work.

#include <optional>
#include <string>

#include "cairn/cli/vslam_flags.hpp"
#include "cairn/io/image_sequence.hpp"
#include "cairn/vision/features.hpp"
#include "cairn/vslam/bag_images.hpp"
#include "cairn/vslam/evaluation.hpp"

namespace cairn::cli {

/// What a run reads: a dataset folder, or a bag's image topics.
struct VslamInput {
  io::ImageSequence folder;
  std::optional<vslam::BagImages> bag;
  io::ImageSequence& sequence() { return bag ? bag->sequence : folder; }
  const io::ImageSequence& sequence() const { return bag ? bag->sequence : folder; }
};

/// The folder or the bag FOLDER names; bag flags with a folder are a usage error.
VslamInput read_vslam_input(const VslamFlags& flags);
/// The camera; refused when given twice, or stereo without a baseline. Returns an EuRoC pair's rectifier.
std::optional<vision::StereoRectifier> resolve_calibration(VslamInput& input, const VslamFlags& flags);
/// Where the calibration came from, for messages and report.json.
std::string calibration_source(const VslamInput& input, const VslamFlags& flags);
/// --ground-truth, else the dataset's (EuRoC's moved from the body to the rectified left camera).
vslam::GroundTruth resolve_ground_truth(const io::ImageSequence& seq, const VslamFlags& flags,
                                        const std::optional<vision::StereoRectifier>& rectifier);
/// Refuses an implausible calibration before any work, naming where it came from.
void check_calibration(const VslamInput& input, const VslamFlags& flags);

}  // namespace cairn::cli
