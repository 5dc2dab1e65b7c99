#pragma once
/// \file
/// The constants of the MCAP format (https://mcap.dev/spec, major version 0) that its reader and
/// its writer share: record opcodes ("Records"), the magic ("Magic") and the CRC-32 of data,
/// summary and chunk records.

#include <array>
#include <cstdint>
#include <span>

namespace cairn::bag::mcap {

// "Records": opcodes 0x01-0x0F are the spec's; 0x00 is invalid; a reader skips any other.
namespace op {
constexpr std::uint8_t kHeader = 0x01;
constexpr std::uint8_t kFooter = 0x02;
constexpr std::uint8_t kSchema = 0x03;
constexpr std::uint8_t kChannel = 0x04;
constexpr std::uint8_t kMessage = 0x05;
constexpr std::uint8_t kChunk = 0x06;
constexpr std::uint8_t kMessageIndex = 0x07;
constexpr std::uint8_t kChunkIndex = 0x08;
constexpr std::uint8_t kAttachment = 0x09;
constexpr std::uint8_t kAttachmentIndex = 0x0A;
constexpr std::uint8_t kStatistics = 0x0B;
constexpr std::uint8_t kMetadata = 0x0C;
constexpr std::uint8_t kMetadataIndex = 0x0D;
constexpr std::uint8_t kSummaryOffset = 0x0E;
constexpr std::uint8_t kDataEnd = 0x0F;
}  // namespace op

// "Magic": 0x89 M C A P <major version '0'> \r \n, at the start and at the end of the file.
constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

/// CRC-32 as MCAP's CRC fields use it (zlib's crc32, continuing from `crc`), over spans of any length.
std::uint32_t crc32_of(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

}  // namespace cairn::bag::mcap
