#include "cairn/bag/topic_choice.hpp"

#include <algorithm>

#include "cairn/bag/message_schema.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

std::string type_list(const std::vector<std::string>& types) {
  std::string out;
  for (const std::string& type : types) out += (out.empty() ? "" : " or ") + type;
  return out;
}

std::string topic_list(const Bag& bag, const std::vector<std::size_t>& topics) {
  std::string out;
  for (const std::size_t t : topics) out += (out.empty() ? "" : ", ") + bag.topics()[t].name;
  return out;
}

}  // namespace

std::vector<std::size_t> topics_of_type(const Bag& bag, const std::vector<std::string>& types) {
  std::vector<std::size_t> found;
  for (std::size_t t = 0; t < bag.topics().size(); ++t) {
    const std::string type = normalize_type(bag.topics()[t].type);
    if (std::find(types.begin(), types.end(), type) != types.end()) found.push_back(t);
  }
  return found;
}

std::optional<std::size_t> choose_optional_topic(const Bag& bag, const std::string& requested, const TopicWanted& wanted) {
  if (requested == "none") return std::nullopt;
  if (!requested.empty()) {
    const std::size_t t = bag.topic_index(requested);
    const std::string type = normalize_type(bag.topics()[t].type);
    if (std::find(wanted.types.begin(), wanted.types.end(), type) == wanted.types.end()) {
      throw io::ParseError(bag.path(), 0, wanted.flag + " " + requested + ": the topic has type " + bag.topics()[t].type +
                                              ", expected " + type_list(wanted.types));
    }
    return t;
  }
  const std::vector<std::size_t> candidates = topics_of_type(bag, wanted.types);
  if (candidates.empty()) return std::nullopt;
  if (candidates.size() > 1) {
    throw io::ParseError(bag.path(), 0, std::to_string(candidates.size()) + " " + wanted.what + " topics (" +
                                            topic_list(bag, candidates) + "): choose one with " + wanted.flag);
  }
  return candidates.front();
}

std::size_t choose_topic(const Bag& bag, const std::string& requested, const TopicWanted& wanted) {
  if (requested == "none") throw io::ParseError(bag.path(), 0, wanted.flag + " cannot be 'none': the command needs a " + wanted.what + " topic");
  if (const auto found = choose_optional_topic(bag, requested, wanted)) return *found;
  std::vector<std::size_t> all(bag.topics().size());
  for (std::size_t t = 0; t < all.size(); ++t) all[t] = t;
  std::string listing;
  for (const Topic& topic : bag.topics()) listing += "\n  " + topic.name + " (" + topic.type + ")";
  throw io::ParseError(bag.path(), 0, "no " + wanted.what + " topic (" + type_list(wanted.types) + "); the bag has:" +
                                          (listing.empty() ? " no topics" : listing));
}

}  // namespace cairn::bag
