// map_builder end to end, the config files, and VoxelMap's small helpers.
#include <cmath>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "map_test_util.h"
#include "mrvs/config/options.h"
#include "mrvs/map/map_builder.h"
#include "mrvs/map/map_file.h"
#include "mrvs/map/query_engine.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::map {
namespace {

using mrvs::test::quoted;
using mrvs::test::run_tool;
using mrvs::test::value_of;
using ::testing::HasSubstr;

const std::filesystem::path kConfigDir = MRVS_CONFIG_DIR;

/// A small cloud on two planes with intensity patterns, written as the simulator writes its
/// pointcloud0/data.ply (binary little-endian, float x y z intensity).
std::filesystem::path write_small_cloud(const mrvs::test::TempDir& dir) {
  std::vector<sim::MapPoint> points;
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 60; ++j) {
      sim::MapPoint floor;
      floor.position =
          Eigen::Vector3f(0.004f * i, 0.004f * j, 0.001f * static_cast<float>((i * 13 + j * 7) % 5));
      floor.intensity = static_cast<float>(((i / 8) + (j / 8)) % 2);
      points.push_back(floor);
      sim::MapPoint wall;
      wall.position = Eigen::Vector3f(0.004f * i, 0.3f, 0.004f * j);
      wall.intensity = static_cast<float>((i / 5) % 2) * 0.5f;
      points.push_back(wall);
    }
  }
  const std::filesystem::path path = dir / "cloud.ply";
  EXPECT_TRUE(sim::write_ply(path, points, "map_builder test cloud").ok());
  return path;
}

TEST(MapBuilderTool, BuildsAMapThatLoads) {
  mrvs::test::TempDir dir;
  const auto cloud = write_small_cloud(dir);
  const auto r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(cloud) + " --config " +
                                                quoted(kConfigDir / "map_indoor.yaml") + " --out " +
                                                quoted(dir / "out" / "map.mrvm") + " --log-level warn");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto map = load_voxel_map(dir / "out" / "map.mrvm");
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_EQ(map->levels.size(), 3u);
  EXPECT_EQ(value_of(r.output, "RAW_POINTS"), 7200.0);
  EXPECT_EQ(value_of(r.output, "LEVELS"), 3.0);
  for (std::size_t l = 0; l < 3; ++l) {
    EXPECT_EQ(value_of(r.output, fmt::format("LEVEL_{}_RESOLUTION_M", l)), map->levels[l].resolution);
    EXPECT_EQ(value_of(r.output, fmt::format("LEVEL_{}_POINTS", l)),
              static_cast<double>(map->levels[l].points.size()));
    EXPECT_GT(map->levels[l].points.size(), 0u);
  }
  EXPECT_EQ(map->resolutions(), (std::vector<double>{0.01, 0.02, 0.03}));
  EXPECT_EQ(value_of(r.output, "MAP_POINTS"), static_cast<double>(map->point_count()));
  EXPECT_EQ(value_of(r.output, "MAP_BYTES"), static_cast<double>(map_file_size(*map)));
  EXPECT_GT(value_of(r.output, "PEAK_MEMORY_MIB"), 0.0);
  EXPECT_GE(value_of(r.output, "SECONDS_TOTAL"), 0.0);
  EXPECT_GT(value_of(r.output, "BYTE_RATIO"), 0.0);
  EXPECT_EQ(map->raw_point_count, 7200u);
  EXPECT_THAT(map->description, HasSubstr("cloud.ply"));
  EXPECT_THAT(map->description, HasSubstr("map_indoor.yaml"));

  // --set overrides the file; the outdoor file gives four levels.
  const auto r2 = run_tool(
      MRVS_MAP_BUILDER, "--input " + quoted(cloud) + " --config " + quoted(kConfigDir / "map_outdoor.yaml") +
                            " --set builder.levels=[0.05,0.1] --set builder.knn=8 --out " +
                            quoted(dir / "o.mrvm") + " --log-level warn");
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  auto outdoor = load_voxel_map(dir / "o.mrvm");
  ASSERT_TRUE(outdoor.ok());
  EXPECT_EQ(outdoor->resolutions(), (std::vector<double>{0.05, 0.1}));
}

TEST(MapBuilderTool, ExitCodes) {
  mrvs::test::TempDir dir;
  const auto cloud = write_small_cloud(dir);
  const std::string out = " --out " + quoted(dir / "m.mrvm");
  // Usage / config errors: 2.
  EXPECT_EQ(run_tool(MRVS_MAP_BUILDER, "--out x.mrvm").exit_code, 2);
  auto r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(cloud) + out + " --set builder.knn=0");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("builder.knn"));
  r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(cloud) + out + " --set builder.nearest=3");
  EXPECT_EQ(r.exit_code, 2);
  r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(cloud) + out + " --set builder.levels=[0.02,0.02]");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("given twice"));
  // Data errors: 1, nothing written.
  r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(dir / "missing.ply") + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.output, HasSubstr("missing.ply"));
  dir.write("bad.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_header\n1\n");
  r = run_tool(MRVS_MAP_BUILDER, "--input " + quoted(dir / "bad.ply") + out);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.output, HasSubstr("truncated"));
  EXPECT_FALSE(std::filesystem::exists(dir / "m.mrvm"));
}

TEST(MapConfigFiles, BuilderAndQuerySectionsLoad) {
  auto indoor = config::load_options_file<MapBuilderOptions>(kConfigDir / "map_indoor.yaml", "builder");
  ASSERT_TRUE(indoor.ok()) << indoor.status();
  EXPECT_EQ(indoor->levels, (std::vector<double>{0.01, 0.02, 0.03}));
  EXPECT_EQ(indoor->knn, 16);
  EXPECT_EQ(indoor->alpha, 1.0);
  auto outdoor = config::load_options_file<MapBuilderOptions>(kConfigDir / "map_outdoor.yaml", "builder");
  ASSERT_TRUE(outdoor.ok()) << outdoor.status();
  EXPECT_EQ(outdoor->levels, (std::vector<double>{0.05, 0.10, 0.15, 0.20}));
  EXPECT_EQ(outdoor->knn, 16);

  auto q_in = config::load_options_file<QueryOptions>(kConfigDir / "map_indoor.yaml", "query");
  ASSERT_TRUE(q_in.ok()) << q_in.status();
  EXPECT_EQ(q_in->search_range_m, 0.75);
  EXPECT_EQ(q_in->threshold_offset_px, 0.5);
  EXPECT_EQ(q_in->focal_length_px, 458.0);
  EXPECT_FALSE(q_in->refine_plane_intersection);  // the stored point measured better in VIO (decision 6)
  auto q_out = config::load_options_file<QueryOptions>(kConfigDir / "map_outdoor.yaml", "query");
  ASSERT_TRUE(q_out.ok()) << q_out.status();
  EXPECT_EQ(q_out->search_range_m, 1.5);
  EXPECT_EQ(q_out->threshold_offset_px, 1.5);
  EXPECT_EQ(q_out->focal_length_px, 816.0);
  EXPECT_FALSE(q_out->refine_plane_intersection);
}

TEST(VoxelMap, LevelOfResolutionsAndVoxelOf) {
  VoxelMap map;
  for (double r : {0.01, 0.02, 0.03}) map.levels.push_back(MapLevel{r, {}});
  map.levels[1].points.resize(4);
  EXPECT_EQ(map.level_of(0.01), 0);
  EXPECT_EQ(map.level_of(0.020001), 1);  // within a relative 1e-4
  EXPECT_EQ(map.level_of(0.0299985), 2);
  EXPECT_EQ(map.level_of(0.0201), -1);
  EXPECT_EQ(map.level_of(0.05), -1);
  EXPECT_EQ(map.level_of(0.0), -1);
  EXPECT_EQ(map.level_of(std::nan("")), -1);
  EXPECT_EQ(map.resolutions(), (std::vector<double>{0.01, 0.02, 0.03}));
  EXPECT_EQ(map.point_count(), 4u);
  EXPECT_EQ(VoxelMap{}.level_of(0.01), -1);

  EXPECT_EQ(*voxel_of(Eigen::Vector3f(0.015f, -0.001f, 0.0f), 0.01), voxel::VoxelIndex(1, -1, 0));
  EXPECT_FALSE(voxel_of(Eigen::Vector3f(1e5f, 0.0f, 0.0f), 0.01).has_value());  // beyond 2^20 voxels
  EXPECT_FALSE(voxel_of(Eigen::Vector3f(std::nanf(""), 0.0f, 0.0f), 0.01).has_value());
  EXPECT_FALSE(voxel_of(Eigen::Vector3f::Zero(), 0.0).has_value());
}

}  // namespace
}  // namespace mrvs::map
