#include "cairn/bag/bag_info.hpp"

#include <algorithm>

#include "cairn/bag/message_decoder.hpp"

namespace cairn::bag {

nlohmann::json bag_info_json(const Bag& bag) {
  nlohmann::json files = nlohmann::json::array();
  for (const auto& file : bag.files()) {
    const ContainerSummary& s = file->summary();
    files.push_back({{"path", file->path()},
                     {"format", s.format},
                     {"profile", s.profile},
                     {"bytes", s.file_bytes},
                     {"chunks", s.chunks},
                     {"indexed", s.indexed},
                     {"notes", s.notes}});
  }
  MessageDecoder decoder(bag);
  nlohmann::json topics = nlohmann::json::array();
  std::uint64_t messages = 0;
  std::int64_t start_ns = 0, end_ns = 0;
  for (std::size_t t = 0; t < bag.topics().size(); ++t) {
    const Topic& topic = bag.topics()[t];
    std::string why;
    const bool decodable = decoder.can_decode(t, &why);
    const double span_s = static_cast<double>(topic.last_ns - topic.first_ns) * 1e-9;
    const double rate_hz = topic.messages > 1 && span_s > 0 ? static_cast<double>(topic.messages - 1) / span_s : 0.0;
    topics.push_back({{"name", topic.name},
                      {"type", topic.type},
                      {"encoding", topic.encoding},
                      {"messages", topic.messages},
                      {"first_ns", topic.first_ns},
                      {"last_ns", topic.last_ns},
                      {"rate_hz", rate_hz},
                      {"decodable", decodable},
                      {"why_not", why}});
    if (topic.messages == 0) continue;
    start_ns = messages == 0 ? topic.first_ns : std::min(start_ns, topic.first_ns);
    end_ns = messages == 0 ? topic.last_ns : std::max(end_ns, topic.last_ns);
    messages += topic.messages;
  }
  return {{"path", bag.path()},
          {"format", bag.format()},
          {"files", files},
          {"messages", messages},
          {"start_ns", start_ns},
          {"end_ns", end_ns},
          {"duration_s", static_cast<double>(end_ns - start_ns) * 1e-9},
          {"topics", topics}};
}

}  // namespace cairn::bag
