#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/io/csv.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::vector<TextRow> read_all(const std::filesystem::path& path, Separator separator) {
  auto reader = TableReader::open(path, separator);
  EXPECT_TRUE(reader.ok()) << reader.status();
  std::vector<TextRow> rows;
  if (!reader.ok()) return rows;
  TextRow row;
  while (reader->next(row)) rows.push_back(row);
  EXPECT_TRUE(reader->status().ok()) << reader->status();
  return rows;
}

TEST(Csv, SplitsAndTrimsCommaFields) {
  EXPECT_THAT(split_fields("1, 2,3 ", Separator::kComma), ElementsAre("1", "2", "3"));
  EXPECT_THAT(split_fields("a,,b", Separator::kComma), ElementsAre("a", "", "b"));
  EXPECT_THAT(split_fields("a,b,", Separator::kComma), ElementsAre("a", "b", ""));
  EXPECT_THAT(split_fields("\t x \t", Separator::kComma), ElementsAre("x"));
}

TEST(Csv, SplitsOnRunsOfBlanks) {
  EXPECT_THAT(split_fields("  1 2\t\t3   4 ", Separator::kWhitespace), ElementsAre("1", "2", "3", "4"));
  EXPECT_TRUE(split_fields("   ", Separator::kWhitespace).empty());
}

TEST(Csv, SkipsCommentsBlanksAndCrlfAndCountsLinesLikeAnEditor) {
  test::TempDir dir;
  const auto path = dir.write("t.csv",
                              "\xEF\xBB\xBF#timestamp [ns],a,b\r\n"
                              "\r\n"
                              "1, 2,3 \r\n"
                              "   # indented comment\r\n"
                              "\t\r\n"
                              "4,5, 6\r\n");
  const std::vector<TextRow> rows = read_all(path, Separator::kComma);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[0].line, 3);
  EXPECT_THAT(rows[0].fields, ElementsAre("1", "2", "3"));
  EXPECT_FALSE(rows[0].unterminated);
  EXPECT_EQ(rows[1].line, 6);
  EXPECT_THAT(rows[1].fields, ElementsAre("4", "5", "6"));
  EXPECT_FALSE(rows[1].unterminated);
}

TEST(Csv, MarksLastLineWithoutNewline) {
  test::TempDir dir;
  const auto path = dir.write("t.csv", "1,2\n3,4");
  const std::vector<TextRow> rows = read_all(path, Separator::kComma);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_FALSE(rows[0].unterminated);
  EXPECT_TRUE(rows[1].unterminated);
  EXPECT_EQ(rows[1].line, 2);
}

TEST(Csv, TruncatedLastLineIsDataLossNamingFileAndLine) {
  test::TempDir dir;
  const auto path = dir.write("imu.csv", "#t,a,b\n1,2,3\n4,5");
  auto reader = TableReader::open(path, Separator::kComma);
  ASSERT_TRUE(reader.ok());
  TextRow row;
  ASSERT_TRUE(reader->next(row));
  EXPECT_TRUE(reader->check_field_count(row, 3, "t,a,b").ok());
  ASSERT_TRUE(reader->next(row));
  const Status s = reader->check_field_count(row, 3, "t,a,b");
  EXPECT_EQ(s.code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(std::string(s.message()),
              HasSubstr(path.string() + ":3: expected 3 comma-separated fields (t,a,b), found 2"));
  EXPECT_THAT(std::string(s.message()), HasSubstr("does not end in a newline"));
  EXPECT_FALSE(reader->next(row));
}

TEST(Csv, ShortLineInTheMiddleIsInvalidArgument) {
  test::TempDir dir;
  const auto path = dir.write("x.txt", "1 2 3\n4 5\n6 7 8\n");
  auto reader = TableReader::open(path, Separator::kWhitespace);
  ASSERT_TRUE(reader.ok());
  TextRow row;
  ASSERT_TRUE(reader->next(row));
  ASSERT_TRUE(reader->next(row));
  const Status s = reader->check_field_count(row, 3, "a b c");
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(
      std::string(s.message()),
      path.string() + ":2: expected 3 blank-separated fields (a b c), found 2; fix or delete this line");
}

TEST(Csv, FieldParsersNameFileLineFieldAndText) {
  test::TempDir dir;
  const auto path = dir.write("d.csv", "#h\n1403715273262142976, 1.5, abc, 12.25\n");
  auto reader = TableReader::open(path, Separator::kComma);
  ASSERT_TRUE(reader.ok());
  TextRow row;
  ASSERT_TRUE(reader->next(row));
  EXPECT_EQ(*reader->parse_ns(row, 0, "t"), std::int64_t{1403715273262142976});
  EXPECT_EQ(*reader->parse_double(row, 1, "x"), 1.5);
  EXPECT_EQ(*reader->parse_seconds(row, 3, "s"), std::int64_t{12'250'000'000});
  const auto bad = reader->parse_double(row, 2, "w_RS_S_y");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(std::string(bad.status().message()),
            path.string() + ":2: field 3 ('w_RS_S_y'): 'abc' is not a number; fix or delete this line");
  const auto bad_ns = reader->parse_ns(row, 1, "#timestamp [ns]");
  ASSERT_FALSE(bad_ns.ok());
  EXPECT_THAT(std::string(bad_ns.status().message()),
              HasSubstr(path.string() + ":2: field 2 ('#timestamp [ns]'): '1.5' is not a number"));
  const auto missing = reader->parse_double(row, 7, "z");
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(std::string(missing.status().message()), HasSubstr(":2: field 8 ('z') is missing"));
}

TEST(Csv, ParsesOnlyWholeFiniteNumbers) {
  double v = 0.0;
  EXPECT_TRUE(parse_finite_double("+1.5", v));
  EXPECT_EQ(v, 1.5);
  EXPECT_TRUE(parse_finite_double("-2e-3", v));
  EXPECT_EQ(v, -2e-3);
  EXPECT_TRUE(parse_finite_double("1.76187114e-05", v));
  EXPECT_EQ(v, 1.76187114e-05);
  for (const char* bad : {"", "+", "+-1", "nan", "inf", "-inf", "1.0x", " 1", "1 ", "1,5", "0x10", "1e400"}) {
    EXPECT_FALSE(parse_finite_double(bad, v)) << "accepted '" << bad << "'";
  }
}

TEST(Csv, OpenNamesMissingFileAndRejectsFolders) {
  test::TempDir dir;
  const auto missing = TableReader::open(dir / "nope.csv", Separator::kComma);
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(missing.status().message()), HasSubstr((dir / "nope.csv").string()));
  const auto folder = TableReader::open(dir.path(), Separator::kComma);
  ASSERT_FALSE(folder.ok());
  EXPECT_THAT(std::string(folder.status().message()), HasSubstr("is a folder"));
}

}  // namespace
}  // namespace mrvs::io
