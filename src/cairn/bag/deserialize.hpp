#pragma once
/// \file
/// Decodes serialised message bytes into a Value tree, laid out by a SchemaSet:
///   * ROS 1 serialisation (wiki.ros.org/msg "Serialization"): little endian, packed (no
///     alignment), string = uint32 length + bytes, sequence = uint32 count + elements, fixed
///     arrays without a count, time and duration as two 32-bit integers.
///   * CDR as ROS 2 writes it (OMG CDR / XCDR1, DDS-XTypes 1.3 section 7.4.1; rmw_fastrtps): a
///     4-byte encapsulation header (00 00 big endian, 00 01 little endian; parameter-list and XCDR2
///     kinds are refused), then every primitive aligned to its own size (8 at most) relative to
///     the end of that header, strings as uint32 length including the terminating NUL, sequences
///     as uint32 count. A message with no fields is serialised as one uint8 (rosidl's
///     "structure_needs_at_least_one_member").
/// A length or count larger than the bytes left, a string without its NUL, trailing bytes in a
/// ROS 1 message: io::ParseError naming `where` and the byte offset inside the message.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "cairn/bag/message_schema.hpp"
#include "cairn/bag/value.hpp"

namespace cairn::bag {

enum class Serialization : std::uint8_t { kRos1, kCdr };

/// Decodes `bytes` as the root type of `schemas`. `where` names the message in errors
/// ("bag.bag: /scan message at byte 4211").
/// `owner`, when set, keeps `bytes` alive: uint8 arrays (an image's, a cloud's data) then refer to
/// them instead of being copied.
Value deserialize(const SchemaSet& schemas, std::span<const std::uint8_t> bytes, Serialization serialization,
                  const std::string& where, std::shared_ptr<const void> owner = nullptr);

}  // namespace cairn::bag
