#pragma once
/// \file
/// Decodes a bag's messages into Value trees with the layouts the bag itself carries: each
/// connection's definition is parsed once (ROS 1 message_definition, MCAP "ros1msg"/"ros2msg"
/// schema, rosbag2 message_definitions) and kept. A connection whose payload encoding is not
/// ROS 1 or CDR, or whose type comes without a definition, cannot be decoded: can_decode() says
/// why, and cairn lists such topics instead of guessing their layout.

#include <map>
#include <memory>
#include <string>
#include <utility>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/deserialize.hpp"
#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/value.hpp"

namespace cairn::bag {

class MessageDecoder {
 public:
  explicit MessageDecoder(const Bag& bag) : bag_(bag) {}

  /// True when the messages of topic `topic` (index into Bag::topics()) can be decoded; else false
  /// with the reason in `why` ("no message definition in the bag", "encoding 'json' is not ROS 1 or CDR",
  /// or the definition's parse error).
  bool can_decode(std::size_t topic, std::string* why = nullptr);
  /// Decodes one message; throws io::ParseError naming the bag, the topic and the byte.
  Value decode(const BagMessage& message);
  /// The normalised type of a topic ("sensor_msgs/LaserScan", without ROS 2's "/msg/").
  std::string type(std::size_t topic) const;

 private:
  struct Layout {
    std::shared_ptr<const SchemaSet> schemas;  ///< null when it cannot be decoded
    Serialization serialization = Serialization::kRos1;
    std::string problem;
  };
  const Layout& layout(std::size_t file, std::size_t connection);

  const Bag& bag_;
  std::map<std::pair<std::size_t, std::size_t>, Layout> layouts_;
};

}  // namespace cairn::bag
