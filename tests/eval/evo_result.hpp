#pragma once
/// \file
/// Reads evo's stored result archives (res_files/*.zip from `--save_results`) at test time, so
/// the expected numbers come from the files evo wrote, not from cairn: stats.json through
/// nlohmann::json and error_array.npz, which is a single .npy array despite its suffix (see
/// ../shared/data/trajectories/README.md). evo's archives store their members uncompressed
/// (method 0), so reading the local file headers is enough; anything else fails the test.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace cairn::test {

inline std::uint32_t little_endian(const std::string& bytes, std::size_t at, int size) {
  std::uint32_t v = 0;
  for (int k = size - 1; k >= 0; --k) {
    v = (v << 8) | static_cast<unsigned char>(bytes.at(at + static_cast<std::size_t>(k)));
  }
  return v;
}

/// The bytes of member `name` of a stored (uncompressed) zip archive; nullopt when absent.
inline std::optional<std::string> zip_member(const std::string& zip_path, const std::string& name) {
  std::ifstream in(zip_path, std::ios::binary);
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  std::size_t at = 0;
  // Local file header (PKWARE APPNOTE 4.3.7): signature, 26 bytes of fields, name, extra, data.
  while (at + 30 <= bytes.size() && little_endian(bytes, at, 4) == 0x04034b50u) {
    const std::uint32_t flags = little_endian(bytes, at + 6, 2);
    const std::uint32_t method = little_endian(bytes, at + 8, 2);
    const std::uint32_t size = little_endian(bytes, at + 18, 4);
    const std::uint32_t name_length = little_endian(bytes, at + 26, 2);
    const std::uint32_t extra_length = little_endian(bytes, at + 28, 2);
    const std::string member = bytes.substr(at + 30, name_length);
    const std::size_t data = at + 30 + name_length + extra_length;
    if (method != 0 || (flags & 8u) != 0) {
      ADD_FAILURE() << zip_path << ": member " << member << " is compressed or streamed; expected stored";
      return std::nullopt;
    }
    if (member == name) return bytes.substr(data, size);
    at = data + size;
  }
  return std::nullopt;
}

/// stats.json of an evo result archive.
inline nlohmann::json evo_stats(const std::string& zip_path) {
  const auto text = zip_member(zip_path, "stats.json");
  if (!text) {
    ADD_FAILURE() << zip_path << " has no stats.json";
    return {};
  }
  return nlohmann::json::parse(*text);
}

/// error_array.npz of an evo result archive: a .npy v1 array of little-endian float64.
inline std::vector<double> evo_error_array(const std::string& zip_path) {
  const auto npy = zip_member(zip_path, "error_array.npz");
  if (!npy || npy->size() < 10 || npy->compare(0, 6, "\x93NUMPY") != 0) {
    ADD_FAILURE() << zip_path << ": error_array.npz is not a .npy array";
    return {};
  }
  const std::size_t header_length = little_endian(*npy, 8, 2);
  const std::string header = npy->substr(10, header_length);
  if (header.find("'descr': '<f8'") == std::string::npos || header.find("'fortran_order': False") == std::string::npos) {
    ADD_FAILURE() << zip_path << ": expected a C-order <f8 array, header " << header;
    return {};
  }
  const std::size_t data = 10 + header_length;
  std::vector<double> values((npy->size() - data) / sizeof(double));
  std::memcpy(values.data(), npy->data() + data, values.size() * sizeof(double));
  return values;
}

}  // namespace cairn::test
