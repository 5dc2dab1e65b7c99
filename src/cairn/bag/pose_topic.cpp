#include "cairn/bag/pose_topic.hpp"

#include <cmath>
#include <stdexcept>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
StampedPose pose_of(const std::string& type, const Value& m) {
  if (type == "nav_msgs/Odometry") {
    const Odometry o = to_odometry(m);
    return {o.header.stamp_ns, o.position, o.orientation};
  }
  if (type == "geometry_msgs/TransformStamped") {
    const TransformStamped t = to_transform_stamped(m);
    return {t.header.stamp_ns, t.translation, t.rotation};
  }
  const Value& pose = type == "geometry_msgs/PoseWithCovarianceStamped" ? m["pose"]["pose"] : m["pose"];
  const Header header = to_header(m["header"]);
  const Value& p = pose["position"];
  const Value& q = pose["orientation"];
  return {header.stamp_ns, {p["x"].number(), p["y"].number(), p["z"].number()},
          Eigen::Quaterniond(q["w"].number(), q["x"].number(), q["y"].number(), q["z"].number())};
}

io::Trajectory read_pose_topic(const std::string& path, const std::string& topic_name) {
  Bag bag = Bag::open(path);
  const std::size_t topic =
      choose_topic(bag, topic_name, {{"nav_msgs/Odometry", "geometry_msgs/PoseStamped",
                                      "geometry_msgs/PoseWithCovarianceStamped", "geometry_msgs/TransformStamped"},
                                     "pose", "BAG:/topic"});
  MessageDecoder decoder(bag);
  const std::string type = decoder.type(topic);
  io::Trajectory trajectory;
  const auto stream = bag.read({topic});
  BagMessage message;
  while (stream->next(&message)) {
    const std::string where = path + ": " + bag.topics()[topic].name + " message " + std::to_string(trajectory.size() + 1);
    StampedPose pose;
    try {
      pose = pose_of(type, decoder.decode(message));
    } catch (const io::ParseError&) {
      throw;
    } catch (const std::runtime_error& e) {
      throw io::ParseError(where, 0, e.what());
    }
    const double norm = pose.orientation.norm();
    if (!pose.position.allFinite() || !std::isfinite(norm) || norm < 1e-9) {
      throw io::ParseError(where, 0, "expected a finite position and a quaternion of non-zero norm");
    }
    const core::Timestamp stamp = core::Timestamp::from_nanoseconds(pose.stamp_ns);
    if (!trajectory.stamps.empty() && !(stamp > trajectory.stamps.back())) {
      throw io::ParseError(where, 0, "stamp " + stamp.to_seconds_string() + " s does not follow the previous " +
                                         trajectory.stamps.back().to_seconds_string() + " s");
    }
    trajectory.stamps.push_back(stamp);
    trajectory.poses.push_back(core::SE3(core::SO3(pose.orientation.normalized()), pose.position));
  }
  if (trajectory.size() == 0) throw io::ParseError(path, 0, "topic " + bag.topics()[topic].name + " holds no message");
  return trajectory;
}

std::optional<std::pair<std::string, std::string>> split_bag_topic(const std::string& argument) {
  const auto colon = argument.rfind(":/");
  if (colon == std::string::npos || colon == 0) return std::nullopt;
  std::string bag = argument.substr(0, colon);
  if (!is_bag(bag)) return std::nullopt;
  return std::make_pair(std::move(bag), argument.substr(colon + 1));
}

}  // namespace cairn::bag
