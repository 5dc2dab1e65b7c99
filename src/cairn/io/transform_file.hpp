#pragma once
/// \file
/// A rigid transform in a text file, as people hand them to registration tools: 12 numbers (a
/// KITTI pose line, the top three rows of the matrix) or 16 (the 4 x 4 matrix, last row 0 0 0 1,
/// as small_gicp's and Open3D's examples write T_target_source), separated by white space over any
/// number of lines; a line starting with '#' is a comment. The 3 x 3 block must be a rotation to
/// within kMaxRotationOrthonormalityError (trajectory.hpp), then it is projected onto SO(3).
/// Anything else is an io::ParseError naming the file, the line and what was expected.

#include <string>

#include "cairn/core/se3.hpp"

namespace cairn::io {

/// Parses `contents`, naming `path` in errors.
core::SE3 parse_transform(const std::string& path, const std::string& contents);

/// Reads and parses `path` (compressed or not).
core::SE3 read_transform(const std::string& path);

}  // namespace cairn::io
