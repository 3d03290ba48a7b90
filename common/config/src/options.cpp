#include "mrvs/config/options.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>

#include <fmt/format.h>

namespace mrvs::config {
namespace {

constexpr std::size_t kMaxCommentColumn = 60;
constexpr std::size_t kMaxKnownKeysListed = 20;

std::string to_lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

/// Optimal-string-alignment distance (Levenshtein plus swaps of neighbours).
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

/// The known key closest to `key`, if it is close enough to be a likely typo.
std::string suggest(const std::string& key, const std::vector<std::string>& known) {
  const std::string lower = to_lower(key);
  const std::size_t limit = std::max<std::size_t>(2, key.size() / 3);
  std::string best;
  std::size_t best_distance = limit + 1;
  for (const std::string& candidate : known) {
    const std::size_t d = edit_distance(lower, to_lower(candidate));
    if (d < best_distance) {
      best = candidate;
      best_distance = d;
    }
  }
  return best;
}

std::string unknown_key_hint(const std::string& key, const std::vector<std::string>& known) {
  const std::string suggestion = suggest(key, known);
  if (!suggestion.empty()) return fmt::format("unknown key, did you mean '{}'?", suggestion);
  if (known.empty()) return "unknown key (this section has no keys)";
  std::string list;
  for (std::size_t i = 0; i < known.size() && i < kMaxKnownKeysListed; ++i)
    list += (i == 0 ? "" : ", ") + known[i];
  if (known.size() > kMaxKnownKeysListed) list += ", ...";
  return fmt::format("unknown key (known keys here: {})", list);
}

bool is_plain_safe(const std::string& s) {
  if (s.empty()) return false;
  const auto c0 = static_cast<unsigned char>(s[0]);
  if (!(std::isalpha(c0) || s[0] == '_' || s[0] == '/')) return false;
  for (const char c : s) {
    const auto u = static_cast<unsigned char>(c);
    if (!(std::isalnum(u) || c == '_' || c == '.' || c == '/' || c == '-')) return false;
  }
  static constexpr const char* kReserved[] = {"true", "false", "yes", "no", "on", "off", "y", "n", "null"};
  const std::string lower = to_lower(s);
  return std::none_of(std::begin(kReserved), std::end(kReserved), [&](const char* r) { return lower == r; });
}

}  // namespace

namespace detail {

bool parse_double(const std::string& text, double* out) {
  const std::string lower = to_lower(text);
  if (lower == ".inf" || lower == "+.inf") {
    *out = std::numeric_limits<double>::infinity();
    return true;
  }
  if (lower == "-.inf") {
    *out = -std::numeric_limits<double>::infinity();
    return true;
  }
  if (lower == ".nan") {
    *out = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  double value = 0.0;
  const auto [ptr, ec] = std::from_chars(first, last, value, std::chars_format::general);
  if (ec != std::errc() || ptr != last) return false;
  *out = value;
  return true;
}

bool parse_bool(const std::string& text, bool* out) {
  const std::string lower = to_lower(text);
  if (lower == "true" || lower == "yes" || lower == "on") {
    *out = true;
    return true;
  }
  if (lower == "false" || lower == "no" || lower == "off") {
    *out = false;
    return true;
  }
  return false;
}

namespace {
std::string finish_float_text(std::string text, bool is_nan, bool is_inf, bool negative) {
  if (is_nan) return ".nan";
  if (is_inf) return negative ? "-.inf" : ".inf";
  if (text.find_first_of(".eE") == std::string::npos) text += ".0";
  return text;
}
}  // namespace

std::string format_double(double value) {
  return finish_float_text(fmt::format("{}", value), std::isnan(value), std::isinf(value), value < 0);
}

std::string format_float(float value) {
  return finish_float_text(fmt::format("{}", value), std::isnan(value), std::isinf(value), value < 0);
}

std::string yaml_quote(const std::string& text) {
  if (is_plain_safe(text)) return text;
  std::string out = "\"";
  for (const char c : text) {
    switch (c) {
      case '"':
        out += "\\\"";
        break;
      case '\\':
        out += "\\\\";
        break;
      case '\n':
        out += "\\n";
        break;
      case '\t':
        out += "\\t";
        break;
      case '\r':
        out += "\\r";
        break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          out += fmt::format("\\x{:02x}", static_cast<unsigned>(static_cast<unsigned char>(c)));
        } else {
          out += c;
        }
    }
  }
  return out + "\"";
}

YAML::Node Loader::find(const char* key) const {
  if (map_.IsDefined() && map_.IsMap()) {
    for (auto it = map_.begin(); it != map_.end(); ++it) {
      if (it->first.IsScalar() && it->first.Scalar() == key) return it->second;
    }
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

void Loader::finish() const {
  if (!map_.IsDefined() || !map_.IsMap()) return;
  std::map<std::string, std::string> first_seen;  // key -> its location
  for (auto it = map_.begin(); it != map_.end(); ++it) {
    const YAML::Node key_node = it->first;  // a copy: `it->` returns a temporary proxy
    if (!key_node.IsScalar()) {
      errors_->push_back(fmt::format("{}: key '{}': expected a plain key, got '{}'", location(doc_, key_node),
                                     path_.prefix(), node_text(key_node)));
      continue;
    }
    const std::string& key = key_node.Scalar();
    const std::string dotted = path_.join(key.c_str());
    const std::string where = location(doc_, key_node, dotted);
    const auto [seen, inserted] = first_seen.emplace(key, where);
    if (!inserted) {
      errors_->push_back(
          fmt::format("{}: key '{}': duplicate key (first at {})", where, dotted, seen->second));
    } else if (std::find(known_.begin(), known_.end(), key) == known_.end()) {
      errors_->push_back(fmt::format("{}: key '{}': {}", where, dotted, unknown_key_hint(key, known_)));
    }
  }
}

std::string render_yaml_lines(const std::vector<YamlLine>& lines) {
  std::vector<std::string> texts;
  texts.reserve(lines.size());
  std::size_t column = 0;
  for (const YamlLine& line : lines) {
    std::string text = std::string(static_cast<std::size_t>(2 * line.depth), ' ') + line.key + ":";
    if (!line.value.empty()) text += " " + line.value;
    if (!line.comment.empty() && text.size() <= kMaxCommentColumn) column = std::max(column, text.size());
    texts.push_back(std::move(text));
  }
  std::string out;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    out += texts[i];
    if (!lines[i].comment.empty()) {
      std::string comment = lines[i].comment;
      std::replace(comment.begin(), comment.end(), '\n', ' ');
      const std::size_t pad = texts[i].size() < column ? column - texts[i].size() : 0;
      out += std::string(pad + 2, ' ') + "# " + comment;
    }
    out += "\n";
  }
  return out;
}

Status errors_to_status(const std::vector<std::string>& errors) {
  if (errors.empty()) return absl::OkStatus();
  std::string message;
  for (const std::string& e : errors) message += (message.empty() ? "" : "\n") + e;
  return absl::InvalidArgumentError(message);
}

int section_depth(const std::string& section) {
  if (section.empty()) return 0;
  return static_cast<int>(std::count(section.begin(), section.end(), '.')) + 1;
}

std::vector<YamlLine> section_headers(const std::string& section) {
  std::vector<YamlLine> lines;
  if (section.empty()) return lines;
  std::size_t begin = 0;
  int depth = 0;
  while (true) {
    const std::size_t dot = section.find('.', begin);
    lines.push_back(
        {depth++, section.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin), "", ""});
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  return lines;
}

}  // namespace detail
}  // namespace mrvs::config
