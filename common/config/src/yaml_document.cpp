#include "mrvs/config/yaml_document.h"

#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>
#include <utility>

#include <fmt/format.h>

namespace mrvs::config {
namespace {

constexpr std::size_t kMaxNodeTextChars = 80;

/// OpenCV writes "%YAML:1.0" as the first line, which yaml-cpp rejects. Turn it into a
/// comment (same number of lines, so positions in messages stay right).
std::string neutralise_opencv_header(std::string text) {
  std::size_t start = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) start = 3;  // UTF-8 byte order mark
  if (text.compare(start, 6, "%YAML:") == 0) text.insert(start, "#");
  return text;
}

std::vector<std::string> split_dotted(const std::string& dotted) {
  std::vector<std::string> parts;
  if (dotted.empty()) return parts;
  std::size_t begin = 0;
  while (true) {
    const std::size_t dot = dotted.find('.', begin);
    parts.push_back(dotted.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin));
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  return parts;
}

std::string trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  const auto last = s.find_last_not_of(" \t");
  return s.substr(first, last - first + 1);
}

/// Value of `key` in a map node (first occurrence), or nullopt.
std::optional<YAML::Node> map_value(const YAML::Node& map, const std::string& key) {
  if (!map.IsMap()) return std::nullopt;
  for (auto it = map.begin(); it != map.end(); ++it) {
    if (it->first.IsScalar() && it->first.Scalar() == key) return it->second;
  }
  return std::nullopt;
}

/// Sets one override on `root` (a map). Returns an error message or "".
std::string set_override(YAML::Node& root, const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos) {
    return fmt::format("override '{}': expected 'dotted.key=value'", text);
  }
  const std::string key = trim(text.substr(0, eq));
  const std::vector<std::string> parts = split_dotted(key);
  if (parts.empty()) return fmt::format("override '{}': empty key", text);
  for (const std::string& part : parts) {
    if (trim(part).empty()) return fmt::format("override '{}': empty part in key '{}'", text, key);
  }
  YAML::Node value;
  try {
    value = YAML::Load(trim(text.substr(eq + 1)));
  } catch (const YAML::Exception& e) {
    return fmt::format("override '{}': the value is not valid YAML: {}", text, e.msg);
  }
  YAML::Node cur(root);
  std::string path;
  for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
    path += (i == 0 ? "" : ".") + parts[i];
    YAML::Node child = cur[parts[i]];
    if (!child.IsDefined() || child.IsNull()) {
      cur[parts[i]] = YAML::Node(YAML::NodeType::Map);
      child.reset(cur[parts[i]]);
    } else if (!child.IsMap()) {
      return fmt::format("override '{}': '{}' is not a section (it holds '{}')", text, path,
                         node_text(child));
    }
    cur.reset(child);
  }
  cur[parts.back()] = value;
  return {};
}

}  // namespace

std::filesystem::path YamlDocument::base_dir() const { return path.parent_path(); }

StatusOr<YamlDocument> parse_yaml_string(const std::string& text, const std::string& name) {
  YamlDocument doc;
  doc.name = name;
  try {
    doc.root.reset(YAML::Load(neutralise_opencv_header(text)));
  } catch (const YAML::ParserException& e) {
    return absl::InvalidArgumentError(
        fmt::format("{}:{}:{}: YAML syntax error: {}", name, e.mark.line + 1, e.mark.column + 1, e.msg));
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(fmt::format("{}: cannot parse YAML: {}", name, e.what()));
  }
  return doc;
}

StatusOr<YamlDocument> load_yaml_file(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    return absl::NotFoundError(fmt::format("YAML file '{}' does not exist", path.string()));
  }
  if (std::filesystem::is_directory(path, ec)) {
    return absl::InvalidArgumentError(fmt::format("'{}' is a folder, expected a YAML file", path.string()));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(fmt::format("cannot open YAML file '{}'", path.string()));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return absl::DataLossError(fmt::format("cannot read YAML file '{}'", path.string()));
  MRVS_ASSIGN_OR_RETURN(YamlDocument doc, parse_yaml_string(text.str(), path.string()));
  doc.path = path;
  return doc;
}

Status apply_overrides(YamlDocument& doc, const std::vector<std::string>& overrides) {
  if (overrides.empty()) return absl::OkStatus();
  YAML::Node root;
  std::vector<std::string> errors;
  try {
    root = YAML::Clone(doc.root);
    if (!root.IsDefined() || root.IsNull()) {
      root.reset(YAML::Node(YAML::NodeType::Map));
    } else if (!root.IsMap()) {
      return absl::InvalidArgumentError(
          fmt::format("{}: cannot apply overrides, the document is not a map of keys", doc.name));
    }
    for (const std::string& text : overrides) {
      std::string error = set_override(root, text);
      if (!error.empty()) errors.push_back(std::move(error));
    }
  } catch (const YAML::Exception& e) {
    errors.push_back(fmt::format("cannot apply overrides: {}", e.what()));
  }
  if (!errors.empty()) {
    std::string message;
    for (const std::string& e : errors) message += (message.empty() ? "" : "\n") + e;
    return absl::InvalidArgumentError(message);
  }
  doc.root.reset(root);  // rebind; `doc.root = root` would write into a tree shared with copies
  for (const std::string& text : overrides) {
    doc.overrides[trim(text.substr(0, text.find('=')))] = text;
  }
  return absl::OkStatus();
}

std::filesystem::path resolve_path(const YamlDocument& doc, const std::filesystem::path& path) {
  if (path.empty() || path.is_absolute()) return path;
  const std::filesystem::path joined = doc.base_dir() / path;
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(joined, ec);
  return (ec ? joined : absolute).lexically_normal();
}

YAML::Node find_node(const YamlDocument& doc, const std::string& dotted_path) {
  YAML::Node cur(doc.root);
  for (const std::string& part : split_dotted(dotted_path)) {
    std::optional<YAML::Node> child = map_value(cur, part);
    if (!child) return YAML::Node(YAML::NodeType::Undefined);
    cur.reset(*child);
  }
  return cur;
}

std::string location(const YamlDocument& doc, const YAML::Node& node, const std::string& dotted_key) {
  // A key set on the command line, or a key below a section set there.
  std::string prefix = dotted_key;
  while (!prefix.empty()) {
    const auto it = doc.overrides.find(prefix);
    if (it != doc.overrides.end()) return fmt::format("override '{}'", it->second);
    const std::size_t dot = prefix.rfind('.');
    prefix = dot == std::string::npos ? std::string() : prefix.substr(0, dot);
  }
  try {
    if (node.IsDefined()) {
      const YAML::Mark mark = node.Mark();
      if (!mark.is_null()) return fmt::format("{}:{}:{}", doc.name, mark.line + 1, mark.column + 1);
    }
  } catch (const YAML::Exception&) {
    // An invalid node has no position: fall through to the file name alone.
  }
  return doc.name;
}

std::string node_text(const YAML::Node& node) {
  std::string text;
  try {
    if (!node.IsDefined() || node.IsNull()) return "";
    if (node.IsScalar()) {
      text = node.Scalar();
    } else {
      YAML::Emitter out;
      out.SetSeqFormat(YAML::Flow);
      out.SetMapFormat(YAML::Flow);
      out << node;
      text = out.c_str();
    }
  } catch (const YAML::Exception&) {
    return "?";
  }
  for (char& c : text) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  if (text.size() > kMaxNodeTextChars) text = text.substr(0, kMaxNodeTextChars - 3) + "...";
  return text;
}

std::string expected_error(const YamlDocument& doc, const YAML::Node& node, const std::string& dotted_key,
                           const std::string& expected) {
  return fmt::format("{}: key '{}': expected {}, got '{}'", location(doc, node, dotted_key), dotted_key,
                     expected, node_text(node));
}

StatusOr<YamlDocument> load_yaml_with_overrides(const std::filesystem::path& file,
                                                const std::vector<std::string>& overrides) {
  MRVS_ASSIGN_OR_RETURN(YamlDocument doc,
                        file.empty() ? parse_yaml_string("", "<command line>") : load_yaml_file(file));
  MRVS_RETURN_IF_ERROR(apply_overrides(doc, overrides));
  return doc;
}

}  // namespace mrvs::config
