// cairn's bag readers against the field's own tools, on fixtures made at test time by
// tests/bag/fixtures/make_all.sh (ctest fixture "bag_fixtures"; $CAIRN_BAG_FIXTURES):
//   * every Imu, Odometry, NavSatFix and LaserScan field of the real Husky and LaserScan bags equal
//     to what python3-rosbag reads from the same files (ros1_reference.py);
//   * PointCloud2, Image and CompressedImage bags written by python3-rosbag, and MCAP files
//     written by Foxglove's @mcap/core with @foxglove/cdr, decoded to the source data (the KITTI
//     PCD files, the TUM PNG files read by OpenCV).

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/tf_tree.hpp"
#include "cairn/io/point_cloud.hpp"
#include "test_data.hpp"

namespace cairn::bag {
namespace {

std::filesystem::path fixtures() {
  const char* dir = std::getenv("CAIRN_BAG_FIXTURES");
  return dir != nullptr ? dir : "";
}

#define REQUIRE_FIXTURE(name)                                                                    \
  do {                                                                                           \
    if (!std::filesystem::exists(fixtures() / (name))) {                                         \
      GTEST_SKIP() << "fixture " << (fixtures() / (name)) << " not made (tests/bag/fixtures/make_all.sh)"; \
    }                                                                                            \
  } while (false)

std::string unescape(const std::string& token) {
  if (token == "-") return "";
  std::string out;
  for (std::size_t i = 0; i < token.size(); ++i) {
    if (token[i] == '%' && i + 2 < token.size()) {
      out += static_cast<char>(std::stoi(token.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += token[i];
    }
  }
  return out;
}

/// The numbers cairn decoded, in the reference's order for each type (ros1_reference.py's layout).
std::vector<double> decoded_numbers(const std::string& type, const Value& m, std::string* child_frame) {
  std::vector<double> out;
  const auto add = [&](const auto& values) { out.insert(out.end(), values.begin(), values.end()); };
  const auto add3 = [&](const Eigen::Vector3d& v) { add(std::vector<double>{v.x(), v.y(), v.z()}); };
  const auto add_q = [&](const Eigen::Quaterniond& q) { add(std::vector<double>{q.x(), q.y(), q.z(), q.w()}); };
  if (type == "sensor_msgs/Imu") {
    const Imu imu = to_imu(m);
    add_q(imu.orientation);
    add(imu.orientation_covariance);
    add3(imu.angular_velocity_rad_s);
    add(imu.angular_velocity_covariance);
    add3(imu.linear_acceleration_m_s2);
    add(imu.linear_acceleration_covariance);
  } else if (type == "nav_msgs/Odometry") {
    const Odometry o = to_odometry(m);
    *child_frame = o.child_frame_id;
    add3(o.position);
    add_q(o.orientation);
    add(o.pose_covariance);
    add3(o.linear_velocity_m_s);
    add3(o.angular_velocity_rad_s);
    add(o.twist_covariance);
  } else if (type == "sensor_msgs/NavSatFix") {
    const NavSatFix f = to_nav_sat_fix(m);
    add(std::vector<double>{static_cast<double>(f.status), static_cast<double>(f.service), f.latitude_deg,
                            f.longitude_deg, f.altitude_m});
    add(f.position_covariance);
    out.push_back(f.position_covariance_type);
  } else if (type == "sensor_msgs/LaserScan") {
    const LaserScan s = to_laser_scan(m);
    add(std::vector<double>{s.angle_min_rad, s.angle_max_rad, s.angle_increment_rad, s.time_increment_s, s.scan_time_s,
                            s.range_min_m, s.range_max_m, static_cast<double>(s.ranges_m.size())});
    for (const float r : s.ranges_m) out.push_back(static_cast<double>(r));
    out.push_back(static_cast<double>(s.intensities.size()));
    for (const float r : s.intensities) out.push_back(static_cast<double>(r));
  }
  return out;
}

/// Compares every message of `bag_path` with the reference python3-rosbag wrote for it.
void expect_equal_to_rosbag(const std::string& bag_path, const std::string& reference_path) {
  std::ifstream reference(reference_path);
  ASSERT_TRUE(reference) << reference_path;
  Bag bag = Bag::open(bag_path);
  MessageDecoder decoder(bag);
  const auto stream = bag.read();
  std::string line;
  std::size_t compared = 0;
  while (std::getline(reference, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in(line);
    std::string topic, type, frame, seq, log_ns, stamp_ns;
    in >> topic >> type >> log_ns >> seq >> stamp_ns >> frame;
    BagMessage message;
    ASSERT_TRUE(stream->next(&message)) << "cairn ran out of messages at reference line " << compared + 1;
    ASSERT_EQ(bag.topics()[message.topic].name, topic) << "message " << compared;
    ASSERT_EQ(message.message.log_time_ns, std::stoll(log_ns)) << topic << " message " << compared;
    const Value value = decoder.decode(message);
    const Header header = to_header(value["header"]);
    EXPECT_EQ(header.seq, std::stoul(seq));
    EXPECT_EQ(header.stamp_ns, std::stoll(stamp_ns));
    EXPECT_EQ(header.frame_id, unescape(frame));
    std::string child_frame;
    const std::vector<double> decoded = decoded_numbers(type, value, &child_frame);
    if (type == "nav_msgs/Odometry") {
      std::string token;
      in >> token;
      EXPECT_EQ(child_frame, unescape(token));
    }
    std::vector<double> expected;
    std::string number;
    while (in >> number) expected.push_back(std::strtod(number.c_str(), nullptr));
    ASSERT_EQ(decoded.size(), expected.size()) << topic << " message " << compared;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      if (std::isnan(expected[i])) {
        EXPECT_TRUE(std::isnan(decoded[i]));
      } else {
        EXPECT_EQ(decoded[i], expected[i]) << topic << " message " << compared << " number " << i;
      }
    }
    ++compared;
  }
  BagMessage extra;
  EXPECT_FALSE(stream->next(&extra)) << "cairn streams more messages than rosbag";
  EXPECT_GT(compared, 0u);
}

TEST(BagAgainstRosbag, HuskyImuOdometryAndNavSatFixDecodeExactly) {
  CAIRN_REQUIRE_DATA("bags/robot_localization_test1.bag");
  REQUIRE_FIXTURE("robot_localization_test1.ref.txt");
  expect_equal_to_rosbag(test::data_path("bags/robot_localization_test1.bag").string(),
                         (fixtures() / "robot_localization_test1.ref.txt").string());
}

TEST(BagAgainstRosbag, LaserScansOfTheBagWithTheMalformedIndexDecodeExactly) {
  CAIRN_REQUIRE_DATA("bags/scan_tools_laser_scan_matcher_demo.bag");
  REQUIRE_FIXTURE("scan_tools_laser_scan_matcher_demo.ref.txt");
  expect_equal_to_rosbag(test::data_path("bags/scan_tools_laser_scan_matcher_demo.bag").string(),
                         (fixtures() / "scan_tools_laser_scan_matcher_demo.ref.txt").string());
}

/// The clouds of a fixture bag: make_ros1_bags.py and make_mcap.mjs keep every 10th point of the
/// first key frames, with intensity = the point's index in its PCD file.
void expect_kitti_clouds(const std::string& bag_path) {
  Bag bag = Bag::open(bag_path);
  MessageDecoder decoder(bag);
  const std::size_t topic = bag.topic_index("/velodyne_points");
  const auto stream = bag.read({topic});
  BagMessage message;
  std::size_t k = 0;
  std::ifstream list(test::data_path("lidar3d/kitti00_keyframes/keyframes.txt"));
  std::string row;
  while (stream->next(&message)) {
    do std::getline(list, row); while (!row.empty() && row[0] == '#');
    std::istringstream fields(row);
    std::string index, line, frame, time, file;
    fields >> index >> line >> frame >> time >> file;
    const io::PointCloud source = io::read_point_cloud(test::data_path("lidar3d/kitti00_keyframes/" + file).string());
    PointCloud2Report report;
    const io::PointCloud cloud = to_point_cloud(decoder.decode(message), &report);
    EXPECT_EQ(report.header.frame_id, "velodyne");
    EXPECT_EQ(report.header.stamp_ns, std::llround(std::stod(time) * 1e9)) << k;
    ASSERT_EQ(cloud.size(), (source.size() + 9) / 10) << "scan " << k;
    for (std::size_t j = 0; j < cloud.size(); ++j) {
      ASSERT_EQ(cloud.points[j], source.points[10 * j]) << "scan " << k << " point " << j;
      ASSERT_EQ(cloud.intensity[j], static_cast<float>(10 * j));
    }
    ++k;
  }
  EXPECT_EQ(k, 20u);
}

TEST(BagFromIndependentWriters, Ros1PointCloud2MatchesTheKittiScans) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes");
  REQUIRE_FIXTURE("kitti_points.bag");
  expect_kitti_clouds((fixtures() / "kitti_points.bag").string());
}

TEST(BagFromIndependentWriters, McapCdrPointCloud2MatchesTheKittiScansWithAndWithoutSummary) {
  CAIRN_REQUIRE_DATA("lidar3d/kitti00_keyframes");
  REQUIRE_FIXTURE("kitti_points.mcap");
  expect_kitti_clouds((fixtures() / "kitti_points.mcap").string());
  REQUIRE_FIXTURE("kitti_points_unindexed.mcap");
  expect_kitti_clouds((fixtures() / "kitti_points_unindexed.mcap").string());
}

TEST(BagFromIndependentWriters, TfStaticGivesTheSensorExtrinsics) {
  REQUIRE_FIXTURE("kitti_points.bag");
  for (const char* name : {"kitti_points.bag", "kitti_points.mcap"}) {
    if (!std::filesystem::exists(fixtures() / name)) continue;
    Bag bag = Bag::open((fixtures() / name).string());
    MessageDecoder decoder(bag);
    TfTree tf;
    const auto stream = bag.read({bag.topic_index("/tf_static")});
    BagMessage message;
    while (stream->next(&message)) {
      for (const TransformStamped& t : to_tf_message(decoder.decode(message))) tf.add(t, true);
    }
    const auto T_base_velodyne = tf.lookup("base_link", "velodyne", 0);
    ASSERT_TRUE(T_base_velodyne.has_value()) << name;
    EXPECT_NEAR(T_base_velodyne->translation().z(), 1.73, 1e-12) << name;
    const auto T_velodyne_base = tf.lookup("velodyne", "base_link", 0);
    EXPECT_TRUE((*T_velodyne_base * *T_base_velodyne).matrix().isIdentity(1e-12));
    EXPECT_FALSE(tf.lookup("base_link", "camera", 0).has_value());
  }
}

TEST(BagFromIndependentWriters, ImagesAndCompressedImagesEqualTheTumFiles) {
  CAIRN_REQUIRE_DATA("visual/tum_fr1_desk_every4th");
  REQUIRE_FIXTURE("tum_rgbd.bag");
  REQUIRE_FIXTURE("tum_rgb_compressed.bag");
  std::ifstream associations(test::data_path("visual/tum_fr1_desk_every4th/associations.txt"));
  std::vector<std::string> rgb_files, depth_files;
  std::string t1, f1, t2, f2;
  while (associations >> t1 >> f1 >> t2 >> f2) {
    rgb_files.push_back(f1);
    depth_files.push_back(f2);
  }
  Bag bag = Bag::open((fixtures() / "tum_rgbd.bag").string());
  MessageDecoder decoder(bag);
  std::size_t rgb = 0, depth = 0, info = 0;
  const auto stream = bag.read();
  BagMessage message;
  const std::string root = test::data_path("visual/tum_fr1_desk_every4th/").string();
  while (stream->next(&message)) {
    const std::string& topic = bag.topics()[message.topic].name;
    const Value value = decoder.decode(message);
    if (topic == "/camera/rgb/image_color") {
      const Image image = to_image(value);
      cv::Mat expected = cv::imread(root + rgb_files.at(rgb++), cv::IMREAD_COLOR);
      cv::cvtColor(expected, expected, cv::COLOR_BGR2RGB);
      ASSERT_EQ(image.encoding, "rgb8");
      ASSERT_EQ(image.data, std::string(reinterpret_cast<const char*>(expected.data), expected.total() * 3));
    } else if (topic == "/camera/depth/image") {
      const Image image = to_image(value);
      const cv::Mat expected = cv::imread(root + depth_files.at(depth++), cv::IMREAD_ANYDEPTH);
      ASSERT_EQ(image.encoding, "16UC1");
      ASSERT_EQ(image.data, std::string(reinterpret_cast<const char*>(expected.data), expected.total() * 2));
    } else if (topic == "/camera/rgb/camera_info") {
      const CameraInfo camera = to_camera_info(value);
      EXPECT_EQ(camera.K[0], 517.3);
      EXPECT_EQ(camera.K[4], 516.5);
      EXPECT_EQ(camera.D.size(), 5u);
      ++info;
    }
  }
  EXPECT_GT(rgb, 0u);
  EXPECT_EQ(rgb, depth);
  EXPECT_EQ(rgb, info);

  Bag compressed = Bag::open((fixtures() / "tum_rgb_compressed.bag").string());
  MessageDecoder compressed_decoder(compressed);
  const auto images = compressed.read();
  std::size_t k = 0;
  while (images->next(&message)) {
    const CompressedImage image = to_compressed_image(compressed_decoder.decode(message));
    std::ifstream file(root + rgb_files.at(k++), std::ios::binary);
    std::ostringstream contents;
    contents << file.rdbuf();
    const std::string bytes = contents.str();
    EXPECT_EQ(image.format, "png");
    EXPECT_EQ(image.data, bytes);
  }
  EXPECT_EQ(k, rgb);
}

}  // namespace
}  // namespace cairn::bag
