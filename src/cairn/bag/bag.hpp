#pragma once
/// \file
/// A bag as the user hands it to cairn: a ROS 1 `.bag`, a single `.mcap` or `.db3`, or a rosbag2
/// folder (metadata.yaml and its storage files, several files read as one). Topics are merged
/// across files; messages stream in log-time order across all of them (a k-way merge of the
/// files' own time-ordered streams), one chunk per file in memory.
///
/// Which reader: a folder is rosbag2 (its metadata.yaml names the files and the storage); a file
/// is recognised by its first bytes ("#ROSBAG V", MCAP's magic, "SQLite format 3"), not its name.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "cairn/bag/container.hpp"

namespace cairn::bag {

/// One topic of the bag, across its files.
struct Topic {
  std::string name;
  std::string type;      ///< as the bag spells it
  std::string encoding;  ///< "ros1", "cdr", ...
  std::uint64_t messages = 0;
  std::int64_t first_ns = 0;
  std::int64_t last_ns = 0;
  /// (file index, connection index in that file) of every connection carrying this topic.
  std::vector<std::pair<std::size_t, std::size_t>> connections;
};

/// One message of a merged stream. `message.data` is valid until the next call of next().
struct BagMessage {
  std::size_t topic = 0;  ///< index into Bag::topics()
  std::size_t file = 0;   ///< index into Bag::files()
  Message message;
};

class BagStream {
 public:
  virtual ~BagStream() = default;
  virtual bool next(BagMessage* message) = 0;
};

/// True when `path` is for Bag::open(): a rosbag2 folder, a file named .bag, .mcap or .db3 (so a
/// damaged one gets the bag reader's error), or a file whose first bytes are a ROS 1 bag's, an
/// MCAP file's or an SQLite database's.
bool is_bag(const std::string& path);

class Bag {
 public:
  /// Opens a bag file or rosbag2 folder. Throws io::ParseError.
  static Bag open(const std::string& path);

  const std::string& path() const { return path_; }
  /// "ROS 1 bag 2.0", "MCAP", "rosbag2 SQLite3", "rosbag2 (MCAP)", ...
  const std::string& format() const { return format_; }
  const std::vector<std::unique_ptr<Container>>& files() const { return files_; }
  const std::vector<Topic>& topics() const { return topics_; }
  /// The connection a message came from.
  const Connection& connection(const BagMessage& message) const;

  /// Index of the topic named `name`, or throws io::ParseError listing the topics there are.
  std::size_t topic_index(const std::string& name) const;
  /// Messages of the given topics (indices into topics(); empty: all) in log-time order.
  std::unique_ptr<BagStream> read(const std::vector<std::size_t>& topics = {});

 private:
  void add_file(std::unique_ptr<Container> file);

  std::string path_;
  std::string format_;
  std::vector<std::unique_ptr<Container>> files_;
  std::vector<Topic> topics_;
};

}  // namespace cairn::bag
