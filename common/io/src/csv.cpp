#include "mrvs/io/csv.h"

#include <charconv>
#include <cmath>
#include <system_error>
#include <utility>

#include <fmt/format.h>

namespace mrvs::io {
namespace {

bool is_blank(char c) { return c == ' ' || c == '\t'; }

std::string_view trim(std::string_view s) {
  while (!s.empty() && is_blank(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_blank(s.back())) s.remove_suffix(1);
  return s;
}

const char* separator_name(Separator separator) {
  return separator == Separator::kComma ? "comma-separated" : "blank-separated";
}

constexpr const char* kTruncatedHint =
    " (this is the last line and the file does not end in a newline: the file was probably cut off "
    "while being written or copied; re-copy it, or delete this partial line)";

}  // namespace

std::vector<std::string> split_fields(std::string_view line, Separator separator) {
  std::vector<std::string> fields;
  if (separator == Separator::kComma) {
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = line.find(',', start);
      const std::string_view field =
          line.substr(start, comma == std::string_view::npos ? std::string_view::npos : comma - start);
      fields.emplace_back(trim(field));
      if (comma == std::string_view::npos) break;
      start = comma + 1;
    }
    return fields;
  }
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && is_blank(line[i])) ++i;
    const std::size_t start = i;
    while (i < line.size() && !is_blank(line[i])) ++i;
    if (i > start) fields.emplace_back(line.substr(start, i - start));
  }
  return fields;
}

bool parse_finite_double(std::string_view text, double& value) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text.front() == '-' || text.front() == '+')) return false;
  }
  if (text.empty()) return false;
  double parsed = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), parsed);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(parsed)) return false;
  value = parsed;
  return true;
}

TableReader::TableReader(std::filesystem::path path, Separator separator, std::ifstream in)
    : path_(std::move(path)), separator_(separator), in_(std::move(in)) {}

StatusOr<TableReader> TableReader::open(const std::filesystem::path& path, Separator separator) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (!std::filesystem::exists(st)) {
    return absl::NotFoundError(fmt::format("file {} does not exist; check the path", path.string()));
  }
  if (std::filesystem::is_directory(st)) {
    return absl::InvalidArgumentError(
        fmt::format("{} is a folder, expected a text file; give the path of the file itself", path.string()));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    return absl::PermissionDeniedError(
        fmt::format("cannot open {} for reading; check its permissions", path.string()));
  }
  return TableReader(path, separator, std::move(in));
}

bool TableReader::next(TextRow& row) {
  std::string text;
  while (std::getline(in_, text)) {
    ++line_;
    const bool unterminated = in_.eof();
    if (line_ == 1 && text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3);  // UTF-8 BOM
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const std::string_view content = trim(text);
    if (content.empty() || content.front() == '#') continue;
    row.line = line_;
    row.fields = split_fields(content, separator_);
    row.unterminated = unterminated;
    return true;
  }
  if (in_.bad()) {
    status_ = absl::DataLossError(fmt::format(
        "{}: read error after line {}; check the disk or re-copy the file", path_.string(), line_));
  }
  return false;
}

std::string TableReader::where(const TextRow& row) const {
  return fmt::format("{}:{}", path_.string(), row.line);
}

Status TableReader::row_error(const TextRow& row, const std::string& what) const {
  const std::string message =
      fmt::format("{}: {}{}", where(row), what, row.unterminated ? kTruncatedHint : "");
  return row.unterminated ? absl::DataLossError(message) : absl::InvalidArgumentError(message);
}

Status TableReader::check_field_count(const TextRow& row, std::size_t expected,
                                      std::string_view columns) const {
  if (row.fields.size() == expected) return absl::OkStatus();
  std::string what = fmt::format("expected {} {} fields ({}), found {}", expected, separator_name(separator_),
                                 columns, row.fields.size());
  if (!row.unterminated) what += "; fix or delete this line";
  return row_error(row, what);
}

StatusOr<double> TableReader::parse_double(const TextRow& row, std::size_t k, std::string_view name) const {
  if (k >= row.fields.size()) {
    return row_error(row, fmt::format("field {} ('{}') is missing", k + 1, name));
  }
  double value = 0.0;
  if (!parse_finite_double(row.fields[k], value)) {
    return row_error(row, fmt::format("field {} ('{}'): '{}' is not a number{}", k + 1, name, row.fields[k],
                                      row.unterminated ? "" : "; fix or delete this line"));
  }
  return value;
}

StatusOr<TimestampNs> TableReader::parse_ns(const TextRow& row, std::size_t k, std::string_view name) const {
  if (k >= row.fields.size()) {
    return row_error(row, fmt::format("field {} ('{}') is missing", k + 1, name));
  }
  StatusOr<TimestampNs> t = parse_nanoseconds(row.fields[k]);
  if (!t.ok()) {
    return row_error(
        row, fmt::format("field {} ('{}'): '{}' is not a number (expected integer nanoseconds: {})", k + 1,
                         name, row.fields[k], std::string(t.status().message())));
  }
  return t;
}

StatusOr<TimestampNs> TableReader::parse_seconds(const TextRow& row, std::size_t k,
                                                 std::string_view name) const {
  if (k >= row.fields.size()) {
    return row_error(row, fmt::format("field {} ('{}') is missing", k + 1, name));
  }
  StatusOr<TimestampNs> t = parse_decimal_seconds(row.fields[k]);
  if (!t.ok()) {
    return row_error(row,
                     fmt::format("field {} ('{}'): '{}' is not a number (expected decimal seconds such as "
                                 "1403715273.262142976: {})",
                                 k + 1, name, row.fields[k], std::string(t.status().message())));
  }
  return t;
}

}  // namespace mrvs::io
