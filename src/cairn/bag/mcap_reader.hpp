#pragma once
/// \file
/// Reads MCAP files (https://mcap.dev/spec, major version 0) as a bag::Container: the files
/// rosbag2 writes with its mcap storage plugin, Foxglove and the MCAP CLI write, and McapWriter.
///
/// Two ways in, one result:
/// * A file with a usable summary section (Footer.summary_start != 0, a Statistics record,
///   one Chunk Index record per chunk, each with its Message Index offsets) is opened from the
///   summary alone: channels with their schemas, per-channel counts from
///   Statistics.channel_message_counts, per-channel first/last log times from the Message Index
///   records of the few chunks that can hold them. ContainerSummary::indexed is true.
/// * Any other file (no summary, a summary without Statistics or Message Indexes, messages
///   outside chunks, a file cut off before its footer) is scanned record by record once at open;
///   counts and times come from that scan, indexed is false and a note says why. A file cut off
///   in the middle of a record keeps every whole record before the cut ("file ends inside a
///   record at byte N" in the notes).
///
/// Either way messages stream in log-time order (ties in file order): the chunks (and runs of
/// messages written outside chunks) are taken in order of their first log time, and only the
/// ones overlapping the time being emitted are held decompressed, pending messages in a
/// priority queue. A file without a summary is therefore not streamed in file order: the scan at
/// open records each chunk's time range, so the same merge applies.
///
/// Supported chunk compression: "" (none), "zstd", "lz4" (LZ4 frame format). Anything else is
/// an io::ParseError naming it. CRCs are checked when non-zero: Chunk uncompressed_crc whenever
/// a chunk is decompressed, Footer summary_crc when the summary is used, Data End
/// data_section_crc and Attachment crc on a scan. A compressed chunk larger than 1 GiB
/// uncompressed is refused. When a stream ends, each wanted connection must have produced the
/// count the file was opened with (a damaged chunk without a CRC otherwise loses messages
/// silently); a mismatch throws io::ParseError from MessageStream::next().
///
/// Connection fields: id = channel id, topic, type = schema name, encoding = the channel's
/// message_encoding ("cdr", "ros1", "json", ...), definition = schema data as text,
/// definition_encoding = schema encoding ("ros2msg", "ros2idl", "ros1msg", "jsonschema", ...).
/// A channel with schema id 0 has no schema: type, definition and definition_encoding are empty.
/// Connections are listed in channel id order. Attachments and Metadata records are checked and
/// counted in the notes, not exposed.

#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "cairn/bag/container.hpp"

namespace cairn::bag {

/// Opens an MCAP file. Throws io::ParseError(path, 0, "byte N: ...") for a file that is not
/// MCAP, is damaged, or uses a compression cairn does not read.
std::unique_ptr<Container> open_mcap(const std::string& path);

/// True when `first_bytes` starts with the MCAP magic 0x89 "MCAP" <version> "\r\n" (any major
/// version byte, so that open_mcap can name an unsupported version). Needs at least 8 bytes.
bool looks_like_mcap(std::span<const std::uint8_t> first_bytes);

}  // namespace cairn::bag
