#pragma once
/// \file
/// The sensor messages cairn uses, decoded from Value trees into plain structs: sensor_msgs
/// LaserScan, Imu, NavSatFix, Image, CompressedImage, CameraInfo; nav_msgs Odometry;
/// geometry_msgs PoseStamped, TransformStamped; tf2_msgs TFMessage. ROS 1 and ROS 2 layouts both
/// (std_msgs/Header with or without seq; CameraInfo's D K R P in ROS 1, d k r p in ROS 2). Units
/// are the messages' own (REP 103: metres, radians, seconds), named in the fields.
///
/// Each to_*() throws std::runtime_error when the value lacks a field the type must have (the
/// caller names the topic); the values themselves are not judged here (a NaN range stays NaN).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "cairn/bag/value.hpp"

namespace cairn::bag {

struct Header {
  std::uint32_t seq = 0;  ///< ROS 1 only (0 in ROS 2)
  std::int64_t stamp_ns = 0;
  std::string frame_id;
};

struct LaserScan {
  Header header;
  double angle_min_rad = 0, angle_max_rad = 0, angle_increment_rad = 0;
  double time_increment_s = 0, scan_time_s = 0;
  double range_min_m = 0, range_max_m = 0;
  std::vector<float> ranges_m;
  std::vector<float> intensities;
};

struct Imu {
  Header header;
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< x y z w as stored
  std::array<double, 9> orientation_covariance{};  ///< row-major; [0] = -1: no orientation estimate
  Eigen::Vector3d angular_velocity_rad_s = Eigen::Vector3d::Zero();
  std::array<double, 9> angular_velocity_covariance{};
  Eigen::Vector3d linear_acceleration_m_s2 = Eigen::Vector3d::Zero();
  std::array<double, 9> linear_acceleration_covariance{};
};

struct NavSatFix {
  Header header;
  std::int8_t status = 0;    ///< -1 no fix, 0 fix, 1 SBAS, 2 GBAS
  std::uint16_t service = 0;
  double latitude_deg = 0, longitude_deg = 0, altitude_m = 0;
  std::array<double, 9> position_covariance{};  ///< ENU, m^2, row-major
  std::uint8_t position_covariance_type = 0;
};

struct Odometry {
  Header header;
  std::string child_frame_id;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  std::array<double, 36> pose_covariance{};
  Eigen::Vector3d linear_velocity_m_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d angular_velocity_rad_s = Eigen::Vector3d::Zero();
  std::array<double, 36> twist_covariance{};
};

struct PoseStamped {
  Header header;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};

/// T_parent_child: header.frame_id is the parent, child_frame_id the child (REP 105).
struct TransformStamped {
  Header header;
  std::string child_frame_id;
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
};

struct Image {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string encoding;  ///< "mono8", "rgb8", "bgr8", "16UC1", "32FC1", ...
  bool is_bigendian = false;
  std::uint32_t step = 0;  ///< bytes per row
  std::string data;
};

struct CompressedImage {
  Header header;
  std::string format;  ///< "png", "jpeg", "rgb8; jpeg compressed bgr8", ...
  std::string data;
};

struct CameraInfo {
  Header header;
  std::uint32_t height = 0, width = 0;
  std::string distortion_model;  ///< "plumb_bob", "rational_polynomial", "equidistant", ...
  std::vector<double> D;
  std::array<double, 9> K{};
  std::array<double, 9> R{};
  std::array<double, 12> P{};
};

/// Nanoseconds of a ROS time value: ROS 1 time {sec, nsec} or builtin_interfaces/Time {sec, nanosec}.
std::int64_t time_ns(const Value& time);
Header to_header(const Value& header);
LaserScan to_laser_scan(const Value& message);
Imu to_imu(const Value& message);
NavSatFix to_nav_sat_fix(const Value& message);
Odometry to_odometry(const Value& message);
PoseStamped to_pose_stamped(const Value& message);
TransformStamped to_transform_stamped(const Value& message);
/// tf2_msgs/TFMessage (and ROS 1's tf/tfMessage): its transforms.
std::vector<TransformStamped> to_tf_message(const Value& message);
Image to_image(const Value& message);
CompressedImage to_compressed_image(const Value& message);
CameraInfo to_camera_info(const Value& message);

}  // namespace cairn::bag
