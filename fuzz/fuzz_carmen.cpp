// libFuzzer entry point for the CARMEN log reader (plain text; gzip and bzip2 by magic bytes).
// Any input must end in a log or a cairn::io::ParseError. The corpus in fuzz/corpus/carmen runs
// in `make test`.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "cairn/io/carmen_log.hpp"
#include "cairn/io/parse_error.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path =
      (std::filesystem::temp_directory_path() / ("cairn_fuzz_carmen_" + std::to_string(::getpid()) + ".clf")).string();
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    cairn::io::CarmenReadReport report;
    const auto log = cairn::io::read_carmen_log(path, &report);
    (void)log;
  } catch (const cairn::io::ParseError&) {
    // Expected for malformed input.
  }
  return 0;
}
