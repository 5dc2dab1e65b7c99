// libFuzzer entry point for the MCAP reader (bag/mcap_reader.hpp: opened from the summary
// section, or scanned record by record when there is none or the file is cut off; plain, zstd and
// lz4 chunks; CRCs) and for what cairn does with a bag's messages. The input is written to a file
// named *.mcap and opened with bag::Bag::open; every topic is listed, every message streamed and
// decoded with the schema the file carries (bag::MessageDecoder: ros1msg, ros2msg; ROS 1 and CDR
// payloads), and the types cairn knows go through their typed decoders (bag/sensor_messages.hpp,
// bag/point_cloud2.hpp).
// What every input must do: fuzz/bag_fuzz.hpp. The corpus in fuzz/corpus/mcap runs in `make test`.

#include <cstddef>
#include <cstdint>

#include "bag_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return cairn::bag::fuzz::fuzz_bag_input(data, size, "fuzz_mcap", ".mcap");
}
