#pragma once
/// \file
/// Bounds-checked little-endian reads from a byte span, for the binary container formats (ROS 1
/// bags, MCAP). Every read past the end throws io::ParseError naming the file and the absolute
/// byte offset of the field that did not fit, so a truncated or corrupt record is reported where
/// it is, never read out of bounds.

#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {

class ByteCursor {
 public:
  /// `bytes` starts at absolute offset `base` of `file` (used only in messages).
  ByteCursor(std::span<const std::uint8_t> bytes, std::string_view file, std::uint64_t base = 0)
      : bytes_(bytes), file_(file), base_(base) {}

  std::size_t position() const { return position_; }
  std::size_t remaining() const { return bytes_.size() - position_; }
  bool at_end() const { return position_ == bytes_.size(); }
  /// Absolute file offset of the next byte.
  std::uint64_t offset() const { return base_ + position_; }

  std::uint8_t u8(const char* what) { return read<std::uint8_t>(what); }
  std::uint16_t u16(const char* what) { return read<std::uint16_t>(what); }
  std::uint32_t u32(const char* what) { return read<std::uint32_t>(what); }
  std::uint64_t u64(const char* what) { return read<std::uint64_t>(what); }
  std::int32_t i32(const char* what) { return read<std::int32_t>(what); }

  /// The next `n` bytes as a view.
  std::span<const std::uint8_t> bytes(std::uint64_t n, const char* what) {
    require(n, what);
    auto view = bytes_.subspan(position_, static_cast<std::size_t>(n));
    position_ += static_cast<std::size_t>(n);
    return view;
  }
  std::string_view string(std::uint64_t n, const char* what) {
    auto view = bytes(n, what);
    return {reinterpret_cast<const char*>(view.data()), view.size()};
  }
  void skip(std::uint64_t n, const char* what) { (void)bytes(n, what); }

  /// Throws the cursor's error at the current offset.
  [[noreturn]] void fail(const std::string& detail) const { fail_at(offset(), detail); }
  [[noreturn]] void fail_at(std::uint64_t absolute_offset, const std::string& detail) const {
    throw io::ParseError(std::string(file_), 0, "byte " + std::to_string(absolute_offset) + ": " + detail);
  }

 private:
  void require(std::uint64_t n, const char* what) const {
    if (n > remaining()) {
      fail(std::string(what) + " needs " + std::to_string(n) + " bytes, only " + std::to_string(remaining()) +
           " left");
    }
  }
  template <typename T>
  T read(const char* what) {
    require(sizeof(T), what);
    T value;
    std::memcpy(&value, bytes_.data() + position_, sizeof(T));  // little-endian hosts only (x86-64, arm64)
    position_ += sizeof(T);
    return value;
  }

  std::span<const std::uint8_t> bytes_;
  std::string_view file_;
  std::uint64_t base_;
  std::size_t position_ = 0;
};

}  // namespace cairn::bag
