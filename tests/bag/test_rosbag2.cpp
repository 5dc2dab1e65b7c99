// rosbag2's own bags (../shared/data/bags/rosbag2, written by rosbag2 with its SQLite3 and MCAP
// storage plugins): containers, metadata and CDR decoding checked against what the files say
// about themselves: metadata.yaml's counts and times, the default values written in the schemas,
// and the same messages decoded from both storages.

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cairn/bag/bag.hpp"
#include "cairn/bag/bag_info.hpp"
#include "cairn/bag/message_decoder.hpp"
#include "cairn/io/parse_error.hpp"
#include "test_data.hpp"

namespace cairn::bag {
namespace {

std::vector<Value> decode_topic(Bag& bag, const std::string& topic) {
  MessageDecoder decoder(bag);
  std::vector<Value> out;
  const auto stream = bag.read({bag.topic_index(topic)});
  BagMessage message;
  while (stream->next(&message)) out.push_back(decoder.decode(message));
  return out;
}

bool same_value(const Value& a, const Value& b) {
  if (a.kind() != b.kind()) return false;
  switch (a.kind()) {
    case Value::Kind::kBool: return a.as_bool() == b.as_bool();
    case Value::Kind::kInt: return a.as_int() == b.as_int();
    case Value::Kind::kUInt: return a.as_uint() == b.as_uint();
    case Value::Kind::kFloat: return a.number() == b.number() || (std::isnan(a.number()) && std::isnan(b.number()));
    case Value::Kind::kString:
    case Value::Kind::kBytes: return a.text() == b.text();
    case Value::Kind::kArray:
    case Value::Kind::kMessage:
      if (a.items().size() != b.items().size()) return false;
      for (std::size_t i = 0; i < a.items().size(); ++i) {
        if (!same_value(a.items()[i], b.items()[i])) return false;
      }
      return true;
  }
  return false;
}

/// "message_count: N" and "nanoseconds_since_epoch: N" of a metadata.yaml, read with a regex (not
/// with cairn's reader).
std::vector<long long> yaml_numbers(const std::string& path, const std::string& key) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  std::vector<long long> out;
  const std::regex pattern(key + ":\\s*(\\d+)");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), pattern); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stoll((*it)[1].str()));
  }
  return out;
}

class Rosbag2Fixtures : public ::testing::TestWithParam<const char*> {};

TEST_P(Rosbag2Fixtures, CountsAndTimesMatchMetadataYaml) {
  const std::string relative = std::string("bags/rosbag2/") + GetParam();
  CAIRN_REQUIRE_DATA(relative);
  const std::string folder = test::data_path(relative).string();
  const Bag bag = Bag::open(folder);
  const nlohmann::json info = bag_info_json(bag);
  const auto counts = yaml_numbers(folder + "/metadata.yaml", "message_count");
  ASSERT_FALSE(counts.empty());
  EXPECT_EQ(info["messages"].get<long long>(), counts.front());  // the bag's total comes first
  const auto starts = yaml_numbers(folder + "/metadata.yaml", "nanoseconds_since_epoch");
  ASSERT_FALSE(starts.empty());
  EXPECT_EQ(info["start_ns"].get<long long>(), starts.front());
  const auto durations = yaml_numbers(folder + "/metadata.yaml", "nanoseconds");
  ASSERT_FALSE(durations.empty());
  EXPECT_EQ(info["end_ns"].get<long long>() - info["start_ns"].get<long long>(), durations.front());

  // Every message streams out, in time order.
  Bag readable = Bag::open(folder);
  const auto stream = readable.read();
  BagMessage message;
  long long streamed = 0;
  std::int64_t last = std::numeric_limits<std::int64_t>::min();
  while (stream->next(&message)) {
    EXPECT_GE(message.message.log_time_ns, last);
    last = message.message.log_time_ns;
    ++streamed;
  }
  EXPECT_EQ(streamed, counts.front());
}

INSTANTIATE_TEST_SUITE_P(Bags, Rosbag2Fixtures,
                         ::testing::Values("sqlite3_cdr_test", "mcap_cdr_test", "sqlite3_talker", "mcap_talker",
                                           "mcap_convert_b"));

/// The default values the Arrays schema writes after its *_default fields ("int64[3] x [0, 9..7, -9..8]").
std::map<std::string, std::vector<std::string>> schema_defaults(const std::string& definition) {
  std::map<std::string, std::vector<std::string>> out;
  const std::regex line("^\\w+\\[3\\] (\\w+_default) \\[(.*)\\]$");
  std::istringstream in(definition);
  std::string text;
  while (std::getline(in, text)) {
    std::smatch m;
    if (!std::regex_match(text, m, line)) continue;
    std::vector<std::string> items;
    std::istringstream list(m[2].str());
    std::string item;
    while (std::getline(list, item, ',')) {
      item.erase(0, item.find_first_not_of(' '));
      if (item.size() >= 2 && item.front() == '"') item = item.substr(1, item.size() - 2);
      items.push_back(item);
    }
    out[m[1].str()] = items;
  }
  return out;
}

std::string as_schema_text(const Value& v) {
  switch (v.kind()) {
    case Value::Kind::kBool: return v.as_bool() ? "true" : "false";
    case Value::Kind::kInt: return std::to_string(v.as_int());
    case Value::Kind::kUInt: return std::to_string(v.as_uint());
    case Value::Kind::kString: return std::string(v.text());
    default: {
      std::ostringstream o;
      o << v.number();
      return o.str();
    }
  }
}

TEST(Rosbag2Cdr, ArraysDecodeToTheDefaultsTheirSchemaDeclares) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/mcap_cdr_test");
  Bag bag = Bag::open(test::data_path("bags/rosbag2/mcap_cdr_test").string());
  const std::size_t topic = bag.topic_index("/array_topic");
  const Connection& connection = bag.files()[0]->connections()[bag.topics()[topic].connections[0].second];
  const auto defaults = schema_defaults(connection.definition);
  ASSERT_EQ(defaults.size(), 14u);  // bool byte char float32 float64 int8..uint64 string
  const std::vector<Value> messages = decode_topic(bag, "/array_topic");
  ASSERT_EQ(messages.size(), 4u);
  for (const Value& message : messages) {
    for (const auto& [field, expected] : defaults) {
      const Value& value = message[field];
      std::vector<std::string> found;
      if (value.kind() == Value::Kind::kBytes) {
        for (const double d : value.numbers()) found.push_back(std::to_string(static_cast<int>(d)));
      } else {
        for (const Value& item : value.items()) found.push_back(as_schema_text(item));
      }
      ASSERT_EQ(found.size(), 3u) << field;
      for (std::size_t i = 0; i < 3; ++i) {
        if (value.kind() == Value::Kind::kArray && value.items()[i].kind() == Value::Kind::kFloat) {
          EXPECT_DOUBLE_EQ(value.items()[i].number(), std::stod(expected[i])) << field;
        } else {
          EXPECT_EQ(found[i], expected[i]) << field << "[" << i << "]";
        }
      }
    }
    // Defaults' own default values ("int32 int32_value -30000"), and the alignment check after arrays.
    for (const Value& d : message["defaults_values"].items()) {
      EXPECT_TRUE(d["bool_value"].as_bool());
      EXPECT_EQ(d["byte_value"].as_uint(), 50u);
      EXPECT_EQ(d["int32_value"].as_int(), -30000);
      EXPECT_EQ(d["uint64_value"].as_uint(), 50000000u);
      EXPECT_EQ(d["float64_value"].number(), 1.125);
    }
    EXPECT_EQ(message["constants_values"].items().size(), 3u);
  }
}

TEST(Rosbag2Cdr, SqliteAndMcapCopiesDecodeToTheSameMessages) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/mcap_cdr_test");
  CAIRN_REQUIRE_DATA("bags/rosbag2/sqlite3_cdr_test");
  Bag mcap = Bag::open(test::data_path("bags/rosbag2/mcap_cdr_test").string());
  Bag sqlite = Bag::open(test::data_path("bags/rosbag2/sqlite3_cdr_test/cdr_test_0.db3").string());
  for (const char* topic : {"/test_topic", "/array_topic"}) {
    const std::vector<Value> a = decode_topic(mcap, topic);
    const std::vector<Value> b = decode_topic(sqlite, topic);
    ASSERT_EQ(a.size(), b.size()) << topic;
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(same_value(a[i], b[i])) << topic << " message " << i;
  }
  // rosbag2 writes the sqlite3 bag's BasicTypes with only int32_value set (0x7B in its bytes).
  EXPECT_EQ(decode_topic(sqlite, "/test_topic").front()["int32_value"].as_int(), 123);
}

TEST(Rosbag2Cdr, TalkerStringsDecode) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/sqlite3_talker");
  Bag bag = Bag::open(test::data_path("bags/rosbag2/sqlite3_talker").string());
  const std::vector<Value> messages = decode_topic(bag, "/topic");
  ASSERT_FALSE(messages.empty());
  for (const Value& m : messages) EXPECT_TRUE(m["data"].text().starts_with("Hello, world!")) << m["data"].text();
}

TEST(Bag, UnknownTopicListsTheTopicsThereAre) {
  CAIRN_REQUIRE_DATA("bags/rosbag2/sqlite3_talker");
  const Bag bag = Bag::open(test::data_path("bags/rosbag2/sqlite3_talker").string());
  try {
    (void)bag.topic_index("/scan");
    FAIL();
  } catch (const io::ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("/topic (std_msgs/msg/String)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace cairn::bag
