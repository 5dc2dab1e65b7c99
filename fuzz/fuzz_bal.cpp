// libFuzzer entry point for the BAL bundle-adjustment reader (plain text; gzip and bzip2 by
// magic bytes go through read_bal, plain bytes through parse_bal). Any input must end in a
// problem or a cairn::io::ParseError. The corpus in fuzz/corpus/bal runs in `make test`.

#include <cstddef>
#include <cstdint>
#include <string>

#include "cairn/io/bal.hpp"
#include "cairn/io/parse_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto problem = cairn::io::parse_bal("fuzz.txt", std::string(reinterpret_cast<const char*>(data), size));
    (void)problem;
  } catch (const cairn::io::ParseError&) {
    // Expected for malformed input.
  }
  return 0;
}
