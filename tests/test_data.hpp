#pragma once
/// \file
/// Where tests find the shared benchmark data: $CAIRN_DATA_ROOT, else ../shared/data beside the
/// clone. CAIRN_REQUIRE_DATA(path) skips the test, naming what is missing, when it is absent.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace cairn::test {

inline std::filesystem::path data_root() {
  if (const char* env = std::getenv("CAIRN_DATA_ROOT"); env != nullptr && *env != '\0') return env;
  return CAIRN_DEFAULT_DATA_ROOT;
}

inline std::filesystem::path data_path(const std::string& relative) { return data_root() / relative; }

}  // namespace cairn::test

/// Skips the current test when `relative` (under the data root) does not exist.
#define CAIRN_REQUIRE_DATA(relative)                                                          \
  do {                                                                                        \
    if (!std::filesystem::exists(::cairn::test::data_path(relative))) {                      \
      GTEST_SKIP() << "benchmark data not found: " << ::cairn::test::data_path(relative)     \
                   << " (set CAIRN_DATA_ROOT to the folder holding posegraph/, trajectories/)"; \
    }                                                                                         \
  } while (false)
