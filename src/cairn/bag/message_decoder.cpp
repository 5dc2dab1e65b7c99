#include "cairn/bag/message_decoder.hpp"

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {

const MessageDecoder::Layout& MessageDecoder::layout(std::size_t file, std::size_t connection_index) {
  const auto key = std::make_pair(file, connection_index);
  if (auto it = layouts_.find(key); it != layouts_.end()) return it->second;
  const Connection& connection = bag_.files().at(file)->connections().at(connection_index);
  const std::string where = bag_.files()[file]->path() + ": topic " + connection.topic + " (" + connection.type + ")";
  Layout layout;
  if (connection.encoding == "ros1") {
    layout.serialization = Serialization::kRos1;
  } else if (connection.encoding == "cdr") {
    layout.serialization = Serialization::kCdr;
  } else {
    layout.problem = "message encoding '" + connection.encoding + "' is not ROS 1 or CDR";
  }
  const bool ros2_text = connection.definition_encoding == "ros2msg";
  const bool ros1_text = connection.definition_encoding == "ros1msg" || connection.definition_encoding.empty();
  if (layout.problem.empty() && connection.definition.empty()) {
    layout.problem = "the bag carries no message definition for " + connection.type;
  } else if (layout.problem.empty() && !ros1_text && !ros2_text) {
    layout.problem = "message definitions in '" + connection.definition_encoding + "' are not read (ros1msg, ros2msg are)";
  }
  if (layout.problem.empty()) {
    try {
      const auto dialect = ros2_text || layout.serialization == Serialization::kCdr ? SchemaSet::Dialect::kRos2
                                                                                    : SchemaSet::Dialect::kRos1;
      layout.schemas = std::make_shared<const SchemaSet>(
          SchemaSet::parse(connection.type, connection.definition, dialect, where));
    } catch (const io::ParseError& e) {
      layout.problem = e.detail();
    }
  }
  return layouts_.emplace(key, std::move(layout)).first->second;
}

bool MessageDecoder::can_decode(std::size_t topic, std::string* why) {
  for (const auto& [file, connection] : bag_.topics().at(topic).connections) {
    const Layout& found = layout(file, connection);
    if (found.schemas == nullptr) {
      if (why != nullptr) *why = found.problem;
      return false;
    }
  }
  return true;
}

Value MessageDecoder::decode(const BagMessage& message) {
  const Layout& found = layout(message.file, message.message.connection);
  const Connection& connection = bag_.connection(message);
  const std::string& file = bag_.files()[message.file]->path();
  if (found.schemas == nullptr) {
    throw io::ParseError(file, 0, "topic " + connection.topic + " (" + connection.type + "): " + found.problem);
  }
  // Name the message only when it fails: this runs once per message.
  static const std::string kUnnamed;
  try {
    return deserialize(*found.schemas, message.message.data, found.serialization, kUnnamed, message.message.owner);
  } catch (const io::ParseError& e) {
    throw io::ParseError(file + ": " + connection.topic + " message at " + std::to_string(message.message.log_time_ns) +
                             " ns (record at byte " + std::to_string(message.message.file_offset) + ")",
                         0, e.detail());
  }
}

std::string MessageDecoder::type(std::size_t topic) const { return normalize_type(bag_.topics().at(topic).type); }

}  // namespace cairn::bag
