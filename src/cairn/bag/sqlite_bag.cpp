#include "cairn/bag/sqlite_bag.hpp"

#include <sqlite3.h>

#include <cstring>
#include <filesystem>
#include <climits>
#include <cstdint>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "cairn/io/parse_error.hpp"

namespace cairn::bag {
namespace {

struct DatabaseCloser {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct StatementCloser {
  void operator()(sqlite3_stmt* statement) const { sqlite3_finalize(statement); }
};
using Database = std::unique_ptr<sqlite3, DatabaseCloser>;
using Statement = std::unique_ptr<sqlite3_stmt, StatementCloser>;

std::string column_text(sqlite3_stmt* statement, int column) {
  const unsigned char* text = sqlite3_column_text(statement, column);
  return text == nullptr ? std::string{} : std::string(reinterpret_cast<const char*>(text));
}

class SqliteStream final : public MessageStream {
 public:
  SqliteStream(Database database, Statement statement, std::map<std::int64_t, std::size_t> index_of_topic,
               std::vector<std::uint64_t> expected, std::string path)
      : database_(std::move(database)),
        statement_(std::move(statement)),
        index_of_topic_(std::move(index_of_topic)),
        expected_(std::move(expected)),
        streamed_(expected_.size(), 0),
        path_(std::move(path)) {}

  bool next(Message* message) override {
    const int status = sqlite3_step(statement_.get());
    if (status == SQLITE_DONE) {
      check_counts();
      return false;
    }
    if (status != SQLITE_ROW) {
      throw io::ParseError(path_, 0, std::string("reading the messages table: ") + sqlite3_errmsg(database_.get()));
    }
    const std::int64_t topic_id = sqlite3_column_int64(statement_.get(), 0);
    const auto it = index_of_topic_.find(topic_id);
    if (it == index_of_topic_.end()) {
      throw io::ParseError(path_, 0, "message row " + std::to_string(sqlite3_column_int64(statement_.get(), 3)) +
                                         " names topic_id " + std::to_string(topic_id) + ", which the topics table lacks");
    }
    message->connection = it->second;
    if (sqlite3_column_type(statement_.get(), 1) != SQLITE_INTEGER) {
      throw io::ParseError(path_, 0, "message row " + std::to_string(sqlite3_column_int64(statement_.get(), 3)) +
                                         ": the timestamp is not an integer (nanoseconds)");
    }
    message->log_time_ns = sqlite3_column_int64(statement_.get(), 1);
    if (message->log_time_ns < last_ns_) {
      throw io::ParseError(path_, 0, "message row " + std::to_string(sqlite3_column_int64(statement_.get(), 3)) +
                                         " comes out of timestamp order (a damaged timestamp index?)");
    }
    last_ns_ = message->log_time_ns;
    ++streamed_[it->second];
    const void* blob = sqlite3_column_blob(statement_.get(), 2);
    const int size = sqlite3_column_bytes(statement_.get(), 2);
    message->data = std::span<const std::uint8_t>(static_cast<const std::uint8_t*>(blob), static_cast<std::size_t>(size));
    message->file_offset = static_cast<std::uint64_t>(sqlite3_column_int64(statement_.get(), 3));  // the row id
    return true;
  }

 private:
  /// Every wanted topic streamed as many rows as the count at open (a damaged index drops rows).
  void check_counts() const {
    for (std::size_t i = 0; i < expected_.size(); ++i) {
      if (expected_[i] != kNotWanted && streamed_[i] != expected_[i]) {
        throw io::ParseError(path_, 0, "topic " + std::to_string(i) + " streamed " + std::to_string(streamed_[i]) +
                                           " messages, the messages table counts " + std::to_string(expected_[i]) +
                                           " (a damaged timestamp index?)");
      }
    }
  }

 public:
  static constexpr std::uint64_t kNotWanted = UINT64_MAX;

 private:
  Database database_;
  Statement statement_;
  std::map<std::int64_t, std::size_t> index_of_topic_;
  std::vector<std::uint64_t> expected_;  ///< per connection; kNotWanted when not streamed
  std::vector<std::uint64_t> streamed_;
  std::int64_t last_ns_ = INT64_MIN;
  std::string path_;
};

class SqliteBag final : public Container {
 public:
  explicit SqliteBag(std::string path) : path_(std::move(path)) {
    database_ = open_database();
    read_topics();
    read_definitions();
    count_messages();
  }

  const std::string& path() const override { return path_; }
  const std::vector<Connection>& connections() const override { return connections_; }
  const ContainerSummary& summary() const override { return summary_; }

  std::unique_ptr<MessageStream> messages(const std::vector<bool>& wanted) override {
    std::string sql = "SELECT topic_id, timestamp, data, id FROM messages";
    std::string ids;
    for (std::size_t i = 0; i < connections_.size(); ++i) {
      if (!wanted.empty() && (i >= wanted.size() || !wanted[i])) continue;
      ids += (ids.empty() ? "" : ",") + std::to_string(connections_[i].id);
    }
    if (!wanted.empty()) sql += " WHERE topic_id IN (" + ids + ")";
    sql += " ORDER BY timestamp, id";
    Database database = open_database();  // a stream reads on its own connection
    Statement statement = prepare(database.get(), sql);
    std::map<std::int64_t, std::size_t> index_of_topic;
    std::vector<std::uint64_t> expected(connections_.size(), SqliteStream::kNotWanted);
    for (std::size_t i = 0; i < connections_.size(); ++i) {
      index_of_topic[connections_[i].id] = i;
      if (wanted.empty() || (i < wanted.size() && wanted[i])) expected[i] = summary_.connections[i].messages;
    }
    return std::make_unique<SqliteStream>(std::move(database), std::move(statement), std::move(index_of_topic),
                                          std::move(expected), path_);
  }

 private:
  Database open_database() const {
    if (!std::filesystem::is_regular_file(path_)) throw io::ParseError(path_, 0, "cannot open: not a readable file");
    // immutable=1: no lock files and no journal beside a bag that may sit on read-only media.
    std::string uri = "file:";
    for (const char c : path_) {
      if (c == '%' || c == '?' || c == '#') {
        static constexpr char kHex[] = "0123456789ABCDEF";
        const auto byte = static_cast<unsigned char>(c);
        uri += {'%', kHex[byte >> 4], kHex[byte & 15]};
      } else {
        uri += c;
      }
    }
    uri += "?immutable=1";
    sqlite3* raw = nullptr;
    const int status = sqlite3_open_v2(uri.c_str(), &raw, SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
    Database database(raw);
    if (status != SQLITE_OK) {
      throw io::ParseError(path_, 0, std::string("cannot open as SQLite: ") + sqlite3_errmsg(raw));
    }
    return database;
  }

  Statement prepare(sqlite3* database, const std::string& sql) const {
    sqlite3_stmt* raw = nullptr;
    if (sqlite3_prepare_v2(database, sql.c_str(), -1, &raw, nullptr) != SQLITE_OK) {
      Statement closer(raw);
      throw io::ParseError(path_, 0, std::string("not a rosbag2 SQLite3 bag (") + sqlite3_errmsg(database) +
                                         ", running: " + sql + ")");
    }
    return Statement(raw);
  }

  bool has_table(const char* name) const {
    Statement statement = prepare(database_.get(), "SELECT 1 FROM sqlite_master WHERE type='table' AND name=?");
    sqlite3_bind_text(statement.get(), 1, name, -1, SQLITE_STATIC);
    return sqlite3_step(statement.get()) == SQLITE_ROW;
  }

  void read_topics() {
    summary_.format = "rosbag2 SQLite3";
    summary_.indexed = true;  // counts come from SQL over the messages table
    summary_.file_bytes = std::filesystem::file_size(path_);
    Statement statement = prepare(database_.get(), "SELECT id, name, type, serialization_format FROM topics ORDER BY id");
    int status = SQLITE_ROW;
    std::set<std::int64_t> ids;
    while ((status = sqlite3_step(statement.get())) == SQLITE_ROW) {
      const std::int64_t id = sqlite3_column_int64(statement.get(), 0);
      if (sqlite3_column_type(statement.get(), 0) != SQLITE_INTEGER || id < 0 || id > UINT32_MAX || !ids.insert(id).second) {
        throw io::ParseError(path_, 0, "topics table: id " + std::to_string(id) +
                                           " is not a unique integer id (rosbag2 numbers its topics 1, 2, ...)");
      }
      Connection connection;
      connection.id = static_cast<std::uint32_t>(id);
      connection.topic = column_text(statement.get(), 1);
      connection.type = column_text(statement.get(), 2);
      connection.encoding = column_text(statement.get(), 3);
      connections_.push_back(std::move(connection));
    }
    if (status != SQLITE_DONE) {
      throw io::ParseError(path_, 0, std::string("reading the topics table: ") + sqlite3_errmsg(database_.get()));
    }
  }

  void read_definitions() {
    if (!has_table("message_definitions")) {
      summary_.notes.push_back("no message_definitions table (a bag from before ROS 2 Iron): the bag carries no "
                               "message layouts");
      return;
    }
    Statement statement = prepare(
        database_.get(), "SELECT topic_type, encoding, encoded_message_definition FROM message_definitions");
    while (sqlite3_step(statement.get()) == SQLITE_ROW) {
      const std::string type = column_text(statement.get(), 0);
      for (Connection& connection : connections_) {
        if (connection.type != type) continue;
        connection.definition_encoding = column_text(statement.get(), 1);
        connection.definition = column_text(statement.get(), 2);
      }
    }
  }

  void count_messages() {
    summary_.connections.assign(connections_.size(), {});
    Statement statement = prepare(
        database_.get(),
        "SELECT topic_id, COUNT(*), MIN(timestamp), MAX(timestamp) FROM messages GROUP BY topic_id");
    while (sqlite3_step(statement.get()) == SQLITE_ROW) {
      const std::int64_t topic_id = sqlite3_column_int64(statement.get(), 0);
      for (std::size_t i = 0; i < connections_.size(); ++i) {
        if (connections_[i].id != topic_id) continue;
        summary_.connections[i].messages = static_cast<std::uint64_t>(sqlite3_column_int64(statement.get(), 1));
        summary_.connections[i].first_ns = sqlite3_column_int64(statement.get(), 2);
        summary_.connections[i].last_ns = sqlite3_column_int64(statement.get(), 3);
      }
    }
  }

  std::string path_;
  Database database_;
  std::vector<Connection> connections_;
  ContainerSummary summary_;
};

}  // namespace

std::unique_ptr<Container> open_sqlite_bag(const std::string& path) { return std::make_unique<SqliteBag>(path); }

bool looks_like_sqlite(std::span<const std::uint8_t> first_bytes) {
  static constexpr char kMagic[] = "SQLite format 3";  // 16 bytes with the NUL
  return first_bytes.size() >= sizeof(kMagic) && std::memcmp(first_bytes.data(), kMagic, sizeof(kMagic)) == 0;
}

}  // namespace cairn::bag
