// map_builder: builds the multi-resolution voxel map (.mrvm) from a raw LiDAR cloud with
// intensity (PLY or PCD). See cloud_server/map/include/mrvs/map/map_builder.h.
//
//   map_builder --input cloud.ply --config config/map_indoor.yaml --out map.mrvm
//       [--set builder.knn=20] [--log-level info]
//
// Reads only the `builder` section of the config file. Prints machine-readable "KEY: value"
// lines on stdout (per-level counts, timings, peak memory, compression); logs go to stderr.
// Exit codes: 0 success, 1 data error (input cloud, build or output), 2 usage or config error.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/config/options.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/map/map_builder.h"
#include "mrvs/map/map_file.h"
#include "mrvs/map/point_cloud_io.h"

namespace {

struct Args {
  std::string input;
  std::string config;
  std::string out;
  std::vector<std::string> overrides;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--input", a.input, "Raw point cloud with intensity: .ply (ascii/binary) or .pcd")
      ->required();
  app.add_option("--config", a.config,
                 "YAML file whose `builder` section holds the options, e.g. config/map_indoor.yaml "
                 "(default: the indoor defaults)")
      ->check(CLI::ExistingFile);
  app.add_option("--out", a.out, "Map file to write (.mrvm), replaced atomically")->required();
  app.add_option("--set", a.overrides,
                 "Override one option, e.g. --set builder.knn=20 --set builder.levels=[0.05,0.1] "
                 "--set builder.threads=1 (keys as printed at start-up)");
  mrvs::add_log_level_option(app, a.log_level);
}

mrvs::StatusOr<mrvs::map::MapBuilderOptions> resolve_options(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const mrvs::config::YamlDocument doc,
                        mrvs::config::load_yaml_with_overrides(a.config, a.overrides));
  MRVS_ASSIGN_OR_RETURN(mrvs::map::MapBuilderOptions options,
                        mrvs::config::load_options<mrvs::map::MapBuilderOptions>(doc, "builder"));
  MRVS_RETURN_IF_ERROR(mrvs::map::sorted_levels(options.levels).status());
  return options;
}

std::uint64_t file_size_or_zero(const std::string& path) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  return ec ? 0 : static_cast<std::uint64_t>(size);
}

void print_report(const Args& a, const mrvs::map::BuildReport& r, double seconds_read, double seconds_save,
                  double seconds_total) {
  fmt::print("INPUT: {}\nRAW_POINTS: {}\nORIGIN: {:.6f} {:.6f} {:.6f}\nLEVELS: {}\n", a.input, r.raw_points,
             r.origin.x(), r.origin.y(), r.origin.z(), r.levels.size());
  for (std::size_t l = 0; l < r.levels.size(); ++l) {
    fmt::print("LEVEL_{}_RESOLUTION_M: {}\nLEVEL_{}_POINTS: {}\n", l, r.levels[l].resolution, l,
               r.levels[l].points);
  }
  const std::uint64_t raw_file_bytes = file_size_or_zero(a.input);
  const std::uint64_t map_file_bytes = file_size_or_zero(a.out);
  fmt::print("MAP_POINTS: {}\nMAP_BYTES: {}\nRAW_FILE_BYTES: {}\n", r.map_points, map_file_bytes,
             raw_file_bytes);
  fmt::print(
      "POINT_RATIO: {:.6f}\nBYTE_RATIO: {:.6f}\n",
      static_cast<double>(r.map_points) / static_cast<double>(std::max<std::uint64_t>(r.raw_points, 1)),
      static_cast<double>(map_file_bytes) / static_cast<double>(std::max<std::uint64_t>(raw_file_bytes, 1)));
  fmt::print(
      "SECONDS_READ: {:.3f}\nSECONDS_SALIENCY: {:.3f}\nSECONDS_LEVELS: {:.3f}\nSECONDS_SAVE: {:.3f}\n"
      "SECONDS_TOTAL: {:.3f}\nPEAK_MEMORY_MIB: {:.1f}\nOUT: {}\n",
      seconds_read, r.seconds_saliency, r.seconds_levels, seconds_save, seconds_total,
      static_cast<double>(mrvs::map::peak_memory_bytes()) / (1024.0 * 1024.0), a.out);
}

int run(const Args& a) {
  using Clock = std::chrono::steady_clock;
  auto seconds = [](Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  const Clock::time_point t0 = Clock::now();
  auto options = resolve_options(a);
  if (!options.ok()) {
    fmt::print(stderr, "map_builder: error: {}\n", std::string(options.status().message()));
    return mrvs::kExitUsageError;
  }
  spdlog::info("map_builder options:\n{}", mrvs::config::options_to_yaml(*options, "builder"));
  auto cloud = mrvs::map::read_point_cloud(a.input);
  if (!cloud.ok()) {
    fmt::print(stderr, "map_builder: error: {}\n", std::string(cloud.status().message()));
    return mrvs::kExitDataError;
  }
  const double seconds_read = seconds(t0);
  spdlog::info("read {} points from '{}' (intensity: {}) in {:.2f} s; peak memory {} MiB", cloud->size(),
               a.input, cloud->intensity_field, seconds_read, mrvs::map::peak_memory_bytes() >> 20);
  mrvs::map::BuildReport report;
  auto map = mrvs::map::build_voxel_map(*cloud, *options, &report);
  if (!map.ok()) {
    fmt::print(stderr, "map_builder: error: {}\n", std::string(map.status().message()));
    return mrvs::kExitDataError;
  }
  map->description += fmt::format("; config: {}", a.config.empty() ? "<defaults>" : a.config);
  const Clock::time_point t_save = Clock::now();
  const mrvs::Status saved = mrvs::map::save_voxel_map(a.out, *map);
  if (!saved.ok()) {
    fmt::print(stderr, "map_builder: error: {}\n", std::string(saved.message()));
    return mrvs::kExitDataError;
  }
  const double seconds_save = seconds(t_save);
  spdlog::info("build summary:\n{}", report.summary());
  print_report(a, report, seconds_read, seconds_save, seconds(t0));
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Builds the multi-resolution voxel map (.mrvm) from a raw point cloud with intensity.",
               "map_builder"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
