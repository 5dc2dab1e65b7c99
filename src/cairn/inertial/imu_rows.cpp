#include "cairn/inertial/imu_rows.hpp"

#include <system_error>

#include "cairn/io/input_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::inertial {
namespace {

bool in_range(core::Timestamp stamp) {
  return stamp.nanoseconds() >= -kMaxAbsImuStampNs && stamp.nanoseconds() <= kMaxAbsImuStampNs;
}

}  // namespace

core::Timestamp parse_stamp_ns(const io::TextReader& reader, std::string_view token, std::string_view what) {
  const auto stamp = core::Timestamp::parse_nanoseconds(token);
  if (!stamp || !in_range(*stamp)) {
    reader.fail("expected an integer number of nanoseconds within +-9.2e18 for " + std::string(what) + ", found " +
                io::quote_token(token));
  }
  return *stamp;
}

core::Timestamp parse_stamp_s(const io::TextReader& reader, std::string_view token, std::string_view what) {
  const auto stamp = core::Timestamp::parse_seconds(token);
  if (!stamp || !in_range(*stamp)) {
    reader.fail("expected a number of seconds within +-9.2e9 for " + std::string(what) + ", found " +
                io::quote_token(token));
  }
  return *stamp;
}

void IncreasingStampCheck::check(const io::TextReader& reader, core::Timestamp stamp) {
  if (previous_ && stamp <= *previous_) {
    const bool duplicate = stamp == *previous_;
    reader.fail(std::string(duplicate ? "duplicated stamp: " : "stamp out of order: ") + "expected a stamp after " +
                previous_->to_seconds_string() + " s (line " + std::to_string(previous_line_) + "), found " +
                stamp.to_seconds_string() + " s" + (duplicate ? " again" : ""));
  }
  previous_ = stamp;
  previous_line_ = reader.line_number();
}

std::string resolve_dataset_file(const std::filesystem::path& path, std::initializer_list<const char*> candidates,
                                 const std::string& what) {
  std::error_code error;
  if (candidates.size() > 0 && std::filesystem::is_directory(path, error)) {
    std::string tried;
    for (const char* candidate : candidates) {
      const std::filesystem::path file = path / candidate;
      if (std::filesystem::exists(file, error)) {
        io::check_input_file(file.string(), what);
        return file.string();
      }
      tried += std::string(tried.empty() ? "" : " or ") + candidate;
    }
    throw io::ParseError(path.string(), 0, "is a directory without " + tried + ": expected " + what);
  }
  io::check_input_file(path.string(), what);
  return path.string();
}

}  // namespace cairn::inertial
