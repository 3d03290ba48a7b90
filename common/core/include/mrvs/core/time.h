#pragma once
// Time convention: every timestamp in this project is an int64 count of nanoseconds
// (`TimestampNs`, variables named `t_ns`). Doubles appear only at the edges (printing,
// integration step lengths) and are never used as keys.
#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

#include "mrvs/core/status.h"

namespace mrvs {

using TimestampNs = std::int64_t;
using DurationNs = std::int64_t;

inline constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;

/// Seconds (double) of a duration in ns. For step lengths and printing only.
constexpr double to_seconds(DurationNs d_ns) { return static_cast<double>(d_ns) * 1e-9; }

/// Nearest ns of a duration in seconds. Prefer parse_decimal_seconds for file input.
DurationNs from_seconds(double s);

/// Parses a decimal number of seconds ("1403715273.262142976", "-0.5", "12", "1e-3" is
/// rejected) into ns exactly, without going through a double: a 19-digit EuRoC stamp
/// survives unchanged. Digits beyond the 9th decimal are rounded half away from zero.
StatusOr<TimestampNs> parse_decimal_seconds(std::string_view text);

/// Parses an integer nanosecond stamp ("1403715273262142976") with overflow checks.
StatusOr<TimestampNs> parse_nanoseconds(std::string_view text);

/// Formats ns as seconds with exactly 9 decimals ("1403715273.262142976"); the inverse of
/// parse_decimal_seconds.
std::string format_seconds(TimestampNs t_ns);

/// Wall time in milliseconds (steady clock) since t0: the per-frame timing columns.
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace mrvs
