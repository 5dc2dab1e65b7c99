// libFuzzer entry point for the ROS 1 bag reader (bag/ros1_bag.hpp, format 2.0: opened from its
// index, or scanned when it has none; plain, bz2 and lz4 chunks) and for what cairn does with a
// bag's messages. The input is written to a file named *.bag and opened with bag::Bag::open; every
// topic is listed, every message streamed and decoded with the layout the bag carries
// (bag::MessageDecoder), and the types cairn knows go through their typed decoders
// (bag/sensor_messages.hpp, bag/point_cloud2.hpp).
// Any input must end in an io::ParseError (the container, a message's bytes) or, from a typed
// decoder, a std::runtime_error: another exception, a crash, a hang or a sanitizer report is a
// bug. A stream that ends normally must have handed out its messages in log-time order, as many
// per topic as the bag said it holds; decoded values kept while the stream goes on must not change
// (their byte arrays may refer to a chunk: Message::owner). The corpus in fuzz/corpus/ros1_bag runs
// in `make test`.

#include <cstddef>
#include <cstdint>

#include "bag_fuzz.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  return cairn::bag::fuzz::fuzz_bag_input(data, size, "fuzz_ros1_bag", ".bag");
}
