#include "cairn/bag/bag.hpp"

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <utility>

#include "cairn/bag/mcap_reader.hpp"
#include "cairn/bag/ros1_bag.hpp"
#include "cairn/bag/rosbag2_metadata.hpp"
#include "cairn/bag/sqlite_bag.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

std::vector<std::uint8_t> first_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw io::ParseError(path, 0, "cannot open");
  std::vector<std::uint8_t> bytes(16);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  bytes.resize(static_cast<std::size_t>(in.gcount()));
  return bytes;
}

std::unique_ptr<Container> open_file(const std::string& path) {
  const std::vector<std::uint8_t> head = first_bytes(path);
  if (looks_like_ros1_bag(head)) return open_ros1_bag(path);
  if (looks_like_mcap(head)) return open_mcap(path);
  if (looks_like_sqlite(head)) return open_sqlite_bag(path);
  if (head.empty()) throw io::ParseError(path, 0, "empty file: expected a ROS 1 bag, an MCAP file or a rosbag2 .db3");
  throw io::ParseError(path, 0,
                       "not a bag: expected a ROS 1 bag (\"#ROSBAG V2.0\"), an MCAP file or a rosbag2 SQLite3 "
                       "database by its first bytes");
}

/// Merges the files' time-ordered streams: keeps one pending message per file and hands out the
/// earliest, refilling from that file only when the caller asks for the next one (so the data
/// handed out stays valid until then).
class MergedStream final : public BagStream {
 public:
  struct Source {
    std::unique_ptr<MessageStream> stream;
    std::size_t file = 0;
    std::vector<std::size_t> topic_of_connection;
    BagMessage pending;
    bool has_pending = false;
  };

  explicit MergedStream(std::vector<Source> sources) : sources_(std::move(sources)) {
    for (Source& source : sources_) refill(&source);
  }

  bool next(BagMessage* out) override {
    if (last_ != nullptr) refill(last_);
    last_ = nullptr;
    for (Source& source : sources_) {
      if (!source.has_pending) continue;
      if (last_ == nullptr || source.pending.message.log_time_ns < last_->pending.message.log_time_ns) last_ = &source;
    }
    if (last_ == nullptr) return false;
    *out = last_->pending;
    return true;
  }

 private:
  static void refill(Source* source) {
    source->has_pending = source->stream->next(&source->pending.message);
    if (!source->has_pending) return;
    source->pending.file = source->file;
    source->pending.topic = source->topic_of_connection[source->pending.message.connection];
  }

  std::vector<Source> sources_;
  Source* last_ = nullptr;
};

}  // namespace

bool is_bag(const std::string& path) {
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    return std::filesystem::exists(std::filesystem::path(path) / "metadata.yaml", error);
  }
  if (!std::filesystem::is_regular_file(path, error)) return false;
  // By name too, so that an empty or damaged .bag/.mcap/.db3 gets the bag reader's error.
  const std::string extension = std::filesystem::path(path).extension().string();
  if (extension == ".bag" || extension == ".mcap" || extension == ".db3") return true;
  try {
    const std::vector<std::uint8_t> head = first_bytes(path);
    return looks_like_ros1_bag(head) || looks_like_mcap(head) || looks_like_sqlite(head);
  } catch (const io::ParseError&) {
    return false;
  }
}

Bag Bag::open(const std::string& path) {
  Bag bag;
  bag.path_ = path;
  std::error_code error;
  if (std::filesystem::is_directory(path, error)) {
    const Rosbag2Metadata metadata = read_rosbag2_metadata(path);
    for (const std::string& file : metadata.files) bag.add_file(open_file(file));
    bag.format_ = "rosbag2 (" + bag.files_.front()->summary().format + ")";
  } else {
    bag.add_file(open_file(path));
    bag.format_ = bag.files_.front()->summary().format;
  }
  return bag;
}

void Bag::add_file(std::unique_ptr<Container> file) {
  const std::size_t file_index = files_.size();
  const ContainerSummary& summary = file->summary();
  for (std::size_t c = 0; c < file->connections().size(); ++c) {
    const Connection& connection = file->connections()[c];
    auto it = std::find_if(topics_.begin(), topics_.end(), [&](const Topic& topic) {
      return topic.name == connection.topic && topic.type == connection.type;
    });
    if (it == topics_.end()) {
      topics_.push_back(Topic{connection.topic, connection.type, connection.encoding, 0, 0, 0, {}});
      it = std::prev(topics_.end());
    }
    const ConnectionStatistics& statistics = summary.connections.at(c);
    if (statistics.messages > 0) {
      it->first_ns = it->messages == 0 ? statistics.first_ns : std::min(it->first_ns, statistics.first_ns);
      it->last_ns = it->messages == 0 ? statistics.last_ns : std::max(it->last_ns, statistics.last_ns);
    }
    it->messages += statistics.messages;
    it->connections.emplace_back(file_index, c);
  }
  files_.push_back(std::move(file));
}

const Connection& Bag::connection(const BagMessage& message) const {
  return files_.at(message.file)->connections().at(message.message.connection);
}

std::size_t Bag::topic_index(const std::string& name) const {
  for (std::size_t i = 0; i < topics_.size(); ++i) {
    if (topics_[i].name == name) return i;
  }
  std::string list;
  for (const Topic& topic : topics_) list += "\n  " + topic.name + " (" + topic.type + ")";
  throw io::ParseError(path_, 0, "no topic '" + name + "'; the bag has:" + (list.empty() ? " no topics" : list));
}

std::unique_ptr<BagStream> Bag::read(const std::vector<std::size_t>& topics) {
  std::vector<MergedStream::Source> sources;
  for (std::size_t f = 0; f < files_.size(); ++f) {
    const std::size_t connection_count = files_[f]->connections().size();
    MergedStream::Source source;
    source.file = f;
    source.topic_of_connection.assign(connection_count, 0);
    std::vector<bool> wanted(connection_count, false);
    for (std::size_t t = 0; t < topics_.size(); ++t) {
      const bool selected = topics.empty() || std::find(topics.begin(), topics.end(), t) != topics.end();
      for (const auto& [file, c] : topics_[t].connections) {
        if (file != f) continue;
        source.topic_of_connection[c] = t;
        wanted[c] = selected;
      }
    }
    if (std::find(wanted.begin(), wanted.end(), true) == wanted.end()) continue;
    source.stream = files_[f]->messages(wanted);
    sources.push_back(std::move(source));
  }
  return std::make_unique<MergedStream>(std::move(sources));
}

}  // namespace cairn::bag
