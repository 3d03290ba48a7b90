#include <cstdint>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "mrvs/core/time.h"

namespace mrvs {
namespace {

TEST(Time, ParsesEurocStampExactly) {
  // 19 significant digits: a double would lose the last ones.
  auto t = parse_decimal_seconds("1403715273.262142976");
  ASSERT_TRUE(t.ok()) << t.status();
  EXPECT_EQ(*t, std::int64_t{1403715273262142976});
}

TEST(Time, ParsesShortAndSignedForms) {
  EXPECT_EQ(*parse_decimal_seconds("12"), 12 * kNanosecondsPerSecond);
  EXPECT_EQ(*parse_decimal_seconds("0.5"), 500'000'000);
  EXPECT_EQ(*parse_decimal_seconds(".25"), 250'000'000);
  EXPECT_EQ(*parse_decimal_seconds("3."), 3 * kNanosecondsPerSecond);
  EXPECT_EQ(*parse_decimal_seconds("-1.5"), -1'500'000'000);
  EXPECT_EQ(*parse_decimal_seconds("+2.000000001"), 2'000'000'001);
}

TEST(Time, RoundsBeyondNanoseconds) {
  EXPECT_EQ(*parse_decimal_seconds("1.0000000004"), 1'000'000'000);
  EXPECT_EQ(*parse_decimal_seconds("1.0000000005"), 1'000'000'001);
  EXPECT_EQ(*parse_decimal_seconds("-1.0000000006"), -1'000'000'001);
}

TEST(Time, RejectsMalformedText) {
  for (const char* bad : {"", "-", ".", "1e9", "1.2.3", "abc", "1 ", " 1", "12x", "1,5"}) {
    auto t = parse_decimal_seconds(bad);
    EXPECT_FALSE(t.ok()) << "accepted '" << bad << "'";
    if (!t.ok()) {
      EXPECT_NE(t.status().message().find("seconds"), std::string::npos) << t.status();
    }
  }
}

TEST(Time, RejectsOverflow) {
  EXPECT_FALSE(parse_decimal_seconds("9223372037").ok());  // > INT64_MAX ns
  EXPECT_TRUE(parse_decimal_seconds("9223372036.854775807").ok());
  EXPECT_FALSE(parse_decimal_seconds("9223372036.854775808").ok());
  EXPECT_FALSE(parse_nanoseconds("9223372036854775808").ok());
  EXPECT_EQ(*parse_nanoseconds("9223372036854775807"), std::numeric_limits<std::int64_t>::max());
}

TEST(Time, ParsesNanoseconds) {
  EXPECT_EQ(*parse_nanoseconds("1403715273262142976"), std::int64_t{1403715273262142976});
  EXPECT_EQ(*parse_nanoseconds("-42"), -42);
  for (const char* bad : {"", "-", "1.5", "12a", " 3"}) {
    EXPECT_FALSE(parse_nanoseconds(bad).ok()) << "accepted '" << bad << "'";
  }
}

TEST(Time, FormatIsInverseOfParse) {
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::int64_t> dist(-(std::int64_t{1} << 62), std::int64_t{1} << 62);
  for (int i = 0; i < 10000; ++i) {
    const std::int64_t t = dist(rng);
    const std::string text = format_seconds(t);
    auto back = parse_decimal_seconds(text);
    ASSERT_TRUE(back.ok()) << text;
    ASSERT_EQ(*back, t) << text;
  }
  EXPECT_EQ(format_seconds(1403715273262142976), "1403715273.262142976");
  EXPECT_EQ(format_seconds(-1), "-0.000000001");
  EXPECT_EQ(format_seconds(std::numeric_limits<std::int64_t>::min()), "-9223372036.854775808");
}

TEST(Time, SecondsConversions) {
  EXPECT_DOUBLE_EQ(to_seconds(1'500'000'000), 1.5);
  EXPECT_EQ(from_seconds(0.05), 50'000'000);
  EXPECT_EQ(from_seconds(-0.0000000016), -2);
}

}  // namespace
}  // namespace mrvs
