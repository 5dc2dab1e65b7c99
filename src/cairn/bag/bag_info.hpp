#pragma once
/// \file
/// What a bag holds, as `rosbag info` and `ros2 bag info` tell it: its files and their formats,
/// compression by chunk, whether counts came from an index, the time span, and per topic the
/// type, serialisation, message count, mean rate and whether cairn can decode it (and if not,
/// why). As JSON, for `cairn info BAG --json` and for tests.

#include <nlohmann/json.hpp>

#include "cairn/bag/bag.hpp"

namespace cairn::bag {

/// Facts of an open bag. Keys: path, format, files[{path, format, profile, bytes, chunks{compression:
/// count}, indexed, notes[]}], messages, start_ns, end_ns, duration_s, topics[{name, type, encoding,
/// messages, first_ns, last_ns, rate_hz, decodable, why_not}].
nlohmann::json bag_info_json(const Bag& bag);

}  // namespace cairn::bag
