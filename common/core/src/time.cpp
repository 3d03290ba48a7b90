#include "mrvs/core/time.h"

#include <cmath>
#include <limits>

#include <fmt/format.h>

namespace mrvs {
namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }

Status bad_number(std::string_view text, std::string_view why) {
  return absl::InvalidArgumentError(fmt::format("'{}' is not a valid {}", text, why));
}

// Accumulates value = value*10 + digit with an overflow check.
bool push_digit(std::int64_t& value, char digit) {
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  const int d = digit - '0';
  if (value > (kMax - d) / 10) return false;
  value = value * 10 + d;
  return true;
}

}  // namespace

DurationNs from_seconds(double s) { return static_cast<DurationNs>(std::llround(s * 1e9)); }

StatusOr<TimestampNs> parse_nanoseconds(std::string_view text) {
  if (text.empty()) return bad_number(text, "integer nanosecond timestamp (empty)");
  bool negative = false;
  std::size_t i = 0;
  if (text[0] == '-' || text[0] == '+') {
    negative = text[0] == '-';
    i = 1;
  }
  if (i == text.size()) return bad_number(text, "integer nanosecond timestamp");
  std::int64_t value = 0;
  for (; i < text.size(); ++i) {
    if (!is_digit(text[i])) return bad_number(text, "integer nanosecond timestamp");
    if (!push_digit(value, text[i])) return bad_number(text, "nanosecond timestamp (overflows int64)");
  }
  return negative ? -value : value;
}

StatusOr<TimestampNs> parse_decimal_seconds(std::string_view text) {
  constexpr std::string_view kWhat = "decimal number of seconds";
  if (text.empty()) return bad_number(text, kWhat);
  bool negative = false;
  std::size_t i = 0;
  if (text[0] == '-' || text[0] == '+') {
    negative = text[0] == '-';
    i = 1;
  }
  std::int64_t whole = 0;
  std::size_t whole_digits = 0;
  for (; i < text.size() && is_digit(text[i]); ++i, ++whole_digits) {
    if (!push_digit(whole, text[i])) return bad_number(text, "time in seconds (overflows int64 ns)");
  }
  std::int64_t frac_ns = 0;
  std::size_t frac_digits = 0;
  bool round_up = false;
  if (i < text.size() && text[i] == '.') {
    for (++i; i < text.size() && is_digit(text[i]); ++i, ++frac_digits) {
      if (frac_digits < 9) {
        frac_ns = frac_ns * 10 + (text[i] - '0');
      } else if (frac_digits == 9) {
        round_up = text[i] >= '5';
      }
    }
  }
  if (i != text.size() || whole_digits + frac_digits == 0) return bad_number(text, kWhat);
  for (std::size_t k = std::min<std::size_t>(frac_digits, 9); k < 9; ++k) frac_ns *= 10;
  if (round_up) ++frac_ns;
  constexpr std::int64_t kMax = std::numeric_limits<std::int64_t>::max();
  if (whole > (kMax - frac_ns) / kNanosecondsPerSecond) {
    return bad_number(text, "time in seconds (overflows int64 ns)");
  }
  const std::int64_t total = whole * kNanosecondsPerSecond + frac_ns;
  return negative ? -total : total;
}

std::string format_seconds(TimestampNs t_ns) {
  const bool negative = t_ns < 0;
  // Work in unsigned to format INT64_MIN correctly.
  const std::uint64_t mag =
      negative ? std::uint64_t{0} - static_cast<std::uint64_t>(t_ns) : static_cast<std::uint64_t>(t_ns);
  const std::uint64_t ns_per_s = static_cast<std::uint64_t>(kNanosecondsPerSecond);
  return fmt::format("{}{}.{:09d}", negative ? "-" : "", mag / ns_per_s, mag % ns_per_s);
}

}  // namespace mrvs
