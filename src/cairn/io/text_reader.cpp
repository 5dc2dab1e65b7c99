#include "cairn/io/text_reader.hpp"

#include <charconv>
#include <cmath>
#include <cstring>

#include "cairn/io/input_file.hpp"
#include "cairn/io/output_file.hpp"
#include "cairn/io/parse_error.hpp"

namespace cairn::io {

TextReader::TextReader(std::string path, std::string contents)
    : path_(std::move(path)), stream_(std::make_unique<std::istringstream>(std::move(contents))), in_(stream_.get()) {}

TextReader::TextReader(std::string path) : path_(std::move(path)) {
  if (path_ == "-") {  // standard input, read whole once (io/output_file.hpp)
    path_ = "standard input";
    stream_ = std::make_unique<std::istringstream>(standard_input());
  } else {
    check_input_file(path_);
    auto file = std::make_unique<std::ifstream>(path_, std::ios::binary);
    if (!*file) throw ParseError(path_, 0, std::string("cannot open file: ") + std::strerror(errno));
    stream_ = std::move(file);
  }
  in_ = stream_.get();
  char magic[3] = {0, 0, 0};
  in_->read(magic, 3);
  const auto got = in_->gcount();
  const auto b0 = static_cast<unsigned char>(magic[0]);
  const auto b1 = static_cast<unsigned char>(magic[1]);
  if (got >= 2 && b0 == 0x1f && b1 == 0x8b) {
    throw ParseError(path_, 0, "file is gzip-compressed: expected plain text (decompress it first)");
  }
  if (got >= 3 && std::memcmp(magic, "BZh", 3) == 0) {
    throw ParseError(path_, 0, "file is bzip2-compressed: expected plain text (decompress it first)");
  }
  in_->clear();
  in_->seekg(0);
}

std::string TextReader::unterminated_last_line_warning() const {
  if (!unterminated_) return {};
  return path_ + ":" + std::to_string(line_number_) +
         ": the last line does not end with a newline: if the file was cut short, its last record may be incomplete "
         "(a number cut in the middle still parses)";
}

bool TextReader::next_line() {
  line_.clear();
  if (!in_->good()) return false;
  // Read by chunks so a file without newlines cannot make us allocate without bound.
  bool read_any = false;
  bool terminated = false;
  char c = 0;
  while (in_->get(c)) {
    read_any = true;
    if (c == '\n') {
      terminated = true;
      break;
    }
    line_.push_back(c);
    if (line_.size() > kMaxLineBytes) {
      ++line_number_;
      fail("line is longer than " + std::to_string(kMaxLineBytes) +
           " bytes: expected a text record (is this a binary file?)");
    }
  }
  if (!read_any) return false;
  ++line_number_;
  unterminated_ = !terminated;
  if (!line_.empty() && line_.back() == '\r') line_.pop_back();
  for (std::size_t i = 0; i < line_.size(); ++i) {
    const auto byte = static_cast<unsigned char>(line_[i]);
    if ((byte < 0x20 && byte != '\t' && byte != '\f' && byte != '\v') || byte == 0x7f) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02x", byte);
      fail(std::string("binary data (byte ") + hex + " at column " + std::to_string(i + 1) +
           "): expected text");
    }
  }
  return true;
}

void TextReader::fail(const std::string& detail) const { throw ParseError(path_, line_number_, detail); }

namespace {
bool is_blank(char c) { return c == ' ' || c == '\t' || c == '\f' || c == '\v'; }
}  // namespace

std::vector<std::string_view> split_whitespace(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > start) tokens.push_back(line.substr(start, i - start));
  }
  return tokens;
}

std::vector<std::string_view> split_fields(std::string_view line, char separator) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = line.find(separator, start);
    std::string_view field = line.substr(start, end == std::string_view::npos ? line.npos : end - start);
    while (!field.empty() && is_blank(field.front())) field.remove_prefix(1);
    while (!field.empty() && is_blank(field.back())) field.remove_suffix(1);
    fields.push_back(field);
    if (end == std::string_view::npos) break;
    start = end + 1;
  }
  return fields;
}

bool is_blank_or_comment(std::string_view line) {
  for (char c : line) {
    if (is_blank(c)) continue;
    return c == '#';
  }
  return true;
}

std::string quote_token(std::string_view token) {
  constexpr std::size_t kMax = 40;
  std::string out = "'";
  out += token.size() > kMax ? std::string(token.substr(0, kMax)) + "..." : std::string(token);
  out += "'";
  return out;
}

std::string_view TextTokens::next() {
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (c == '\n') {
      ++line_;
    } else if (c != ' ' && c != '\t' && c != '\r') {
      break;
    }
    ++position_;
  }
  const std::size_t begin = position_;
  while (position_ < text_.size()) {
    const char c = text_[position_];
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') break;
    ++position_;
  }
  if (position_ > begin) token_line_ = line_;
  return std::string_view(text_).substr(begin, position_ - begin);
}

double parse_double(const TextReader& reader, std::string_view token, std::string_view what) {
  double value = 0.0;
  const char* begin = token.data();
  const char* end = token.data() + token.size();
  if (!token.empty() && *begin == '+') ++begin;  // from_chars rejects a leading '+'
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (token.empty() || ec != std::errc() || ptr != end || !std::isfinite(value)) {
    reader.fail("expected a finite number for " + std::string(what) + ", found " + quote_token(token));
  }
  return value;
}

std::int64_t parse_id(const TextReader& reader, std::string_view token, std::string_view what) {
  std::int64_t value = 0;
  const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || ptr != token.data() + token.size() || value < 0) {
    reader.fail("expected a non-negative integer for " + std::string(what) + ", found " +
                quote_token(token));
  }
  return value;
}

}  // namespace cairn::io
