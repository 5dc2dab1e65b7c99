#pragma once
/// \file
/// Which topic of a bag a command reads: the one the user named (checked to exist and to have a
/// type the command decodes), else the only topic of such a type. Errors list what the bag has,
/// so the user can pick: "no topic '/scn'; the bag has: /scan (sensor_msgs/LaserScan) ..." or
/// "3 topics of type sensor_msgs/Image: /left, /right, /depth: choose one with --image-topic".

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "cairn/bag/bag.hpp"

namespace cairn::bag {

/// What a command looks for: the types it accepts (normalised, "sensor_msgs/LaserScan"), what it
/// calls the topic in messages ("laser scan"), and the flag that names it ("--scan-topic").
struct TopicWanted {
  std::vector<std::string> types;
  std::string what;
  std::string flag;
};

/// The topic named `requested`, or, when `requested` is empty, the only topic of a wanted type.
/// Throws io::ParseError when the named topic does not exist or has another type, when there is
/// none of the type, or several.
std::size_t choose_topic(const Bag& bag, const std::string& requested, const TopicWanted& wanted);

/// As choose_topic(), but "no topic of the type" is not an error (an optional input such as
/// odometry): returns nothing then. `requested` == "none" also returns nothing.
std::optional<std::size_t> choose_optional_topic(const Bag& bag, const std::string& requested, const TopicWanted& wanted);

/// The topics whose normalised type is one of `types`.
std::vector<std::size_t> topics_of_type(const Bag& bag, const std::vector<std::string>& types);

}  // namespace cairn::bag
