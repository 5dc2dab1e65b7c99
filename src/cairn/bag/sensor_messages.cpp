#include "cairn/bag/sensor_messages.hpp"

#include <stdexcept>

namespace cairn::bag {
namespace {

Eigen::Vector3d vector3(const Value& v) { return {v["x"].number(), v["y"].number(), v["z"].number()}; }

Eigen::Quaterniond quaternion(const Value& v) {
  return Eigen::Quaterniond(v["w"].number(), v["x"].number(), v["y"].number(), v["z"].number());
}

template <std::size_t N>
std::array<double, N> fixed_numbers(const Value& v, const char* name) {
  const std::vector<double> numbers = v.numbers();
  if (numbers.size() != N) {
    throw std::runtime_error(std::string(name) + " has " + std::to_string(numbers.size()) + " values, expected " +
                             std::to_string(N));
  }
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = numbers[i];
  return out;
}

std::vector<float> floats(const Value& v) {
  std::vector<float> out;
  out.reserve(v.items().size());
  for (const Value& item : v.items()) out.push_back(static_cast<float>(item.number()));
  return out;
}

/// A field spelled differently in ROS 1 and ROS 2 (CameraInfo's "K" and "k").
const Value& either(const Value& message, const char* ros1_name, const char* ros2_name) {
  if (const Value* found = message.find(ros1_name)) return *found;
  return message[ros2_name];
}

}  // namespace

std::int64_t time_ns(const Value& time) {
  const std::int64_t seconds = time["sec"].as_int();
  const Value* nanoseconds = time.find("nanosec");
  const std::int64_t nsec = nanoseconds != nullptr ? nanoseconds->as_int() : time["nsec"].as_int();
  std::int64_t ns = 0;
  // A bag's own definition may declare 64-bit seconds: refuse a time int64 nanoseconds cannot hold.
  if (__builtin_mul_overflow(seconds, std::int64_t{1'000'000'000}, &ns) || __builtin_add_overflow(ns, nsec, &ns)) {
    throw std::runtime_error("time " + std::to_string(seconds) + " s + " + std::to_string(nsec) +
                             " ns is beyond what int64 nanoseconds hold");
  }
  return ns;
}

Header to_header(const Value& header) {
  Header out;
  if (const Value* seq = header.find("seq")) out.seq = static_cast<std::uint32_t>(seq->as_uint());
  out.stamp_ns = time_ns(header["stamp"]);
  out.frame_id = header["frame_id"].text();
  return out;
}

LaserScan to_laser_scan(const Value& m) {
  LaserScan out;
  out.header = to_header(m["header"]);
  out.angle_min_rad = m["angle_min"].number();
  out.angle_max_rad = m["angle_max"].number();
  out.angle_increment_rad = m["angle_increment"].number();
  out.time_increment_s = m["time_increment"].number();
  out.scan_time_s = m["scan_time"].number();
  out.range_min_m = m["range_min"].number();
  out.range_max_m = m["range_max"].number();
  out.ranges_m = floats(m["ranges"]);
  out.intensities = floats(m["intensities"]);
  return out;
}

Imu to_imu(const Value& m) {
  Imu out;
  out.header = to_header(m["header"]);
  out.orientation = quaternion(m["orientation"]);
  out.orientation_covariance = fixed_numbers<9>(m["orientation_covariance"], "orientation_covariance");
  out.angular_velocity_rad_s = vector3(m["angular_velocity"]);
  out.angular_velocity_covariance = fixed_numbers<9>(m["angular_velocity_covariance"], "angular_velocity_covariance");
  out.linear_acceleration_m_s2 = vector3(m["linear_acceleration"]);
  out.linear_acceleration_covariance =
      fixed_numbers<9>(m["linear_acceleration_covariance"], "linear_acceleration_covariance");
  return out;
}

NavSatFix to_nav_sat_fix(const Value& m) {
  NavSatFix out;
  out.header = to_header(m["header"]);
  out.status = static_cast<std::int8_t>(m["status"]["status"].as_int());
  out.service = static_cast<std::uint16_t>(m["status"]["service"].as_uint());
  out.latitude_deg = m["latitude"].number();
  out.longitude_deg = m["longitude"].number();
  out.altitude_m = m["altitude"].number();
  out.position_covariance = fixed_numbers<9>(m["position_covariance"], "position_covariance");
  out.position_covariance_type = static_cast<std::uint8_t>(m["position_covariance_type"].as_uint());
  return out;
}

Odometry to_odometry(const Value& m) {
  Odometry out;
  out.header = to_header(m["header"]);
  out.child_frame_id = m["child_frame_id"].text();
  const Value& pose = m["pose"];
  out.position = vector3(pose["pose"]["position"]);
  out.orientation = quaternion(pose["pose"]["orientation"]);
  out.pose_covariance = fixed_numbers<36>(pose["covariance"], "pose.covariance");
  const Value& twist = m["twist"];
  out.linear_velocity_m_s = vector3(twist["twist"]["linear"]);
  out.angular_velocity_rad_s = vector3(twist["twist"]["angular"]);
  out.twist_covariance = fixed_numbers<36>(twist["covariance"], "twist.covariance");
  return out;
}

PoseStamped to_pose_stamped(const Value& m) {
  PoseStamped out;
  out.header = to_header(m["header"]);
  out.position = vector3(m["pose"]["position"]);
  out.orientation = quaternion(m["pose"]["orientation"]);
  return out;
}

TransformStamped to_transform_stamped(const Value& m) {
  TransformStamped out;
  out.header = to_header(m["header"]);
  out.child_frame_id = m["child_frame_id"].text();
  out.translation = vector3(m["transform"]["translation"]);
  out.rotation = quaternion(m["transform"]["rotation"]);
  return out;
}

std::vector<TransformStamped> to_tf_message(const Value& m) {
  std::vector<TransformStamped> out;
  for (const Value& transform : m["transforms"].items()) out.push_back(to_transform_stamped(transform));
  return out;
}

Image to_image(const Value& m) {
  Image out;
  out.header = to_header(m["header"]);
  out.height = static_cast<std::uint32_t>(m["height"].as_uint());
  out.width = static_cast<std::uint32_t>(m["width"].as_uint());
  out.encoding = m["encoding"].text();
  out.is_bigendian = m["is_bigendian"].as_bool();
  out.step = static_cast<std::uint32_t>(m["step"].as_uint());
  out.data = std::string(m["data"].text());
  return out;
}

CompressedImage to_compressed_image(const Value& m) {
  CompressedImage out;
  out.header = to_header(m["header"]);
  out.format = m["format"].text();
  out.data = std::string(m["data"].text());
  return out;
}

CameraInfo to_camera_info(const Value& m) {
  CameraInfo out;
  out.header = to_header(m["header"]);
  out.height = static_cast<std::uint32_t>(m["height"].as_uint());
  out.width = static_cast<std::uint32_t>(m["width"].as_uint());
  out.distortion_model = m["distortion_model"].text();
  out.D = either(m, "D", "d").numbers();
  out.K = fixed_numbers<9>(either(m, "K", "k"), "K");
  out.R = fixed_numbers<9>(either(m, "R", "r"), "R");
  out.P = fixed_numbers<12>(either(m, "P", "p"), "P");
  return out;
}

}  // namespace cairn::bag
