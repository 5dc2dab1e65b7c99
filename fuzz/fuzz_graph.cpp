// libFuzzer entry point for the pose-graph readers (g2o and TORO). Any input must end in a parsed
// graph or a cairn::io::ParseError: another exception, a crash, a hang or a sanitizer report is a
// bug. Run with `make fuzz` (clang); the corpus in fuzz/corpus/graph runs in `make test`.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

#include "cairn/io/graph_io.hpp"
#include "cairn/io/graph_statistics.hpp"
#include "cairn/io/parse_error.hpp"

namespace {

std::string scratch_path(const char* extension) {
  return (std::filesystem::temp_directory_path() /
          ("cairn_fuzz_graph_" + std::to_string(::getpid()) + extension))
      .string();
}

void read_as(const std::string& path, cairn::io::GraphFormat format, cairn::io::ToroInformationOrder order) {
  cairn::io::GraphReadOptions options;
  options.format = format;
  options.toro_information_order = order;
  try {
    const cairn::io::GraphFile file = cairn::io::read_graph(path, options);
    (void)cairn::io::compute_statistics(file.graph);
  } catch (const cairn::io::ParseError&) {
    // Expected for malformed input.
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = scratch_path(".txt");
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  read_as(path, cairn::io::GraphFormat::kG2o, cairn::io::ToroInformationOrder::kAuto);
  read_as(path, cairn::io::GraphFormat::kToro, cairn::io::ToroInformationOrder::kAuto);
  read_as(path, cairn::io::GraphFormat::kToro, cairn::io::ToroInformationOrder::kG2o);
  return 0;
}
