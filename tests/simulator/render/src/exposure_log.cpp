#include "mrvs/sim/exposure_log.h"

#include <iterator>

#include <fmt/format.h>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/file.h"
#include "mrvs/io/csv.h"

namespace mrvs::sim {
namespace {
constexpr const char* kHeader = "#timestamp [ns],exposure [ms],analog_gain,gain,mean_dn,blur_samples";
}  // namespace

Status write_exposure_csv(const std::filesystem::path& path, const std::vector<FrameExposure>& frames) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kHeader);
  for (const FrameExposure& f : frames) {
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{}\n", f.t_ns, f.exposure_ms, f.analog_gain,
                   f.gain, f.mean_dn, f.samples);
  }
  return write_file_atomically(path, fmt::to_string(out));
}

StatusOr<std::vector<FrameExposure>> read_exposure_csv(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(io::TableReader reader, io::TableReader::open(path, io::Separator::kComma));
  std::vector<FrameExposure> frames;
  io::TextRow row;
  while (reader.next(row)) {
    MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 6, kHeader));
    FrameExposure f;
    MRVS_ASSIGN_OR_RETURN(f.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
    MRVS_ASSIGN_OR_RETURN(f.exposure_ms, reader.parse_double(row, 1, "exposure [ms]"));
    MRVS_ASSIGN_OR_RETURN(f.analog_gain, reader.parse_double(row, 2, "analog_gain"));
    MRVS_ASSIGN_OR_RETURN(f.gain, reader.parse_double(row, 3, "gain"));
    MRVS_ASSIGN_OR_RETURN(f.mean_dn, reader.parse_double(row, 4, "mean_dn"));
    MRVS_ASSIGN_OR_RETURN(const double samples, reader.parse_double(row, 5, "blur_samples"));
    if (!(samples >= 1.0 && samples <= 1e6) || samples != static_cast<double>(static_cast<int>(samples))) {
      return reader.row_error(row,
                              fmt::format("field 6 ('blur_samples'): '{}' is not a count >= 1", samples));
    }
    f.samples = static_cast<int>(samples);
    frames.push_back(f);
  }
  MRVS_RETURN_IF_ERROR(reader.status());
  return frames;
}

Status write_illumination_yaml(const std::filesystem::path& path, const Illumination& light) {
  return write_file_atomically(
      path,
      fmt::format("# The scene's light (render.dim_area): light(p) = 1 - (1 - level) exp(-d^2 / (2 "
                  "radius_m^2)),\n# d the horizontal distance of p from centre_xy (world, m).\n"
                  "enabled: {}\ncentre_xy: [{}, {}]\nlevel: {}\nradius_m: {}\n",
                  light.enabled, light.centre_xy.x(), light.centre_xy.y(), light.level, light.radius_m));
}

StatusOr<Illumination> read_illumination_yaml(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(const config::YamlDocument doc, config::load_yaml_file(path));
  Illumination light;
  try {
    light.enabled = doc.root["enabled"].as<bool>();
    const auto xy = doc.root["centre_xy"].as<std::vector<float>>();
    if (xy.size() != 2) throw YAML::Exception(YAML::Mark::null_mark(), "centre_xy needs 2 values");
    light.centre_xy = Eigen::Vector2f(xy[0], xy[1]);
    light.level = doc.root["level"].as<float>();
    light.radius_m = doc.root["radius_m"].as<float>();
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(
        fmt::format("{}: needs enabled, centre_xy [x, y], level and radius_m ({})", path.string(), e.what()));
  }
  return light;
}

}  // namespace mrvs::sim
