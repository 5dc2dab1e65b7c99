// libFuzzer entry point for the saved 2D map reader of `cairn localize2d --map`
// (slam2d/map_file.hpp, docs/formats.md "cairn 2D map"). Any input must end in a map or a
// cairn::io::ParseError naming the byte offset and the field: another exception (bad_alloc
// from a count nobody checked), a crash, a hang or a sanitizer report is a bug. A map it accepts
// encodes again to bytes that decode to the same map. Each input is tried as a whole file and,
// wrapped in a valid container, as a payload. Run with `make fuzz` (clang); the corpus in
// fuzz/corpus/saved_map runs in `make test`.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <zlib.h>

#include "cairn/io/parse_error.hpp"
#include "cairn/slam2d/map_file.hpp"

namespace {

void put_u32(std::string& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int k = 0; k < 8; ++k) out.push_back(static_cast<char>((v >> (8 * k)) & 0xFFu));
}

// `payload` in a valid container (docs/formats.md: magic, version 1, flags 0, sizes, deflated
// payload, CRC-32), so the fuzzer's bytes reach the payload's decoder instead of stopping at
// the checksum.
std::string wrapped(const std::string& payload) {
  uLongf packed_size = compressBound(static_cast<uLong>(payload.size()));
  std::string packed(packed_size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(packed.data()), &packed_size, reinterpret_cast<const Bytef*>(payload.data()),
                static_cast<uLong>(payload.size()), 1) != Z_OK) {
    std::abort();
  }
  packed.resize(packed_size);
  std::string out = "CAIRNMAP";
  put_u32(out, 1);
  put_u32(out, 0);
  put_u64(out, 32 + packed.size() + 4);
  put_u64(out, payload.size());
  out += packed;
  put_u32(out, static_cast<std::uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(out.data()), static_cast<uInt>(out.size()))));
  return out;
}

void decode_and_check(const std::string& bytes) {
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
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  decode_and_check(bytes);           // as a file
  decode_and_check(wrapped(bytes));  // as a payload
  return 0;
}
