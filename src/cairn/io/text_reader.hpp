#pragma once
/// \file
/// Line-oriented reading of text formats with the checks every parser needs: the file opens,
/// is text (no NUL or control bytes, not gzip), no line is absurdly long, and every number is a
/// finite number. Every failure throws ParseError naming file, line and what was expected.

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace cairn::io {

/// Longest line any cairn text format accepts (bytes). Real files stay far below: a g2o
/// EDGE_SE3:QUAT line with 30 numbers at full precision is under 1 KiB.
inline constexpr std::size_t kMaxLineBytes = 1 << 20;

class TextReader {
 public:
  /// Opens `path` ("-" = standard input, read whole once and named "standard input" in errors);
  /// throws ParseError(path, 0, ...) when it cannot be opened or is compressed.
  explicit TextReader(std::string path);
  /// Reads `contents` (for example a decompressed file) as if it were the file `path`.
  TextReader(std::string path, std::string contents);

  /// Advances to the next line; false at the end of the file. The line has its '\n' and any
  /// trailing '\r' removed. Throws on binary bytes or an over-long line.
  bool next_line();
  std::string_view line() const { return line_; }
  /// 1-based number of the current line.
  std::size_t line_number() const { return line_number_; }
  const std::string& path() const { return path_; }

  /// Throws ParseError at the current line.
  [[noreturn]] void fail(const std::string& detail) const;

  /// True once the last line of the file was read and it had no '\n': a file cut short (a copy
  /// that stopped, a disk that filled) ends so, and its last number may be incomplete, yet
  /// parses. Hand-written files end so too, so readers warn rather than refuse:
  /// unterminated_last_line_warning().
  bool last_line_unterminated() const { return unterminated_; }
  /// "line N, the last, does not end with a newline: ..." when last_line_unterminated(), else "".
  std::string unterminated_last_line_warning() const;

 private:
  std::string path_;
  std::unique_ptr<std::istream> stream_;
  std::istream* in_ = nullptr;
  std::string line_;
  std::size_t line_number_ = 0;
  bool unterminated_ = false;
};

/// Whitespace-separated tokens of a text held in memory, for formats whose line breaks carry no
/// meaning (BAL, the data of ASCII PLY), with the 1-based line of each token for errors.
class TextTokens {
 public:
  /// Starts at byte `position` of `text`, which is on line `line`. `text` must outlive this.
  explicit TextTokens(const std::string& text, std::size_t position = 0, std::size_t line = 1)
      : text_(text), position_(position), line_(line), token_line_(line) {}
  /// The next token (spaces, tabs, '\r' and '\n' separate); empty at the end of the text.
  std::string_view next();
  /// Line of the last non-empty token read.
  std::size_t line() const { return token_line_; }
  /// Line of the current position (past the last token and the white space after it).
  std::size_t position_line() const { return line_; }

 private:
  const std::string& text_;
  std::size_t position_;
  std::size_t line_;
  std::size_t token_line_;
};

/// Splits on spaces and tabs; empty tokens are dropped.
std::vector<std::string_view> split_whitespace(std::string_view line);
/// Splits on `separator`, trimming spaces and tabs around each field; keeps empty fields.
std::vector<std::string_view> split_fields(std::string_view line, char separator);
/// True for a line that is empty or only blanks, or whose first non-blank character is '#'.
bool is_blank_or_comment(std::string_view line);

/// Parses a finite double; on failure throws at the reader's line:
/// "expected a finite number for <what>, found '<token>'".
double parse_double(const TextReader& reader, std::string_view token, std::string_view what);
/// Parses a non-negative integer id; throws "expected a non-negative integer for <what>, ...".
std::int64_t parse_id(const TextReader& reader, std::string_view token, std::string_view what);

/// Shortens a token for an error message (long binary garbage stays readable).
std::string quote_token(std::string_view token);

}  // namespace cairn::io
