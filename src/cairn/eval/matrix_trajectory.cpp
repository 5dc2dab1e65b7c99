#include "cairn/eval/matrix_trajectory.hpp"

#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::eval {

MatrixTrajectory::MatrixTrajectory(const io::Trajectory& trajectory) : stamps(trajectory.stamps) {
  poses.reserve(trajectory.poses.size());
  for (const core::SE3& pose : trajectory.poses) poses.push_back(pose.matrix());
}

MatrixTrajectory read_kitti_matrices(const std::string& path, const std::string& times_path) {
  // The strict reader first: its checks and messages, and the stamps.
  const io::Trajectory checked = io::read_kitti(path, times_path);
  MatrixTrajectory result;
  result.stamps = checked.stamps;
  result.poses.reserve(checked.poses.size());
  // Then the numbers as written; the file just passed io::read_kitti, so every non-comment
  // line holds 12 finite numbers.
  io::TextReader reader(path);
  while (reader.next_line()) {
    if (io::is_blank_or_comment(reader.line())) continue;
    const auto tokens = io::split_whitespace(reader.line());
    if (tokens.size() != 12) reader.fail("expected 12 numbers, found " + std::to_string(tokens.size()));
    Matrix4 T = Matrix4::Identity();
    for (int k = 0; k < 12; ++k) T(k / 4, k % 4) = io::parse_double(reader, tokens[static_cast<std::size_t>(k)], "a pose entry");
    result.poses.push_back(T);
  }
  if (result.poses.size() != checked.poses.size()) {
    throw io::ParseError(path, 0, "changed while being read (" + std::to_string(checked.poses.size()) + " then " +
                                      std::to_string(result.poses.size()) + " poses)");
  }
  return result;
}

Outcome validate_trajectory(const MatrixTrajectory& trajectory, const char* name) {
  const std::string who(name);
  if (trajectory.poses.empty()) return {Status::kEmpty, who + " trajectory has no poses"};
  if (trajectory.has_stamps() && trajectory.stamps.size() != trajectory.poses.size()) {
    return {Status::kSizeMismatch, who + " trajectory has " + std::to_string(trajectory.stamps.size()) +
                                       " timestamps for " + std::to_string(trajectory.poses.size()) + " poses"};
  }
  for (std::size_t i = 0; i < trajectory.poses.size(); ++i) {
    if (!trajectory.poses[i].allFinite()) {
      return {Status::kNotFinite, who + " pose " + std::to_string(i) + " holds a NaN or infinity"};
    }
  }
  for (std::size_t i = 1; i < trajectory.stamps.size(); ++i) {
    if (trajectory.stamps[i] <= trajectory.stamps[i - 1]) {
      return {Status::kUnsortedStamps, who + " timestamps must strictly increase, but pose " + std::to_string(i) +
                                           " (t = " + trajectory.stamps[i].to_seconds_string() + " s) follows t = " +
                                           trajectory.stamps[i - 1].to_seconds_string() + " s"};
    }
  }
  return {};
}

Matrix4 se3_inverse(const Matrix4& T) {
  Matrix4 inverse = Matrix4::Identity();
  const Matrix3 R_transposed = T.topLeftCorner<3, 3>().transpose();
  inverse.topLeftCorner<3, 3>() = R_transposed;
  inverse.topRightCorner<3, 1>() = -R_transposed * T.topRightCorner<3, 1>();
  return inverse;
}

}  // namespace cairn::eval
