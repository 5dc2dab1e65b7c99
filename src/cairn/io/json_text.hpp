#pragma once
/// \file
/// The text of every JSON file cairn writes (reports, manifests, `--json`): indented by two,
/// ending in a newline. A string that is not valid UTF-8 -- a file name made of Latin-1 bytes is
/// the usual one -- is never fatal: each invalid byte is written as U+FFFD, the replacement
/// character (nlohmann's default throws type_error 316 after the whole run's work).

#include <nlohmann/json.hpp>
#include <string>

namespace cairn::io {

inline std::string json_text(const nlohmann::json& j) {
  return j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

}  // namespace cairn::io
