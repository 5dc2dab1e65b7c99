#include "cairn/bag/extract.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/laser_log.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/point_cloud2.hpp"
#include "cairn/bag/pose_topic.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/io/carmen_log.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/io/trajectory.hpp"

namespace cairn::bag {
namespace {

std::string file_name_of(const std::string& topic) {
  std::string name;
  for (const char c : topic) {
    if (name.empty() && c == '/') continue;
    name += (c == '/' || c == ' ' || c == ':') ? '_' : c;
  }
  return name.empty() ? "topic" : name;
}

std::string stamp_text(std::int64_t ns) {
  char text[48];
  std::snprintf(text, sizeof text, "%lld.%09lld", static_cast<long long>(ns / 1'000'000'000),
                static_cast<long long>(ns % 1'000'000'000));
  return text;
}

std::ofstream open_text(const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << std::setprecision(17);
  return out;
}

/// Writes an 8- or 16-bit grey or RGB PNG (libpng); 16-bit samples are given in host order.
void write_png(const std::string& path, std::uint32_t width, std::uint32_t height, int channels, int bit_depth,
               const std::vector<unsigned char>& pixels) {
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error("cannot write " + path);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    throw std::runtime_error("libpng could not write " + path);
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, bit_depth, channels == 3 ? PNG_COLOR_TYPE_RGB : PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bit_depth == 16) png_set_swap(png);  // PNG stores big-endian samples
  const std::size_t row_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(channels) * (bit_depth / 8);
  for (std::uint32_t row = 0; row < height; ++row) {
    png_write_row(png, const_cast<png_bytep>(pixels.data() + row * row_bytes));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  if (std::fclose(file) != 0) throw std::runtime_error("cannot write " + path);
}

/// The pixels of an Image, tightly packed, in a layout write_png takes.
void image_to_png(const Image& image, const std::string& path) {
  int channels = 1, bytes_per_sample = 1;
  if (image.encoding == "rgb8" || image.encoding == "bgr8") channels = 3;
  else if (image.encoding == "16UC1" || image.encoding == "mono16") bytes_per_sample = 2;
  else if (image.encoding == "32FC1") bytes_per_sample = 4;
  else if (image.encoding != "mono8" && image.encoding != "8UC1") {
    throw std::runtime_error("image encoding '" + image.encoding + "' is not extracted (mono8, rgb8, bgr8, 16UC1, 32FC1 are)");
  }
  const std::size_t row_in = static_cast<std::size_t>(image.width) * channels * bytes_per_sample;
  if (image.step < row_in || static_cast<std::uint64_t>(image.step) * image.height > image.data.size()) {
    throw std::runtime_error("image data holds " + std::to_string(image.data.size()) + " bytes, less than " +
                             std::to_string(image.height) + " rows of step " + std::to_string(image.step));
  }
  const int out_bytes = bytes_per_sample == 1 ? 1 : 2;
  std::vector<unsigned char> pixels(static_cast<std::size_t>(image.width) * image.height * channels * out_bytes);
  for (std::uint32_t row = 0; row < image.height; ++row) {
    const auto* in = reinterpret_cast<const unsigned char*>(image.data.data()) + static_cast<std::size_t>(row) * image.step;
    unsigned char* out = pixels.data() + static_cast<std::size_t>(row) * image.width * channels * out_bytes;
    for (std::uint32_t column = 0; column < image.width; ++column) {
      const unsigned char* p = in + static_cast<std::size_t>(column) * channels * bytes_per_sample;
      if (channels == 3) {
        const bool bgr = image.encoding == "bgr8";
        out[3 * column] = p[bgr ? 2 : 0];
        out[3 * column + 1] = p[1];
        out[3 * column + 2] = p[bgr ? 0 : 2];
      } else if (bytes_per_sample == 1) {
        out[column] = p[0];
      } else {
        unsigned char raw[4];
        std::memcpy(raw, p, static_cast<std::size_t>(bytes_per_sample));
        if (image.is_bigendian) std::reverse(raw, raw + bytes_per_sample);
        std::uint16_t value = 0;
        if (bytes_per_sample == 2) {
          std::memcpy(&value, raw, 2);
        } else {
          float metres;
          std::memcpy(&metres, raw, 4);
          const double scaled = std::isfinite(metres) && metres > 0 ? std::round(static_cast<double>(metres) * 5000.0) : 0.0;
          value = static_cast<std::uint16_t>(std::min(scaled, 65535.0));
        }
        std::memcpy(out + 2 * column, &value, 2);
      }
    }
  }
  write_png(path, image.width, image.height, channels, out_bytes * 8, pixels);
}

void write_pcd(const std::string& path, const io::PointCloud& cloud) {
  std::ofstream out(path, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + path);
  std::string fields = "x y z", sizes = "4 4 4", types = "F F F", counts = "1 1 1";
  const bool intensity = !cloud.intensity.empty(), ring = !cloud.ring.empty(), time = !cloud.time_s.empty();
  if (intensity) fields += " intensity", sizes += " 4", types += " F", counts += " 1";
  if (ring) fields += " ring", sizes += " 2", types += " U", counts += " 1";
  if (time) fields += " time", sizes += " 4", types += " F", counts += " 1";
  out << "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS " << fields << "\nSIZE " << sizes << "\nTYPE "
      << types << "\nCOUNT " << counts << "\nWIDTH " << cloud.size() << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS "
      << cloud.size() << "\nDATA binary\n";
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    out.write(reinterpret_cast<const char*>(cloud.points[i].data()), 12);
    if (intensity) out.write(reinterpret_cast<const char*>(&cloud.intensity[i]), 4);
    if (ring) out.write(reinterpret_cast<const char*>(&cloud.ring[i]), 2);
    if (time) out.write(reinterpret_cast<const char*>(&cloud.time_s[i]), 4);
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

/// One extracted topic: gets each decoded message, writes what it holds.
class TopicWriter {
 public:
  virtual ~TopicWriter() = default;
  virtual void write(const Value& message) = 0;
  virtual void finish() {}
};

using WriterFactory = std::function<std::unique_ptr<TopicWriter>(const std::string& base)>;

class ImuWriter final : public TopicWriter {
 public:
  explicit ImuWriter(const std::string& base) : out_(open_text(base + ".csv")) {
    out_ << "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
            "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  }
  void write(const Value& m) override {
    const Imu imu = to_imu(m);
    out_ << imu.header.stamp_ns << ',' << imu.angular_velocity_rad_s.x() << ',' << imu.angular_velocity_rad_s.y() << ','
         << imu.angular_velocity_rad_s.z() << ',' << imu.linear_acceleration_m_s2.x() << ','
         << imu.linear_acceleration_m_s2.y() << ',' << imu.linear_acceleration_m_s2.z() << '\n';
  }

 private:
  std::ofstream out_;
};

class NavSatFixWriter final : public TopicWriter {
 public:
  explicit NavSatFixWriter(const std::string& base) : out_(open_text(base + ".csv")) {
    out_ << "#timestamp [ns],status,latitude [deg],longitude [deg],altitude [m],covariance_type,"
            "c00,c01,c02,c10,c11,c12,c20,c21,c22 [m^2, ENU]\n";
  }
  void write(const Value& m) override {
    const NavSatFix fix = to_nav_sat_fix(m);
    out_ << fix.header.stamp_ns << ',' << static_cast<int>(fix.status) << ',' << fix.latitude_deg << ','
         << fix.longitude_deg << ',' << fix.altitude_m << ',' << static_cast<int>(fix.position_covariance_type);
    for (const double c : fix.position_covariance) out_ << ',' << c;
    out_ << '\n';
  }

 private:
  std::ofstream out_;
};

class PoseWriter final : public TopicWriter {
 public:
  PoseWriter(std::string base, std::string type) : path_(std::move(base) + ".tum"), type_(std::move(type)) {}
  void write(const Value& m) override {
    const StampedPose pose = pose_of(type_, m);
    const std::int64_t stamp_ns = pose.stamp_ns;
    const Eigen::Vector3d& p = pose.position;
    const Eigen::Quaterniond& q = pose.orientation;
    if (!trajectory_.stamps.empty() && stamp_ns <= trajectory_.stamps.back().nanoseconds()) return;  // TUM: increasing
    if (q.norm() < 1e-9 || !p.allFinite()) return;
    trajectory_.stamps.push_back(core::Timestamp::from_nanoseconds(stamp_ns));
    trajectory_.poses.push_back(core::SE3(core::SO3(q.normalized()), p));
  }
  void finish() override { io::write_tum(path_, trajectory_); }

 private:
  std::string path_, type_;
  io::Trajectory trajectory_;
};

class PointCloudWriter final : public TopicWriter {
 public:
  explicit PointCloudWriter(const std::string& base) : folder_(base) {
    std::filesystem::create_directories(folder_);
    times_ = open_text(folder_ + "/times.txt");
  }
  void write(const Value& m) override {
    PointCloud2Report report;
    const io::PointCloud cloud = to_point_cloud(m, &report);
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.pcd", count_++);
    write_pcd(folder_ + "/" + name, cloud);
    times_ << stamp_text(report.header.stamp_ns) << '\n';
  }

 private:
  std::string folder_;
  std::ofstream times_;
  std::size_t count_ = 0;
};

class ImageWriter final : public TopicWriter {
 public:
  ImageWriter(const std::string& base, bool compressed) : folder_(base), compressed_(compressed) {
    std::filesystem::create_directories(folder_);
    list_ = open_text(base + ".txt");
    list_ << "# timestamp filename\n";
  }
  void write(const Value& m) override {
    const std::string folder_name = std::filesystem::path(folder_).filename().string();
    if (compressed_) {
      const CompressedImage image = to_compressed_image(m);
      const bool png = image.format.find("png") != std::string::npos;
      const std::string name = stamp_text(image.header.stamp_ns) + (png ? ".png" : ".jpg");
      std::ofstream out(folder_ + "/" + name, std::ios::binary);
      out.write(image.data.data(), static_cast<std::streamsize>(image.data.size()));
      if (!out) throw std::runtime_error("cannot write " + folder_ + "/" + name);
      list_ << stamp_text(image.header.stamp_ns) << ' ' << folder_name << '/' << name << '\n';
      return;
    }
    const Image image = to_image(m);
    const std::string name = stamp_text(image.header.stamp_ns) + ".png";
    image_to_png(image, folder_ + "/" + name);
    list_ << stamp_text(image.header.stamp_ns) << ' ' << folder_name << '/' << name << '\n';
  }

 private:
  std::string folder_;
  bool compressed_;
  std::ofstream list_;
};

class CameraInfoWriter final : public TopicWriter {
 public:
  explicit CameraInfoWriter(const std::string& base) : path_(base + ".yaml") {}
  void write(const Value& m) override {
    if (written_) return;
    written_ = true;
    const CameraInfo info = to_camera_info(m);
    std::ofstream out = open_text(path_);
    const auto list = [&](const char* key, const auto& values) {
      out << key << ": [";
      for (std::size_t i = 0; i < values.size(); ++i) out << (i == 0 ? "" : ", ") << values[i];
      out << "]\n";
    };
    out << "# sensor_msgs/CameraInfo, first message (frame " << info.header.frame_id << ")\n";
    out << "image_width: " << info.width << "\nimage_height: " << info.height << "\ndistortion_model: "
        << info.distortion_model << '\n';
    list("D", info.D);
    list("K", info.K);
    list("R", info.R);
    list("P", info.P);
  }

 private:
  std::string path_;
  bool written_ = false;
};

/// The writer for a type, or null when the type is not extracted here.
WriterFactory factory_for(const std::string& type) {
  if (type == "sensor_msgs/Imu") return [](const std::string& b) { return std::make_unique<ImuWriter>(b); };
  if (type == "sensor_msgs/NavSatFix") return [](const std::string& b) { return std::make_unique<NavSatFixWriter>(b); };
  if (type == "nav_msgs/Odometry" || type == "geometry_msgs/PoseStamped" ||
      type == "geometry_msgs/PoseWithCovarianceStamped") {
    return [type](const std::string& b) { return std::make_unique<PoseWriter>(b, type); };
  }
  if (type == "sensor_msgs/PointCloud2") return [](const std::string& b) { return std::make_unique<PointCloudWriter>(b); };
  if (type == "sensor_msgs/Image") return [](const std::string& b) { return std::make_unique<ImageWriter>(b, false); };
  if (type == "sensor_msgs/CompressedImage") {
    return [](const std::string& b) { return std::make_unique<ImageWriter>(b, true); };
  }
  if (type == "sensor_msgs/CameraInfo") return [](const std::string& b) { return std::make_unique<CameraInfoWriter>(b); };
  return nullptr;
}

/// ROBOTLASER1 records of a laser log (io/carmen_log.hpp reads them back).
void write_laser_clf(const std::string& path, const io::CarmenLog& log) {
  std::ofstream out = open_text(path);
  out << "# written by cairn convert from a bag's sensor_msgs/LaserScan topic\n";
  for (const io::LaserScan& scan : log.scans) {
    const double fov = scan.geometry.angular_resolution_rad * static_cast<double>(scan.ranges_m.size() - 1);
    out << "ROBOTLASER1 0 " << scan.geometry.start_angle_rad << ' ' << fov << ' ' << scan.geometry.angular_resolution_rad
        << ' ' << scan.geometry.max_range_m.value_or(0.0) << " 0 0 " << scan.ranges_m.size();
    for (const float r : scan.ranges_m) out << ' ' << r;
    out << ' ' << scan.remissions.size();
    for (const float r : scan.remissions) out << ' ' << r;
    const auto pose = [&](const core::SE2& T) { out << ' ' << T.x() << ' ' << T.y() << ' ' << T.angle(); };
    pose(scan.T_odom_laser);
    pose(scan.T_odom_robot);
    const std::string t = io::format_carmen_time(scan.time);
    out << " 0 0 0 0 0 " << t << " cairn " << t << '\n';
  }
  if (!out) throw std::runtime_error("cannot write " + path);
}

}  // namespace

ExtractReport extract_bag(const std::string& path, const std::string& out_dir, const ExtractOptions& options) {
  Bag bag = Bag::open(path);
  for (const std::string& name : options.topics) (void)bag.topic_index(name);  // unknown names: an error listing topics
  io::OutputDirectory out(out_dir, options.overwrite);
  MessageDecoder decoder(bag);
  ExtractReport report;
  std::vector<std::unique_ptr<TopicWriter>> writers(bag.topics().size());
  std::vector<std::size_t> selected;
  for (std::size_t t = 0; t < bag.topics().size(); ++t) {
    const Topic& topic = bag.topics()[t];
    ExtractedTopic entry{topic.name, topic.type, "", 0, ""};
    const bool wanted = options.topics.empty() ||
                        std::find(options.topics.begin(), options.topics.end(), topic.name) != options.topics.end();
    const std::string type = decoder.type(t);
    std::string why;
    if (!wanted) {
      entry.skipped_because = "not selected";
    } else if (type == "sensor_msgs/LaserScan") {
      entry.output = file_name_of(topic.name) + ".clf";  // read through read_laser_log below
    } else if (const WriterFactory factory = factory_for(type); !factory) {
      entry.skipped_because = "type not extracted";
    } else if (!decoder.can_decode(t, &why)) {
      entry.skipped_because = why;
    } else {
      entry.output = file_name_of(topic.name) + (type.find("Image") != std::string::npos || type.ends_with("PointCloud2") ? "/" : "");
      writers[t] = factory(out.staging_path(file_name_of(topic.name)));
      selected.push_back(t);
    }
    report.topics.push_back(entry);
  }
  if (!selected.empty()) {
    const auto stream = bag.read(selected);
    BagMessage message;
    while (stream->next(&message)) {
      try {
        writers[message.topic]->write(decoder.decode(message));
      } catch (const io::ParseError&) {
        throw;
      } catch (const std::runtime_error& e) {
        throw io::ParseError(path, 0, bag.topics()[message.topic].name + " message at " +
                                          std::to_string(message.message.log_time_ns) + " ns: " + e.what());
      }
      ++report.topics[message.topic].messages;
      ++report.messages;
    }
    for (const auto& writer : writers) {
      if (writer) writer->finish();
    }
  }
  for (ExtractedTopic& entry : report.topics) {
    if (entry.output.empty() || !entry.output.ends_with(".clf")) continue;
    LaserLogReport laser;
    const io::CarmenLog log = read_laser_log(path, {entry.topic, ""}, &laser);
    write_laser_clf(out.staging_path(entry.output), log);
    entry.messages = log.scans.size();
    report.messages += log.scans.size();
  }
  out.commit();
  return report;
}

}  // namespace cairn::bag
