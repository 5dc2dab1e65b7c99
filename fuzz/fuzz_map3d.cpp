// libFuzzer entry point for the saved 3D LiDAR map reader (lidar3d/map_file.hpp, docs/formats.md
// "cairn 3D LiDAR map"), modelled on fuzz_saved_map.cpp (the 2D map). Any input must end in a map
// or a cairn::io::ParseError naming the byte offset and the field: another exception (bad_alloc
// from a count nobody checked), a crash, a hang or a sanitizer report is a bug. A map it accepts
// encodes again to bytes that decode to the same map. Each input is tried as a whole file and,
// wrapped in a valid container (io::encode_container, so the fuzzer's bytes reach the payload's
// decoder instead of stopping at the checksum), as a payload. Run with `make fuzz` (clang); the
// corpus in fuzz/corpus/map3d runs in `make test`.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cairn/io/map_container.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/lidar3d/map_file.hpp"

namespace {

void decode_and_check(const std::string& bytes) {
  try {
    const cairn::lidar3d::SavedMap3D map = cairn::lidar3d::decode_saved_map(bytes, "fuzz.c3dm");
    // Exceptions from here on are bugs: what was accepted must be written and read back.
    const std::string again = cairn::lidar3d::encode_saved_map(map);
    if (cairn::lidar3d::encode_saved_map(cairn::lidar3d::decode_saved_map(again, "again.c3dm")) != again) {
      std::fprintf(stderr, "fuzz_map3d: an accepted map does not survive writing and reading back\n");
      std::abort();
    }
  } catch (const cairn::io::ParseError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cairn::io::ContainerKind kind =
      cairn::io::known_container_kind("CAIRN3DM", cairn::lidar3d::kMap3dFileVersion);
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  decode_and_check(bytes);                                     // as a file
  decode_and_check(cairn::io::encode_container(kind, bytes));  // as a payload
  return 0;
}
