#pragma once
/// \file
/// `cairn convert BAG DIR`: a bag's sensor topics written out in the folder formats cairn (and
/// the field's tools) already read, one file or folder per topic, named after the topic
/// ("/camera/rgb/image_color" -> camera_rgb_image_color):
///   * sensor_msgs/LaserScan -> NAME.clf, a CARMEN log of ROBOTLASER1 records (beam geometry,
///     ranges with no-returns at range_max, odometry poses when the bag has one Odometry topic),
///     as `cairn slam2d` replays it;
///   * sensor_msgs/PointCloud2 -> NAME/000000.pcd ... (binary PCD v0.7: x y z, and intensity, ring,
///     time in seconds from the stamp when the cloud has them) and NAME/times.txt (one stamp in
///     seconds per scan), as `cairn slam3d NAME --times NAME/times.txt` reads them;
///   * sensor_msgs/Image -> NAME/<stamp>.png (mono8, rgb8, bgr8 as 8-bit PNG; 16UC1 as 16-bit;
///     32FC1 depth in metres as 16-bit PNG at TUM's 5000 per metre, NaN as 0) and NAME.txt
///     ("stamp file" lines, TUM's rgb.txt/depth.txt);
///   * sensor_msgs/CompressedImage -> NAME/<stamp>.png or .jpg, the bytes as they are, and NAME.txt;
///   * sensor_msgs/Imu -> NAME.csv in EuRoC's imu0/data.csv layout (ns, gyro rad/s, accel m/s^2);
///   * nav_msgs/Odometry, geometry_msgs/PoseStamped, PoseWithCovarianceStamped -> NAME.tum;
///   * sensor_msgs/NavSatFix -> NAME.csv (ns, status, latitude, longitude, altitude, covariance);
///   * sensor_msgs/CameraInfo -> NAME.yaml (the first message: size, model, D, K, R, P).
/// Other topics are listed as skipped with the reason. The folder is written whole or not at all
/// (io::OutputDirectory).

#include <cstddef>
#include <map>
#include <string>
#include <vector>

namespace cairn::bag {

struct ExtractedTopic {
  std::string topic;
  std::string type;
  std::string output;  ///< file or folder name inside the output directory; "" when skipped
  std::size_t messages = 0;
  std::string skipped_because;
};

struct ExtractReport {
  std::vector<ExtractedTopic> topics;
  std::size_t messages = 0;
};

struct ExtractOptions {
  /// Topics to extract (empty: every topic of a type listed above).
  std::vector<std::string> topics;
  bool overwrite = false;
};

/// Extracts the bag at `path` into the directory `out_dir`. Throws io::ParseError for a damaged
/// bag or message, std::runtime_error when the directory cannot be written.
ExtractReport extract_bag(const std::string& path, const std::string& out_dir, const ExtractOptions& options = {});

}  // namespace cairn::bag
