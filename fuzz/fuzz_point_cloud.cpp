// libFuzzer entry point for the point-cloud readers (PCD ascii/binary/binary_compressed, PLY;
// gzip, bzip2 and xz by magic bytes). The input is written to a file named *.pcd and read with
// read_point_cloud, so the whole path runs, decompression included. Any input must end in a
// cloud or a cairn::io::ParseError. The corpus in fuzz/corpus/point_cloud runs in `make test`.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/point_cloud.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("cairn_fuzz_point_cloud_" + std::to_string(::getpid()) + ".pcd"))
          .string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    cairn::io::PointCloudReadReport report;
    const auto cloud = cairn::io::read_point_cloud(path, &report);
    (void)cloud;
  } catch (const cairn::io::ParseError&) {
    // Expected for malformed input.
  }
  return 0;
}
