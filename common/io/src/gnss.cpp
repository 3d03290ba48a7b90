// GNSS fixes (mav0/gnss0/): data.csv reader and writer, sensor.yaml reader.
#include "mrvs/io/gnss.h"

#include <cmath>
#include <iterator>
#include <optional>
#include <utility>

#include <fmt/format.h>

#include "mrvs/config/calibration.h"
#include "mrvs/config/options.h"
#include "mrvs/config/yaml_document.h"
#include "mrvs/core/file.h"
#include "mrvs/io/csv.h"
#include "mrvs/io/row_order.h"
#include "read_table.h"
#include "write_rows.h"

namespace mrvs::io {
namespace {

constexpr const char* kGnssFieldNames[6] = {"#timestamp [ns]",      "p_x [m]",           "p_y [m]", "p_z [m]",
                                            "sigma_horizontal [m]", "sigma_vertical [m]"};

StatusOr<GnssFix> parse_gnss_row(const TableReader& reader, const TextRow& row) {
  MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 6, kGnssCsvHeader));
  GnssFix fix;
  MRVS_ASSIGN_OR_RETURN(fix.t_ns, reader.parse_ns(row, 0, kGnssFieldNames[0]));
  for (int i = 0; i < 3; ++i) {
    MRVS_ASSIGN_OR_RETURN(fix.p_map[i],
                          reader.parse_double(row, 1 + static_cast<std::size_t>(i), kGnssFieldNames[1 + i]));
  }
  MRVS_ASSIGN_OR_RETURN(fix.sigma_horizontal_m, reader.parse_double(row, 4, kGnssFieldNames[4]));
  MRVS_ASSIGN_OR_RETURN(fix.sigma_vertical_m, reader.parse_double(row, 5, kGnssFieldNames[5]));
  for (const std::size_t k : {std::size_t{4}, std::size_t{5}}) {
    const double sigma = k == 4 ? fix.sigma_horizontal_m : fix.sigma_vertical_m;
    if (!(sigma > 0.0)) {
      return reader.row_error(row, fmt::format("field {} ('{}'): {} is not > 0 (a standard deviation in "
                                               "metres); fix or delete this line",
                                               k + 1, kGnssFieldNames[k], row.fields[k]));
    }
  }
  return fix;
}

/// Reads the scalar keys of a GNSS sensor.yaml, collecting every error.
class YamlFields {
 public:
  explicit YamlFields(const config::YamlDocument& doc) : doc_(doc) {}

  /// A finite number (> lower, or >= lower when !strict); nullopt when absent or wrong.
  std::optional<double> number(const char* key, bool required, double lower, bool strict) {
    const std::string expected = fmt::format("a number {} {}", strict ? ">" : ">=", lower);
    const YAML::Node node = config::find_node(doc_, key);
    if (!node.IsDefined()) {
      if (required) {
        errors_.push_back(fmt::format("{}: key '{}': missing, expected {}", doc_.name, key, expected));
      }
      return std::nullopt;
    }
    double value = 0.0;
    if (!config::detail::Codec<double>::decode(node, value) || !std::isfinite(value) ||
        (strict ? !(value > lower) : !(value >= lower))) {
      errors_.push_back(config::expected_error(doc_, node, key, expected));
      return std::nullopt;
    }
    return value;
  }

  /// A scalar text; nullopt when absent or not a scalar.
  std::optional<std::string> text(const char* key, const char* expected) {
    const YAML::Node node = config::find_node(doc_, key);
    if (!node.IsDefined()) return std::nullopt;
    if (!node.IsScalar()) {
      errors_.push_back(config::expected_error(doc_, node, key, expected));
      return std::nullopt;
    }
    return node.Scalar();
  }

  void error(std::string message) { errors_.push_back(std::move(message)); }
  const std::vector<std::string>& errors() const { return errors_; }

 private:
  const config::YamlDocument& doc_;
  std::vector<std::string> errors_;
};

StatusOr<GnssSensor> parse_gnss_sensor(const config::YamlDocument& doc) {
  YamlFields f(doc);
  GnssSensor sensor;
  if (const auto type = f.text("sensor_type", "'gnss'"); type && *type != "gnss") {
    f.error(config::expected_error(doc, config::find_node(doc, "sensor_type"), "sensor_type",
                                   "'gnss' (is this the sensor.yaml of another sensor?)"));
  }
  if (const auto comment = f.text("comment", "a text")) sensor.comment = *comment;
  StatusOr<SE3d> T_b_antenna = config::read_euroc_T_BS(doc);
  if (T_b_antenna.ok()) {
    sensor.T_b_antenna = *T_b_antenna;
  } else {
    f.error(std::string(T_b_antenna.status().message()));
  }
  if (const auto rate = f.number("rate_hz", true, 0.0, true)) sensor.rate_hz = *rate;
  if (const auto s = f.number("sigma_horizontal_m", false, 0.0, true)) sensor.sigma_horizontal_m = *s;
  if (const auto s = f.number("sigma_vertical_m", false, 0.0, true)) sensor.sigma_vertical_m = *s;
  if (const auto tau = f.number("correlation_time_s", false, 0.0, false)) sensor.correlation_time_s = *tau;
  if (f.errors().empty()) return sensor;
  std::string message;
  for (const std::string& e : f.errors()) message += (message.empty() ? "" : "\n") + e;
  return absl::InvalidArgumentError(message);
}

}  // namespace

StatusOr<std::vector<GnssFix>> read_euroc_gnss_csv(const std::filesystem::path& csv, const ReadPolicy& policy,
                                                   Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(
      auto rows, internal::read_table<GnssFix>(csv, Separator::kComma, fmt::format("'{}'", kGnssCsvHeader),
                                               warnings, parse_gnss_row));
  return order_rows(csv, std::move(rows), policy, warnings, TimeColumn::kNanoseconds,
                    [](const GnssFix& a, const GnssFix& b) {
                      return a.p_map == b.p_map && a.sigma_horizontal_m == b.sigma_horizontal_m &&
                             a.sigma_vertical_m == b.sigma_vertical_m;
                    });
}

Status write_euroc_gnss_csv(const std::filesystem::path& csv, const std::vector<GnssFix>& fixes) {
  MRVS_RETURN_IF_ERROR(check_rows_to_write(csv, fixes, [](const GnssFix& f) {
    return f.p_map.allFinite() && std::isfinite(f.sigma_horizontal_m) && std::isfinite(f.sigma_vertical_m);
  }));
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    if (!(fixes[i].sigma_horizontal_m > 0.0) || !(fixes[i].sigma_vertical_m > 0.0)) {
      return absl::InvalidArgumentError(fmt::format(
          "cannot write {}: entry {} (t = {} ns) has a standard deviation <= 0 (horizontal {}, "
          "vertical {}); sigmas must be > 0",
          csv.string(), i, fixes[i].t_ns, fixes[i].sigma_horizontal_m, fixes[i].sigma_vertical_m));
    }
  }
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kGnssCsvHeader);
  for (const GnssFix& f : fixes) {
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{}\n", f.t_ns, f.p_map.x(), f.p_map.y(),
                   f.p_map.z(), f.sigma_horizontal_m, f.sigma_vertical_m);
  }
  return write_file_atomically(csv, fmt::to_string(out));
}

StatusOr<GnssSensor> read_gnss_sensor_yaml(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(const config::YamlDocument doc, config::load_yaml_file(path));
  try {
    return parse_gnss_sensor(doc);
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(
        fmt::format("{}: cannot read the GNSS sensor file: {}", path.string(), e.what()));
  }
}

}  // namespace mrvs::io
