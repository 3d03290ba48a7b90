#pragma once
// Reading YAML files (tuning files and calibration files) without exceptions.
//
// yaml-cpp throws; everything here catches its exceptions and returns mrvs::Status with
// a message that names the file, the line and the column (1-based, like compilers do):
//   config/euroc.yaml:12:15: key 'tracker.max_features': expected an integer in [1, 5000], got '100000'
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "mrvs/core/status.h"

namespace mrvs::config {

/// A parsed YAML file plus what is needed to write good error messages.
///
/// YAML::Node has reference semantics: copies of a YamlDocument share one tree.
/// apply_overrides() clones the tree before changing it, so other copies are unaffected.
struct YamlDocument {
  YAML::Node root;             ///< the first YAML document of the file
  std::filesystem::path path;  ///< file it was read from; empty when parsed from a string
  std::string name;            ///< shown in messages: the path, or the name given to parse_yaml_string
  /// Dotted keys set by apply_overrides() -> the override text ("tracker.max_features=300"),
  /// so that errors about those keys point at the command line instead of a file line.
  std::map<std::string, std::string> overrides;

  /// Folder that relative paths in this file are relative to (the current folder for
  /// documents parsed from a string).
  std::filesystem::path base_dir() const;
};

/// Reads and parses a YAML file. Accepts the OpenCV `%YAML:1.0` first line (it is turned
/// into a comment, so line numbers stay right). Errors: NotFound naming the path when the
/// file cannot be opened; InvalidArgument `<file>:<line>:<col>: YAML syntax error: ...`.
StatusOr<YamlDocument> load_yaml_file(const std::filesystem::path& path);

/// Parses YAML text; `name` stands for the file name in messages. Same rules as load_yaml_file.
StatusOr<YamlDocument> parse_yaml_string(const std::string& text, const std::string& name = "<string>");

/// Applies command-line overrides "dotted.key=value" (value parsed as YAML, so "[1, 2]" is
/// a list). Missing sections are created. Types, ranges and unknown keys are checked when
/// the options are loaded (load_options); those errors name the override instead of a file
/// line. Errors here: no '=', empty key part, a key below a non-map value, bad YAML value.
/// On error `doc` is left unchanged.
Status apply_overrides(YamlDocument& doc, const std::vector<std::string>& overrides);

/// What every tool does with its `--config FILE` and `--set key=value` flags: the file (or an
/// empty document named "<command line>" when `file` is empty) with the overrides applied.
StatusOr<YamlDocument> load_yaml_with_overrides(const std::filesystem::path& file,
                                                const std::vector<std::string>& overrides);

/// Resolves a path written in `doc`: absolute paths are returned as they are, relative
/// ones are taken relative to the folder of the file (`calibration: euroc/imu.yaml`) and
/// made absolute (so the result stays valid when written to another file).
std::filesystem::path resolve_path(const YamlDocument& doc, const std::filesystem::path& path);

/// The node at a dotted path ("" = root, "estimator.update"); an invalid/undefined node
/// (check with IsDefined()) when a part is missing or a parent is not a map.
YAML::Node find_node(const YamlDocument& doc, const std::string& dotted_path);

/// "<file>:<line>:<col>" of a node (1-based), "<file>" when the node has no position, or
/// "override '<text>'" when `dotted_key` (or a parent of it) was set by apply_overrides().
std::string location(const YamlDocument& doc, const YAML::Node& node, const std::string& dotted_key = "");

/// A node as one line of text for error messages: the scalar itself, or a flow-style
/// rendering of a list/map ("[1, 2]"), shortened to about 80 characters.
std::string node_text(const YAML::Node& node);

/// The standard message: "<location>: key '<key>': expected <expected>, got '<node text>'".
std::string expected_error(const YamlDocument& doc, const YAML::Node& node, const std::string& dotted_key,
                           const std::string& expected);

}  // namespace mrvs::config
