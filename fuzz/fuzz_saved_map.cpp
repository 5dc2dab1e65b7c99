// libFuzzer entry point for the saved 2D map reader of `cairn localize2d --map`
// (slam2d/map_file.hpp, docs/formats.md "cairn 2D map"). Any input must end in a map or a
// cairn::io::ParseError naming the byte offset and the field: another exception (bad_alloc
// from a count nobody checked), a crash, a hang or a sanitizer report is a bug. A map it accepts
// encodes again to bytes that decode to the same map. Run with `make fuzz` (clang); the corpus in
// fuzz/corpus/saved_map runs in `make test`.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/map_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  try {
    const cairn::slam2d::SavedMap2D map = cairn::slam2d::decode_saved_map(bytes, "fuzz.cmap");
    // Exceptions from here on are bugs: what was accepted must be written and read back.
    const std::string again = cairn::slam2d::encode_saved_map(map);
    if (cairn::slam2d::encode_saved_map(cairn::slam2d::decode_saved_map(again, "again.cmap")) != again) {
      std::fprintf(stderr, "fuzz_saved_map: an accepted map does not survive writing and reading back\n");
      std::abort();
    }
  } catch (const cairn::io::ParseError&) {
  }
  return 0;
}
