#pragma once
/// \file
/// The BAL ("Bundle Adjustment in the Large", Agarwal et al., ECCV 2010) problem format, as on
/// grail.cs.washington.edu/projects/bal and in Ceres' examples/bal_problem.cc:
///
///     <num_cameras> <num_points> <num_observations>
///     <camera_index> <point_index> <x> <y>          (num_observations lines; pixels, origin at
///                                                    the image centre, x right, y up)
///     <camera parameters>                            (9 per camera: angle-axis w (3),
///                                                    translation t (3), f, k1, k2)
///     <point coordinates>                            (3 per point)
///
/// Numbers are whitespace-separated; line breaks are not significant (GTSAM's
/// dubrovnik-3-7-pre.txt has blank lines between sections), so the reader is token-based.
/// gzip and bzip2 files are decompressed transparently (io/compressed_file.hpp); "-" reads
/// standard input. Every failure throws ParseError naming the file, the line and what was
/// expected: a truncated file, a camera or point index out of range, a non-finite number, extra
/// data after the points, binary bytes, counts the file cannot hold.

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

namespace cairn::io {

struct BalObservation {
  int camera = 0;
  int point = 0;
  double x = 0.0;
  double y = 0.0;
};

struct BalProblem {
  static constexpr int kCameraSize = 9;
  int num_cameras = 0;
  int num_points = 0;
  std::vector<BalObservation> observations;
  std::vector<double> cameras;  ///< 9 per camera, in file order
  std::vector<double> points;   ///< 3 per point

  double* camera(int index) { return cameras.data() + kCameraSize * static_cast<std::size_t>(index); }
  const double* camera(int index) const { return cameras.data() + kCameraSize * static_cast<std::size_t>(index); }
  double* point(int index) { return points.data() + 3 * static_cast<std::size_t>(index); }
  const double* point(int index) const { return points.data() + 3 * static_cast<std::size_t>(index); }
};

/// Reads a BAL file (plain, gzip or bzip2; "-" = standard input).
BalProblem read_bal(const std::string& path);
/// Parses BAL text already in memory, naming `path` in errors (the fuzz target's entry).
BalProblem parse_bal(const std::string& path, const std::string& contents);

/// Writes `problem` in the BAL format with 17 significant digits (round-trips exactly).
/// Throws std::runtime_error when the stream fails.
void write_bal(std::ostream& out, const BalProblem& problem);

/// Observations whose point lies behind its camera (P_z >= 0 in BAL's -z-forward convention):
/// the BAL model still defines their residual, so they are kept and counted, not dropped.
std::size_t count_points_behind_camera(const BalProblem& problem);

/// Index of the first observation whose point lies in its camera's plane (P_z = 0), where BAL's
/// projection -P/P_z is undefined; -1 when there is none.
long long first_observation_in_camera_plane(const BalProblem& problem);

}  // namespace cairn::io
