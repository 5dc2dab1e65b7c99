#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cairn/io/parse_error.hpp"
#include "cairn/io/text_reader.hpp"

namespace cairn::io {
namespace {

std::string write_temp(const std::string& name, const std::string& content) {
  const auto path = std::filesystem::temp_directory_path() / ("cairn_test_" + name);
  std::ofstream(path, std::ios::binary) << content;
  return path.string();
}

TEST(TextReader, ReadsLinesAndStripsCarriageReturns) {
  TextReader reader(write_temp("crlf.txt", "a b\r\n\nc"));
  ASSERT_TRUE(reader.next_line());
  EXPECT_EQ(reader.line(), "a b");
  ASSERT_TRUE(reader.next_line());
  EXPECT_EQ(reader.line(), "");
  ASSERT_TRUE(reader.next_line());
  EXPECT_EQ(reader.line(), "c");
  EXPECT_EQ(reader.line_number(), 3u);
  EXPECT_FALSE(reader.next_line());
}

TEST(TextReader, RejectsBinaryWithLineAndColumn) {
  const std::string path = write_temp("bin.txt", std::string("ok\nab\0c\n", 8));
  TextReader reader(path);
  ASSERT_TRUE(reader.next_line());
  try {
    reader.next_line();
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2u);
    EXPECT_EQ(e.file(), path);
    EXPECT_NE(e.detail().find("byte 0x00 at column 3"), std::string::npos) << e.what();
  }
}

TEST(TextReader, RejectsGzipAndMissingFiles) {
  EXPECT_THROW(TextReader(write_temp("gz.txt", "\x1f\x8b\x08rest")), ParseError);
  EXPECT_THROW(TextReader("/nonexistent/cairn/file.g2o"), ParseError);
}

TEST(TextReader, RejectsOverlongLine) {
  TextReader reader(write_temp("long.txt", std::string(kMaxLineBytes + 10, 'x')));
  EXPECT_THROW(reader.next_line(), ParseError);
}

TEST(TextReader, ParsesNumbersOrNamesTheProblem) {
  TextReader reader(write_temp("num.txt", "x\n"));
  ASSERT_TRUE(reader.next_line());
  EXPECT_EQ(parse_double(reader, "-1.5e3", "x"), -1500.0);
  EXPECT_EQ(parse_double(reader, "+2", "x"), 2.0);
  EXPECT_EQ(parse_id(reader, "42", "id"), 42);
  for (const char* bad : {"nan", "inf", "-inf", "1e999", "abc", "", "1.0x"}) {
    EXPECT_THROW(parse_double(reader, bad, "dx"), ParseError) << bad;
  }
  try {
    parse_double(reader, "nan", "dx");
  } catch (const ParseError& e) {
    EXPECT_STREQ(e.what(), (reader.path() + ":1: expected a finite number for dx, found 'nan'").c_str());
  }
  for (const char* bad : {"-1", "1.5", "", "x"}) EXPECT_THROW(parse_id(reader, bad, "id"), ParseError);
}

TEST(TextReader, SplitsFields) {
  const auto t = split_whitespace("  a\tbb  c ");
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[1], "bb");
  const auto f = split_fields("1, 2,,3", ',');
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[1], "2");
  EXPECT_EQ(f[2], "");
  EXPECT_TRUE(is_blank_or_comment("   # x"));
  EXPECT_FALSE(is_blank_or_comment(" 1 # x"));
}

}  // namespace
}  // namespace cairn::io
