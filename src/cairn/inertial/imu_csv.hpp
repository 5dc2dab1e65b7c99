#pragma once
/// \file
/// IMU readings from files that are not EuRoC's: a plain CSV whose header row names each column
/// and its unit (docs/formats.md, "IMU data"), a reader that tells it from EuRoC's
/// imu0/data.csv by the file itself, and sensor_msgs/Imu from a ROS 1 or ROS 2 bag.
///
///     # any comment lines
///     time_s,gyro_x_deg_s,gyro_y_deg_s,gyro_z_deg_s,accel_x_g,accel_y_g,accel_z_g,temperature_c
///     0.000,0.10,-0.20,0.05,0.01,-0.02,1.00,25.1
///
/// Every reader returns samples in SI units (rad/s, m/s^2) with strictly increasing stamps, or
/// throws io::ParseError naming the file (or bag and topic), the line (or message), what was
/// expected and what was found.

#include <filesystem>
#include <string>
#include <vector>

#include "cairn/inertial/imu_types.hpp"

namespace cairn::inertial {

/// Reads a plain IMU CSV. The first line that is neither blank nor a '#' comment is the header:
/// comma-separated column names, in any order, of which these are read (each exactly once):
///  * time: `time_s` (decimal seconds, exact to the ns) or `time_ns` (integer nanoseconds);
///  * gyroscope, for each axis a in x, y, z: `gyro_a_rad_s` or `gyro_a_deg_s`;
///  * accelerometer: `accel_a_mps2` or `accel_a_g` (1 g = kStandardGravity = 9.80665 m/s^2).
/// Other columns are ignored (their fields need not be numbers), but every row must have as many
/// fields as the header. Numbers must be finite; stamps strictly increase. A last line without a
/// newline is read, and a warning saying so appended to `*warnings` when given.
std::vector<ImuSample> read_imu_csv(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr);

/// Writes the plain CSV in SI units: `time_ns,gyro_x_rad_s,...,accel_z_mps2`, numbers in their
/// shortest exact form (read back bit for bit). Throws io::ParseError for an empty list, a
/// non-finite value or stamps that do not increase.
void write_imu_csv(const std::filesystem::path& path, const std::vector<ImuSample>& samples);

/// Reads IMU samples from whatever `path` is: a bag (io: bag::is_bag, a ROS 1 .bag, MCAP, .db3
/// or rosbag2 folder) through read_imu_topic(path, ""); a folder as EuRoC's (mav0/ or imu0/);
/// a file as EuRoC's imu0/data.csv when its first line that is not blank or a comment starts
/// with a number (EuRoC's header is a '#' comment), else as a plain IMU CSV. `warnings` as for
/// read_imu_csv.
std::vector<ImuSample> read_imu_file(const std::filesystem::path& path, std::vector<std::string>* warnings = nullptr);

/// Reads sensor_msgs/Imu messages of a bag's topic: the header stamp is the sample's time, the
/// angular velocity and linear acceleration its readings (orientation and covariances are not
/// used). With an empty `topic`, the bag's only sensor_msgs/Imu topic; several are an error
/// listing them. Non-finite readings and header stamps that do not increase are errors naming
/// the bag, the topic and the message's number (1-based).
std::vector<ImuSample> read_imu_topic(const std::filesystem::path& bag_path, const std::string& topic);

}  // namespace cairn::inertial
