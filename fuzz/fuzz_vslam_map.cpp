// libFuzzer entry point for the saved visual map reader (vslam/map_file.hpp, docs/formats.md
// "cairn visual map"), modelled on fuzz_map3d.cpp (the 3D LiDAR map). Any input must end in a map
// or a cairn::io::ParseError naming the byte offset and the field: another exception (bad_alloc
// from a count nobody checked), a crash, a hang or a sanitizer report is a bug. A map it accepts
// encodes again to bytes that decode to the same map. Each input is tried as a whole file and,
// wrapped in a valid container (io::encode_container, so the fuzzer's bytes reach the payload's
// decoder instead of stopping at the checksum), as a payload. Run with `make fuzz` (clang); the
// corpus in fuzz/corpus/vslam_map runs in `make test`.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cairn/io/map_container.hpp"
#include "cairn/io/parse_error.hpp"
#include "cairn/vslam/map_file.hpp"

namespace {

void decode_and_check(const std::string& bytes) {
  try {
    const cairn::vslam::SavedVisualMap map = cairn::vslam::decode_saved_map(bytes, "fuzz.cvsm");
    // Exceptions from here on are bugs: what was accepted must be written and read back.
    const std::string again = cairn::vslam::encode_saved_map(map);
    if (cairn::vslam::encode_saved_map(cairn::vslam::decode_saved_map(again, "again.cvsm")) != again) {
      std::fprintf(stderr, "fuzz_vslam_map: an accepted map does not survive writing and reading back\n");
      std::abort();
    }
  } catch (const cairn::io::ParseError&) {
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const cairn::io::ContainerKind kind =
      cairn::io::known_container_kind("CAIRNVSM", cairn::vslam::kVisualMapFileVersion);
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  decode_and_check(bytes);                                     // as a file
  decode_and_check(cairn::io::encode_container(kind, bytes));  // as a payload
  return 0;
}
