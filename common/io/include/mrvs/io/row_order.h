#pragma once
// The row-ordering policy shared by every reader (ReadPolicy):
// - timestamps must be strictly increasing;
// - an exact duplicate (same timestamp and same values as an earlier row) is dropped
//   with the warning "<file>:<line>: duplicate of line <k>, dropped";
// - the same timestamp with different values is an error naming both lines;
// - an out-of-order row is an error naming the line and the previous timestamp, unless
//   policy.sort_out_of_order, in which case the rows are sorted (stably) by time and a
//   warning is recorded.
#include <algorithm>
#include <cstddef>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/io/trajectory_io.h"

namespace mrvs::io {

/// How a file writes its time column (only used to print times as the file shows them).
enum class TimeColumn {
  kNanoseconds,  ///< integer ns (EuRoC CSV)
  kSeconds,      ///< decimal seconds (TUM)
};

/// A parsed record and the 1-based file line it came from.
template <typename T>
struct NumberedRow {
  T value;
  int line = 0;
};

namespace detail {

/// Formats a time as the file shows it ("1403715273262142976" or "1403715273.262142976 s").
std::string format_file_time(TimestampNs t_ns, TimeColumn column);
Status out_of_order_error(const std::filesystem::path& path, int line, TimestampNs t_ns, int previous_line,
                          TimestampNs previous_t_ns, TimeColumn column);
Status conflicting_duplicate_error(const std::filesystem::path& path, int line, int first_line,
                                   TimestampNs t_ns, TimeColumn column);
/// Adds "<file>:<line>: duplicate of line <k>, dropped" (the first few individually; the
/// rest are counted by finish_duplicate_warnings).
void add_duplicate_warning(const std::filesystem::path& path, int line, int first_line,
                           std::size_t duplicates_so_far, Warnings* warnings);
void finish_duplicate_warnings(const std::filesystem::path& path, std::size_t duplicates, Warnings* warnings);
void add_sorted_warning(const std::filesystem::path& path, std::size_t rows, int first_line,
                        Warnings* warnings);

/// Index of the first row earlier than its predecessor, or rows.size() when sorted.
template <typename T>
std::size_t first_out_of_order(const std::vector<NumberedRow<T>>& rows) {
  for (std::size_t i = 1; i < rows.size(); ++i) {
    if (rows[i].value.t_ns < rows[i - 1].value.t_ns) return i;
  }
  return rows.size();
}

}  // namespace detail

/// Applies the ReadPolicy to `rows` (in file order). `T` has a `t_ns` member;
/// `same_values(a, b)` tells whether two rows with the same timestamp are identical.
/// Returns the rows in strictly increasing time order.
template <typename T, typename SameValues>
StatusOr<std::vector<T>> order_rows(const std::filesystem::path& path, std::vector<NumberedRow<T>> rows,
                                    const ReadPolicy& policy, Warnings* warnings, TimeColumn column,
                                    SameValues same_values) {
  const std::size_t unsorted_at = detail::first_out_of_order(rows);
  if (unsorted_at < rows.size() && policy.sort_out_of_order) {
    detail::add_sorted_warning(path, rows.size(), rows[unsorted_at].line, warnings);
    std::stable_sort(rows.begin(), rows.end(), [](const NumberedRow<T>& a, const NumberedRow<T>& b) {
      return a.value.t_ns < b.value.t_ns;
    });
  }
  std::vector<T> out;
  out.reserve(rows.size());
  int kept_line = 0;  // file line of out.back()
  std::size_t duplicates = 0;
  for (NumberedRow<T>& row : rows) {
    if (!out.empty()) {
      const T& kept = out.back();
      const TimestampNs t_ns = row.value.t_ns;
      if (t_ns < kept.t_ns) {
        return detail::out_of_order_error(path, row.line, t_ns, kept_line, kept.t_ns, column);
      }
      if (t_ns == kept.t_ns) {
        if (!same_values(row.value, kept)) {
          return detail::conflicting_duplicate_error(path, row.line, kept_line, t_ns, column);
        }
        detail::add_duplicate_warning(path, row.line, kept_line, duplicates++, warnings);
        continue;
      }
    }
    out.push_back(std::move(row.value));
    kept_line = row.line;
  }
  detail::finish_duplicate_warnings(path, duplicates, warnings);
  return out;
}

}  // namespace mrvs::io
