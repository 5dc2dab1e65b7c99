// libFuzzer entry point for the rosbag2 SQLite3 reader (bag/sqlite_bag.hpp: tables topics,
// messages and message_definitions read through libsqlite3) and for what cairn does with a bag's
// messages. The input is written to a file named *.db3 and opened with bag::Bag::open; every topic
// is listed, every message streamed and decoded with the definition the database carries
// (bag::MessageDecoder, CDR payloads), and the types cairn knows go through their typed decoders
// (bag/sensor_messages.hpp, bag/point_cloud2.hpp).
// What every input must do: fuzz/bag_fuzz.hpp. The corpus in fuzz/corpus/rosbag2_sqlite runs in `make test`.

#include <cstddef>
#include <cstdint>

#include "bag_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return cairn::bag::fuzz::fuzz_bag_input(data, size, "fuzz_rosbag2_sqlite", ".db3");
}
