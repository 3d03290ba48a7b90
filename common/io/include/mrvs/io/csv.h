#pragma once
// Line-oriented reader for the text tables of datasets (EuRoC CSV, TUM trajectories).
//
// - Lines are numbered from 1 as an editor shows them (blank and comment lines count).
// - A trailing '\r' (CRLF files) and a UTF-8 byte-order mark on line 1 are removed.
// - Blank lines and lines whose first non-blank character is '#' (EuRoC header lines,
//   TUM comments) are skipped.
// - Fields are split on ',' (CSV) or on runs of blanks (TUM), and trimmed of blanks
//   (' ' and '\t'), so "1, 2,3 " is three fields.
// - Every error names "<file>:<line>", the field (1-based index and column name), and
//   says how to fix it.
#include <cstddef>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"

namespace mrvs::io {

/// How the fields of a line are separated.
enum class Separator {
  kComma,       ///< "a,b,c" (blanks around fields are trimmed)
  kWhitespace,  ///< "a b\tc" (runs of spaces and tabs)
};

/// One data line of a table file.
struct TextRow {
  int line = 0;                     ///< 1-based line number in the file
  std::vector<std::string> fields;  ///< trimmed field texts
  bool unterminated = false;        ///< last line of a file that does not end in '\n'
};

/// Splits one line (without its newline) into trimmed fields.
std::vector<std::string> split_fields(std::string_view line, Separator separator);

/// Streams the data rows of a text table file.
class TableReader {
 public:
  /// Opens `path`. NotFound naming the path when it does not exist, PermissionDenied when
  /// it exists but cannot be read, InvalidArgument when it is a folder.
  static StatusOr<TableReader> open(const std::filesystem::path& path, Separator separator);

  TableReader(TableReader&&) = default;
  TableReader& operator=(TableReader&&) = default;

  /// Reads the next data row into `row` (skipping blank and comment lines). Returns false
  /// at the end of the file; a read error sets status() to an error.
  bool next(TextRow& row);

  /// OK unless reading failed part-way (I/O error).
  const Status& status() const { return status_; }
  const std::filesystem::path& path() const { return path_; }
  Separator separator() const { return separator_; }

  /// "<file>:<line>" for messages.
  std::string where(const TextRow& row) const;

  /// Error unless `row` has exactly `expected` fields. `columns` names them for the
  /// message, e.g. "t tx ty tz qx qy qz qw". A short last line of a file without a final
  /// newline is reported as truncated (DataLoss).
  Status check_field_count(const TextRow& row, std::size_t expected, std::string_view columns) const;

  /// Field `k` (0-based; messages count from 1) as a finite double.
  StatusOr<double> parse_double(const TextRow& row, std::size_t k, std::string_view name) const;
  /// Field `k` as an integer nanosecond stamp (parse_nanoseconds).
  StatusOr<TimestampNs> parse_ns(const TextRow& row, std::size_t k, std::string_view name) const;
  /// Field `k` as decimal seconds converted exactly to ns (parse_decimal_seconds).
  StatusOr<TimestampNs> parse_seconds(const TextRow& row, std::size_t k, std::string_view name) const;

  /// Builds an error "<file>:<line>: <what>" (with the truncation hint when `row` is an
  /// unterminated last line).
  Status row_error(const TextRow& row, const std::string& what) const;

 private:
  TableReader(std::filesystem::path path, Separator separator, std::ifstream in);

  std::filesystem::path path_;
  Separator separator_;
  std::ifstream in_;
  int line_ = 0;
  Status status_;
};

/// Parses a finite double from the whole of `text` (no blanks, "+" allowed, "nan"/"inf"
/// rejected). False when `text` is not such a number.
bool parse_finite_double(std::string_view text, double& value);

}  // namespace mrvs::io
