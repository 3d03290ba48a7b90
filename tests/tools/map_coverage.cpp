// map_coverage: how much of a generated sequence's true surface a built voxel map covers at
// one level (issue 31: the 0.01 m level at least 90 % occupied on the surfaces within 3 m of
// the camera path). Rebuilds the sequence's world (scene, camera path, T_map_world) from its
// sim0/ files, takes the true surface voxels (mrvs/sim/surface_coverage.h) and counts those
// the map's level holds a point in; prints KEY: value lines, with 1 m distance bins.
//
//   map_coverage --dataset SEQ --map SEQ.mrvm [--resolution 0.01] [--within 3] [--whole-trajectory]
// Exit codes: 0 done, 1 data error, 2 usage error.
#include <algorithm>
#include <cstdio>
#include <unordered_set>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/core/cli.h"
#include "mrvs/map/map_file.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/surface_coverage.h"
#include "mrvs/voxel/voxel_key.h"

namespace {

struct Args {
  std::string dataset, map;
  double resolution = 0.01;
  double within_m = 3.0;
  bool whole = false;
  std::string log_level = "warn";
};

/// cam0's centre at every frame of the sequence (or every 50 ms of the whole source
/// trajectory), thinned to 5 cm steps.
mrvs::StatusOr<std::vector<mrvs::Vec3d>> camera_path(const mrvs::sim::World& world, bool whole) {
  std::vector<mrvs::TimestampNs> times = world.grid.camera_true_ns;
  if (whole) {
    times.clear();
    for (auto t = world.spline->support_begin_ns(); t <= world.spline->support_end_ns(); t += 50'000'000) {
      times.push_back(t);
    }
  }
  std::vector<mrvs::Vec3d> path;
  for (const mrvs::TimestampNs t : times) {
    MRVS_ASSIGN_OR_RETURN(const auto kin, world.spline->evaluate(t));
    const mrvs::Vec3d p = (kin.T_w_b * world.calibration.cameras[0].T_b_c).translation();
    if (path.empty() || (p - path.back()).norm() >= 0.05) path.push_back(p);
  }
  return path;
}

mrvs::StatusOr<std::unordered_set<std::uint64_t>> level_keys(const mrvs::map::VoxelMap& map,
                                                             double resolution) {
  const int level = map.level_of(resolution);
  if (level < 0) {
    return absl::InvalidArgumentError(
        fmt::format("the map has no {} m level (it has {})", resolution, fmt::join(map.resolutions(), ", ")));
  }
  std::unordered_set<std::uint64_t> keys;
  for (const auto& p : map.levels[static_cast<std::size_t>(level)].points) {
    if (const auto index = mrvs::map::voxel_of(p.position, resolution))
      keys.insert(mrvs::voxel::pack(*index));
  }
  return keys;
}

mrvs::Status run(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const mrvs::sim::GeneratorRequest request,
                        mrvs::sim::load_generator_request(a.dataset));
  MRVS_ASSIGN_OR_RETURN(const mrvs::sim::World world, mrvs::sim::build_world(request));
  MRVS_ASSIGN_OR_RETURN(const mrvs::map::VoxelMap map, mrvs::map::load_voxel_map(a.map));
  MRVS_ASSIGN_OR_RETURN(const auto keys, level_keys(map, a.resolution));
  MRVS_ASSIGN_OR_RETURN(const auto path, camera_path(world, a.whole));
  MRVS_ASSIGN_OR_RETURN(const auto surface,
                        mrvs::sim::true_surface_voxels(*world.scene, path, world.map.T_map_world, map.origin,
                                                       a.resolution, a.within_m));
  const int bins = static_cast<int>(std::ceil(a.within_m));
  std::vector<std::int64_t> total(static_cast<std::size_t>(bins), 0), hit(total.size(), 0);
  for (const auto& v : surface) {
    const auto b = static_cast<std::size_t>(std::clamp(static_cast<int>(v.distance_m), 0, bins - 1));
    ++total[b];
    hit[b] += keys.count(v.key) ? 1 : 0;
  }
  std::int64_t all = 0, covered = 0;
  for (int b = 0; b < bins; ++b) {
    all += total[static_cast<std::size_t>(b)];
    covered += hit[static_cast<std::size_t>(b)];
    fmt::print("COVERAGE_{}_{}M: {:.4f} ({} of {})\n", b, b + 1,
               total[static_cast<std::size_t>(b)]
                   ? static_cast<double>(hit[static_cast<std::size_t>(b)]) /
                         static_cast<double>(total[static_cast<std::size_t>(b)])
                   : 0.0,
               hit[static_cast<std::size_t>(b)], total[static_cast<std::size_t>(b)]);
  }
  fmt::print("RESOLUTION_M: {}\nWITHIN_M: {}\nSURFACE_VOXELS: {}\nCOVERED_VOXELS: {}\nCOVERAGE: {:.4f}\n",
             a.resolution, a.within_m, all, covered,
             all ? static_cast<double>(covered) / static_cast<double>(all) : 0.0);
  fmt::print("MAP_LEVEL_POINTS: {}\nRAW_POINTS: {}\n", keys.size(), map.raw_point_count);
  return absl::OkStatus();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Share of a generated sequence's true surface voxels that a voxel map's level holds.",
               "map_coverage"};
  Args a;
  app.add_option("--dataset", a.dataset, "Generated EuRoC folder (with sim0/)")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--map", a.map, "Voxel map built from it (.mrvm)")->required()->check(CLI::ExistingFile);
  app.add_option("--resolution", a.resolution, "Level, m")->check(CLI::PositiveNumber);
  app.add_option("--within", a.within_m, "Surfaces within this distance of the camera path, m")
      ->check(CLI::PositiveNumber);
  app.add_flag("--whole-trajectory", a.whole,
               "The camera path of the whole source trajectory, not the window's");
  mrvs::add_log_level_option(app, a.log_level);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, a.log_level)) return *exit_code;
  const mrvs::Status status = run(a);
  if (!status.ok()) {
    fmt::print(stderr, "map_coverage: {}\n", std::string(status.message()));
    return mrvs::kExitDataError;
  }
  return 0;
}
