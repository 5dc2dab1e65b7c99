#pragma once
/// \file
/// What the IMU text readers (EuRoC imu0/data.csv, the plain IMU CSV, state ground truth) share:
/// strict stamp parsing, a check that time neither stands still nor runs backwards (naming both
/// lines), and finding a file inside a dataset folder. Every failure throws io::ParseError.

#include <cstddef>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

#include "cairn/core/time.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::inertial {

/// Largest |stamp| the IMU readers accept, ns: 9.2e9 s (the year 2261), the bound io's trajectory
/// formats keep, so that any stamp read can be written in seconds and read back.
inline constexpr std::int64_t kMaxAbsImuStampNs = 9'200'000'000'000'000'000;

/// Parses an integer count of nanoseconds (EuRoC), within +-kMaxAbsImuStampNs, or fails at the
/// reader's line naming `what` and the token.
core::Timestamp parse_stamp_ns(const io::TextReader& reader, std::string_view token, std::string_view what);
/// Parses decimal seconds ("1403715273.262142976", exact to the ns without exponent), within
/// +-9.2e9 s, or fails at the reader's line.
core::Timestamp parse_stamp_s(const io::TextReader& reader, std::string_view token, std::string_view what);

/// Refuses a stamp that does not follow the previous one (equal: "duplicated"; smaller: "out of
/// order"), naming both lines and both stamps.
class IncreasingStampCheck {
 public:
  void check(const io::TextReader& reader, core::Timestamp stamp);

 private:
  std::optional<core::Timestamp> previous_;
  std::size_t previous_line_ = 0;
};

/// `path` itself when it is not a directory; else the first of `candidates` (relative paths)
/// that exists inside it (no candidates: a directory is refused as io::check_input_file does). Throws ParseError(path, 0, ...) naming the candidates when none does,
/// and for a file that cannot be opened (io::check_input_file, `what` names the content).
std::string resolve_dataset_file(const std::filesystem::path& path, std::initializer_list<const char*> candidates,
                                 const std::string& what);

}  // namespace cairn::inertial
