#include "cairn/navigation/wheel_odometry_reader.hpp"

#include <cmath>
#include <stdexcept>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/bag/sensor_messages.hpp"
#include "cairn/bag/topic_choice.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::navigation {

namespace {

bag::Odometry decode(bag::MessageDecoder& decoder, const bag::BagMessage& message, const std::string& where) {
  try {
    return bag::to_odometry(decoder.decode(message));
  } catch (const io::ParseError&) {
    throw;
  } catch (const std::runtime_error& e) {
    throw io::ParseError(where, 0, e.what());
  }
}

void check(const bag::Odometry& o, const std::string& where) {
  const double norm = o.orientation.norm();
  if (!o.position.allFinite() || !std::isfinite(norm) || norm < 1e-9) {
    throw io::ParseError(where, 0, "expected a finite position and a quaternion of non-zero norm");
  }
  if (!std::isfinite(o.linear_velocity_m_s.x())) {
    throw io::ParseError(where, 0, "expected a finite twist.linear.x, found " + std::to_string(o.linear_velocity_m_s.x()));
  }
  if (!(std::isfinite(o.twist_covariance[0]) && o.twist_covariance[0] >= 0.0)) {
    throw io::ParseError(where, 0, "expected twist_covariance[0] >= 0, found " + std::to_string(o.twist_covariance[0]));
  }
}

}  // namespace

WheelOdometryRecording read_wheel_odometry_bag(const std::string& bag_path, const std::string& topic_name) {
  bag::Bag bag = bag::Bag::open(bag_path);
  const std::size_t topic = bag::choose_topic(bag, topic_name, {{"nav_msgs/Odometry"}, "wheel odometry", "--wheel-topic"});
  bag::MessageDecoder decoder(bag);
  WheelOdometryRecording out;
  const auto stream = bag.read({topic});
  bag::BagMessage message;
  std::size_t count = 0;
  while (stream->next(&message)) {
    ++count;
    const std::string where = bag_path + ": " + bag.topics()[topic].name + " message " + std::to_string(count);
    const bag::Odometry o = decode(decoder, message, where);
    check(o, where);
    const core::Timestamp stamp = core::Timestamp::from_nanoseconds(o.header.stamp_ns);
    if (!out.speeds.empty() && !(stamp > out.speeds.back().stamp)) {
      throw io::ParseError(where, 0, "stamp " + stamp.to_seconds_string() + " s does not follow the previous " +
                                         out.speeds.back().stamp.to_seconds_string() + " s");
    }
    if (count == 1) {
      out.frame_id = o.header.frame_id;
      out.child_frame_id = o.child_frame_id;
    }
    out.speeds.push_back({stamp, o.linear_velocity_m_s.x(), o.twist_covariance[0]});
    out.poses.stamps.push_back(stamp);
    out.poses.poses.emplace_back(core::SO3(o.orientation.normalized()), o.position);
  }
  return out;
}

}  // namespace cairn::navigation
