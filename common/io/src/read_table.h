#pragma once
// Internal: reads every data row of a table file through a row parser.
#include <filesystem>
#include <string_view>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "mrvs/io/csv.h"
#include "mrvs/io/row_order.h"

namespace mrvs::io::internal {

/// Parses all data rows of `path` with `parse(const TableReader&, const TextRow&) ->
/// StatusOr<T>`, keeping line numbers. An empty table is an error naming the file and the
/// expected `layout`. A last line without a final newline that still parses is accepted
/// with a warning (it may have been cut inside its last field).
template <typename T, typename ParseRow>
StatusOr<std::vector<NumberedRow<T>>> read_table(const std::filesystem::path& path, Separator separator,
                                                 std::string_view layout, Warnings* warnings,
                                                 ParseRow parse) {
  MRVS_ASSIGN_OR_RETURN(TableReader reader, TableReader::open(path, separator));
  std::vector<NumberedRow<T>> rows;
  TextRow row;
  while (reader.next(row)) {
    MRVS_ASSIGN_OR_RETURN(T value, parse(reader, row));
    rows.push_back(NumberedRow<T>{std::move(value), row.line});
    if (row.unterminated && warnings != nullptr) {
      warnings->push_back(fmt::format(
          "{}: the file does not end in a newline; the last line was read as complete (if the file was "
          "cut off, its last value may be partial: re-copy the file)",
          reader.where(row)));
    }
  }
  MRVS_RETURN_IF_ERROR(reader.status());
  if (rows.empty()) {
    return absl::InvalidArgumentError(
        fmt::format("{}: no data rows (the file holds only blank or '#' lines); expected rows of {}",
                    path.string(), layout));
  }
  return rows;
}

}  // namespace mrvs::io::internal
