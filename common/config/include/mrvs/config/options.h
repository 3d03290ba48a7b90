#pragma once
// Options structs: one per module, each field declared ONCE (in visit()), so loading,
// validation, printing, saving and comparing cannot drift apart.
//
//   struct TrackerOptions : mrvs::config::OptionsEquality<TrackerOptions> {
//     int max_features = 200;        ///< features per frame
//     double min_px_dist = 10.0;     ///< px
//     std::vector<double> resolutions = {0.01, 0.02};  ///< m
//     Eigen::Vector3d gravity{0.0, 0.0, -9.81};        ///< m/s^2
//     ImuOptions imu;                ///< nested section (has its own visit())
//
//     template <class V>
//     void visit(V& v) {
//       using namespace mrvs::config::constraints;
//       v("max_features", max_features, in_range(1, 5000), "features per frame");
//       v("min_px_dist", min_px_dist, in_range(0.0, 100.0), "px between features");
//       v("resolutions", resolutions, each_in_range(0.001, 10.0).size(1, 16), "voxel sizes, m");
//       v("gravity", gravity, any(), "m/s^2");
//       v.section("imu", imu, "IMU noise");
//     }
//   };
//
//   MRVS_ASSIGN_OR_RETURN(YamlDocument doc, load_yaml_file("config/euroc.yaml"));
//   MRVS_RETURN_IF_ERROR(apply_overrides(doc, {"tracker.max_features=300"}));
//   MRVS_ASSIGN_OR_RETURN(TrackerOptions tracker, load_options<TrackerOptions>(doc, "tracker"));
//   spdlog::info("options:\n{}", options_to_yaml(tracker, "tracker"));
//
// Rules of the loader
// - Keys absent from the file keep the struct's in-class default.
// - Present keys are checked for type and constraint; unknown keys are errors with a
//   "did you mean" hint; duplicated keys are errors. ALL errors are returned at once, one
//   per line: `<file>:<line>:<col>: key '<dotted.key>': expected <what>, got '<value>'`.
// - std::filesystem::path fields written relative in a file are resolved against that
//   file's folder (absolute result); paths given as overrides are taken as they are.
// - A module section missing from the file means "all defaults". To reject misspelt
//   section names, load one root struct whose visit() lists every module as a section.
//
// Requirements on visit(): it calls the same v(...) / v.section(...) in the same order for
// every instance (no branches on field values). Field types: see detail/codecs.h.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "mrvs/config/constraints.h"
#include "mrvs/config/detail/visitors.h"
#include "mrvs/config/yaml_document.h"
#include "mrvs/core/file.h"
#include "mrvs/core/status.h"

namespace mrvs::config {

namespace detail {
/// Header lines "a:", "  b:" for the dotted section "a.b".
std::vector<YamlLine> section_headers(const std::string& section);
/// Number of parts of a dotted section ("" -> 0).
int section_depth(const std::string& section);
}  // namespace detail

/// How options_to_yaml writes.
struct WriteStyle {
  bool comments = true;       ///< each key's doc string as a trailing "# ..." comment
  bool mark_defaults = true;  ///< "(default)" on keys whose value equals the in-class default
};

/// Reads `section` of `doc` ("" = whole document, "estimator.update" = nested) into
/// `options`. All or nothing: on error `options` is unchanged and the status lists every
/// problem, one per line.
template <class T>
Status update_options(const YamlDocument& doc, const std::string& section, T& options) {
  std::vector<std::string> errors;
  T result = options;
  try {
    const YAML::Node node = section.empty() ? doc.root : find_node(doc, section);
    if (node.IsDefined() && !node.IsNull() && !node.IsMap()) {
      errors.push_back(
          expected_error(doc, node, section.empty() ? "<document>" : section, "a section (a map of keys)"));
    } else {
      detail::Loader loader(doc, node, section, &errors);
      result.visit(loader);
      loader.finish();
    }
  } catch (const YAML::Exception& e) {
    errors.push_back(fmt::format("{}: cannot read options: {}", doc.name, e.what()));
  }
  if (!errors.empty()) return detail::errors_to_status(errors);
  options = std::move(result);
  return absl::OkStatus();
}

/// Reads `section` of `doc` on top of the in-class defaults of T (see update_options).
template <class T>
StatusOr<T> load_options(const YamlDocument& doc, const std::string& section = "") {
  T options{};
  MRVS_RETURN_IF_ERROR(update_options(doc, section, options));
  return options;
}

/// load_yaml_file + apply_overrides + load_options in one call (for main()).
template <class T>
StatusOr<T> load_options_file(const std::filesystem::path& path, const std::string& section = "",
                              const std::vector<std::string>& overrides = {}) {
  MRVS_ASSIGN_OR_RETURN(YamlDocument doc, load_yaml_file(path));
  MRVS_RETURN_IF_ERROR(apply_overrides(doc, overrides));
  return load_options<T>(doc, section);
}

/// Checks the current values against the constraints (e.g. after changing them in code).
/// Messages: "key '<section.key>': expected ..., got '...'".
template <class T>
Status validate_options(const T& options, const std::string& section = "") {
  std::vector<std::string> errors;
  T copy = options;
  detail::Validator validator(section, &errors);
  copy.visit(validator);
  return detail::errors_to_status(errors);
}

/// The options as YAML text, nested under `section` (dotted, "" = top level), with each
/// key's doc string and a "(default)" marker (see WriteStyle). Loading the text back gives
/// an equal struct. Meant for start-up logs and for saving the configuration actually used.
template <class T>
std::string options_to_yaml(const T& options, const std::string& section = "", const WriteStyle& style = {}) {
  T defaults{};
  detail::FieldAddresses default_fields;
  defaults.visit(default_fields);
  T copy = options;
  detail::Writer writer(default_fields, detail::section_depth(section), style.comments, style.mark_defaults);
  copy.visit(writer);
  std::vector<detail::YamlLine> lines = detail::section_headers(section);
  lines.insert(lines.end(), writer.lines().begin(), writer.lines().end());
  return detail::render_yaml_lines(lines);
}

/// Writes options_to_yaml(options, section, {comments, no default markers}) to `path`.
template <class T>
Status save_options(const std::filesystem::path& path, const T& options, const std::string& section = "") {
  WriteStyle style;
  style.mark_defaults = false;
  return write_file_atomically(
      path, "# Written by mrvs::config::save_options\n" + options_to_yaml(options, section, style));
}

/// Dotted keys whose values differ between a and b (doubles compare exactly; NaN == NaN).
template <class T>
std::vector<std::string> options_diff(const T& a, const T& b) {
  T copy_b = b;
  detail::FieldAddresses b_fields;
  copy_b.visit(b_fields);
  std::vector<std::string> differences;
  T copy_a = a;
  detail::Differ differ(b_fields, &differences);
  copy_a.visit(differ);
  return differences;
}

/// True when every field compares equal (see options_diff).
template <class T>
bool options_equal(const T& a, const T& b) {
  return options_diff(a, b).empty();
}

/// Base class giving an Options struct operator== / operator!= from its visit():
/// `struct TrackerOptions : mrvs::config::OptionsEquality<TrackerOptions> { ... };`
template <class D>
struct OptionsEquality {
  friend bool operator==(const D& a, const D& b) { return options_equal(a, b); }
  friend bool operator!=(const D& a, const D& b) { return !options_equal(a, b); }
};

}  // namespace mrvs::config
