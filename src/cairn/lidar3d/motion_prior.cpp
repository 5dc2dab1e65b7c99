#include "cairn/lidar3d/motion_prior.hpp"

#include <algorithm>

#include "cairn/core/assert.hpp"

namespace cairn::lidar3d {

core::SE3 MotionPrior::at(double time_s) const {
  CAIRN_ASSERT(!times_s.empty() && times_s.size() == T_world_sensor.size(), "MotionPrior needs matching samples");
  if (time_s <= times_s.front()) return T_world_sensor.front();
  if (time_s >= times_s.back()) return T_world_sensor.back();
  const auto upper = std::upper_bound(times_s.begin(), times_s.end(), time_s);
  const std::size_t j = static_cast<std::size_t>(upper - times_s.begin());
  const double u = (time_s - times_s[j - 1]) / (times_s[j] - times_s[j - 1]);
  const core::SE3& A = T_world_sensor[j - 1];
  const core::SE3& B = T_world_sensor[j];
  return core::SE3(A.so3().unit_quaternion().slerp(u, B.so3().unit_quaternion()),
                   (1.0 - u) * A.translation() + u * B.translation());
}

bool MotionPrior::covers(double time_s) const {
  return !times_s.empty() && time_s >= times_s.front() && time_s <= times_s.back();
}

}  // namespace cairn::lidar3d
