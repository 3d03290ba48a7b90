#include "mrvs/io/row_order.h"

#include <fmt/format.h>

namespace mrvs::io::detail {
namespace {

/// Duplicates listed one by one before the rest are only counted.
constexpr std::size_t kMaxListedDuplicates = 10;

}  // namespace

std::string format_file_time(TimestampNs t_ns, TimeColumn column) {
  return column == TimeColumn::kSeconds ? fmt::format("{} s", format_seconds(t_ns))
                                        : fmt::format("{} ns", t_ns);
}

Status out_of_order_error(const std::filesystem::path& path, int line, TimestampNs t_ns, int previous_line,
                          TimestampNs previous_t_ns, TimeColumn column) {
  return absl::InvalidArgumentError(fmt::format(
      "{}:{}: timestamp {} is not after the previous timestamp {} (line {}); rows must be in strictly "
      "increasing time order: sort the file by its first column (keeping the header first), or read it "
      "with ReadPolicy::sort_out_of_order = true",
      path.string(), line, format_file_time(t_ns, column), format_file_time(previous_t_ns, column),
      previous_line));
}

Status conflicting_duplicate_error(const std::filesystem::path& path, int line, int first_line,
                                   TimestampNs t_ns, TimeColumn column) {
  return absl::InvalidArgumentError(
      fmt::format("{}:{}: timestamp {} also appears on line {} with different values; a time can have only "
                  "one row: delete the wrong one of lines {} and {}",
                  path.string(), line, format_file_time(t_ns, column), first_line, first_line, line));
}

void add_duplicate_warning(const std::filesystem::path& path, int line, int first_line,
                           std::size_t duplicates_so_far, Warnings* warnings) {
  if (warnings == nullptr || duplicates_so_far >= kMaxListedDuplicates) return;
  warnings->push_back(fmt::format("{}:{}: duplicate of line {}, dropped", path.string(), line, first_line));
}

void finish_duplicate_warnings(const std::filesystem::path& path, std::size_t duplicates,
                               Warnings* warnings) {
  if (warnings == nullptr || duplicates <= kMaxListedDuplicates) return;
  warnings->push_back(fmt::format("{}: {} more exact duplicate rows dropped (not listed; {} in total)",
                                  path.string(), duplicates - kMaxListedDuplicates, duplicates));
}

void add_sorted_warning(const std::filesystem::path& path, std::size_t rows, int first_line,
                        Warnings* warnings) {
  if (warnings == nullptr) return;
  warnings->push_back(fmt::format(
      "{}:{}: rows are not in time order (first out-of-order row here); sorted all {} rows by time as the "
      "read policy asks",
      path.string(), first_line, rows));
}

}  // namespace mrvs::io::detail
