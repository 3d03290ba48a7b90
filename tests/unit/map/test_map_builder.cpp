// build_voxel_map: cross-level consistency, per-voxel argmax, determinism, origin, errors.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "map_test_util.h"
#include "mrvs/map/map_builder.h"
#include "mrvs/map/map_file.h"
#include "mrvs/map/saliency.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map {
namespace {

using ::testing::HasSubstr;

std::uint64_t key_of(const Eigen::Vector3f& p, double r) {
  const auto index = voxel_of(p, r);
  EXPECT_TRUE(index.has_value());
  return index ? voxel::pack(*index) : 0;
}

/// Bit pattern of a point, for set membership.
using Bits = std::tuple<float, float, float, float, float>;
Bits bits(const MapPoint& p) {
  return {p.position.x(), p.position.y(), p.position.z(), p.intensity, p.saliency};
}

TEST(MapBuilder, CrossLevelConsistencyOnARandomCloud) {
  const RawCloud cloud = test::random_cloud(30000, 11, 0.6, Eigen::Vector3d(10.3, -4.2, 1.7));
  MapBuilderOptions options;
  options.levels = {0.07, 0.02, 0.03, 0.05};  // any order; non-nested grids
  BuildReport report;
  auto map = build_voxel_map(cloud, options, &report);
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_EQ(map->levels.size(), 4u);
  EXPECT_EQ(map->resolutions(), (std::vector<double>{0.02, 0.03, 0.05, 0.07}));
  EXPECT_TRUE(validate_voxel_map(*map, "built").ok());  // includes one point per voxel per level

  const std::vector<MapPoint>& fine = map->levels[0].points;
  std::set<Bits> fine_bits;
  for (const MapPoint& p : fine) fine_bits.insert(bits(p));
  for (std::size_t l = 1; l < map->levels.size(); ++l) {
    const double r = map->levels[l].resolution;
    // Every coarse point is a fine point, bit for bit.
    for (const MapPoint& p : map->levels[l].points) EXPECT_EQ(fine_bits.count(bits(p)), 1u) << "level " << l;
    // Each coarse voxel holding fine points has exactly one coarse point: the max-saliency one.
    std::map<std::uint64_t, float> best;
    for (const MapPoint& p : fine) {
      auto [it, inserted] = best.emplace(key_of(p.position, r), p.saliency);
      if (!inserted) it->second = std::max(it->second, p.saliency);
    }
    ASSERT_EQ(map->levels[l].points.size(), best.size()) << "level " << l;
    for (const MapPoint& p : map->levels[l].points) EXPECT_EQ(p.saliency, best.at(key_of(p.position, r)));
  }
  // Report.
  EXPECT_EQ(report.raw_points, cloud.size());
  ASSERT_EQ(report.levels.size(), 4u);
  for (std::size_t l = 0; l < 4; ++l) EXPECT_EQ(report.levels[l].points, map->levels[l].points.size());
  EXPECT_EQ(report.map_points, map->point_count());
  EXPECT_EQ(report.map_bytes, serialize_voxel_map(*map)->size());
  EXPECT_EQ(report.raw_bytes, cloud.size() * 28);
  EXPECT_GT(report.peak_memory_bytes, 0u);
  EXPECT_GE(report.seconds_total, report.seconds_saliency);
  EXPECT_THAT(report.summary(), HasSubstr("level 3: resolution 0.07 m"));
}

TEST(MapBuilder, FinestLevelIsTheArgmaxRawPointPerVoxel) {
  const RawCloud cloud = test::random_cloud(8000, 5, 0.3, Eigen::Vector3d(0.5, 0.5, 0.5));
  MapBuilderOptions options;
  options.levels = {0.02};
  auto map = build_voxel_map(cloud, options);
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_EQ(map->origin, Vec3d(0.0, 0.0, 0.0));
  // Independent saliency of the raw points (same local positions and options).
  std::vector<Eigen::Vector3f> local;
  for (const Vec3d& p : cloud.positions) local.push_back((p - map->origin).cast<float>());
  auto s = compute_saliency(local, cloud.intensities, SaliencyOptions{});
  ASSERT_TRUE(s.ok());
  std::map<std::uint64_t, std::size_t> winner;  // voxel -> raw index
  for (std::size_t i = 0; i < local.size(); ++i) {
    auto [it, inserted] = winner.emplace(key_of(local[i], 0.02), i);
    if (!inserted && (*s)[i] > (*s)[it->second]) it->second = i;  // ties keep the lower index
  }
  ASSERT_EQ(map->levels[0].points.size(), winner.size());
  for (const MapPoint& p : map->levels[0].points) {
    const std::size_t i = winner.at(key_of(p.position, 0.02));
    EXPECT_TRUE(test::same_bits(p, MapPoint{local[i], cloud.intensities[i], (*s)[i]}));
  }
}

TEST(MapBuilder, TiesGoToTheLowestRawIndex) {
  // Uniform intensity: every saliency is 0, so the finest level keeps the first raw point of each
  // voxel, and each coarser level the first (in raw order) of the finest points inside it.
  RawCloud cloud = test::random_cloud(3000, 9, 0.2, Eigen::Vector3d::Zero());
  std::fill(cloud.intensities.begin(), cloud.intensities.end(), 0.5f);
  MapBuilderOptions options;
  options.levels = {0.03, 0.05};
  auto map = build_voxel_map(cloud, options);
  ASSERT_TRUE(map.ok()) << map.status();
  std::vector<Eigen::Vector3f> candidates;  // raw order
  for (const Vec3d& p : cloud.positions) candidates.push_back((p - map->origin).cast<float>());
  for (const MapLevel& level : map->levels) {
    std::map<std::uint64_t, Eigen::Vector3f> first;
    for (const Eigen::Vector3f& p : candidates) first.emplace(key_of(p, level.resolution), p);
    ASSERT_EQ(level.points.size(), first.size());
    for (const MapPoint& p : level.points) {
      EXPECT_EQ(p.position, first.at(key_of(p.position, level.resolution)));
      EXPECT_EQ(p.saliency, 0.0f);
    }
    // The next level chooses among this level's winners, still in raw order.
    std::vector<Eigen::Vector3f> winners;
    for (const Eigen::Vector3f& p : candidates) {
      const auto it = first.find(key_of(p, level.resolution));
      if (it->second == p) winners.push_back(p);
    }
    candidates = winners;
  }
}

TEST(MapBuilder, DeterministicForAnyThreadCount) {
  const RawCloud cloud = test::random_cloud(40000, 21, 0.8, Eigen::Vector3d(-3.0, 2.0, 0.0));
  MapBuilderOptions one;
  one.threads = 1;
  MapBuilderOptions two;
  two.threads = 2;
  auto a = build_voxel_map(cloud, one);
  auto b = build_voxel_map(cloud, two);
  ASSERT_TRUE(a.ok() && b.ok());
  auto bytes_a = serialize_voxel_map(*a);
  auto bytes_b = serialize_voxel_map(*b);
  ASSERT_TRUE(bytes_a.ok() && bytes_b.ok());
  EXPECT_TRUE(*bytes_a == *bytes_b);
}

TEST(MapBuilder, UtmCloudKeepsMillimetres) {
  // Two planes of points around (332000, 4140000, 20) with sub-mm offsets.
  RawCloud cloud;
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 60; ++j) {
      cloud.positions.emplace_back(332000.0 + 0.01 * i + 0.00037, 4140000.0 + 0.01 * j + 0.00071,
                                   20.0 + 0.0001 * ((i * 7 + j * 3) % 11));
      cloud.intensities.push_back(static_cast<float>((i / 10 + j / 10) % 2));
    }
  }
  MapBuilderOptions options;
  options.levels = {0.05, 0.10, 0.15, 0.20};
  auto map = build_voxel_map(cloud, options);
  ASSERT_TRUE(map.ok()) << map.status();
  EXPECT_EQ(map->origin, Vec3d(332000.0, 4140000.0, 20.0));
  // Every stored point reconstructs a raw point to well under a millimetre.
  for (const MapLevel& level : map->levels) {
    for (const MapPoint& p : level.points) {
      const Vec3d world = map->origin + p.position.cast<double>();
      double nearest = 1e9;
      for (const Vec3d& q : cloud.positions) nearest = std::min(nearest, (q - world).norm());
      EXPECT_LT(nearest, 1e-6);
    }
  }
}

TEST(MapBuilder, OriginIsTheFlooredBoundingBoxMinimum) {
  auto origin = map_origin({Vec3d(3.7, -2.2, 0.0), Vec3d(1.5, 4.0, -0.1)}, 1.0);
  ASSERT_TRUE(origin.ok());
  EXPECT_EQ(*origin, Vec3d(1.0, -3.0, -1.0));
  origin = map_origin({Vec3d(332017.3, 4140023.9, 21.2)}, 10.0);
  ASSERT_TRUE(origin.ok());
  EXPECT_EQ(*origin, Vec3d(332010.0, 4140020.0, 20.0));
  EXPECT_FALSE(map_origin({}, 1.0).ok());
}

TEST(MapBuilder, LevelsAreSortedDistinctAndPositive) {
  auto sorted = sorted_levels({0.3, 0.1, 0.2});
  ASSERT_TRUE(sorted.ok());
  EXPECT_EQ(*sorted, (std::vector<double>{0.1, 0.2, 0.3}));
  EXPECT_THAT(std::string(sorted_levels({0.1, 0.2, 0.1}).status().message()), HasSubstr("given twice"));
  EXPECT_FALSE(sorted_levels({0.1, -0.2}).ok());
  EXPECT_FALSE(sorted_levels({0.1, std::nan("")}).ok());
  EXPECT_FALSE(sorted_levels({}).ok());

  const RawCloud cloud = test::random_cloud(100, 1, 0.1, Eigen::Vector3d::Zero());
  MapBuilderOptions dup;
  dup.levels = {0.02, 0.02};
  EXPECT_FALSE(build_voxel_map(cloud, dup).ok());
  MapBuilderOptions negative;
  negative.levels = {-0.02};
  auto bad = build_voxel_map(cloud, negative);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr("builder.levels"));
}

TEST(MapBuilder, ExtentTooLargeForTheResolution) {
  RawCloud cloud;
  cloud.positions = {Vec3d(0.0, 0.0, 0.0), Vec3d(0.5, 0.0, 0.0), Vec3d(30000.0, 0.0, 0.0)};  // 30 km at 1 cm
  cloud.intensities = {0.0f, 1.0f, 0.5f};
  MapBuilderOptions options;
  auto map = build_voxel_map(cloud, options);
  ASSERT_FALSE(map.ok());
  EXPECT_THAT(std::string(map.status().message()),
              HasSubstr("map extent is too large for resolution 0.01 m"));
  options.levels = {0.05};  // +-52 km at 5 cm: fine
  EXPECT_TRUE(build_voxel_map(cloud, options).ok());
}

TEST(MapBuilder, InvalidClouds) {
  MapBuilderOptions options;
  EXPECT_FALSE(build_voxel_map(RawCloud{}, options).ok());
  RawCloud mismatch = test::random_cloud(10, 1, 1.0, Eigen::Vector3d::Zero());
  mismatch.intensities.pop_back();
  EXPECT_FALSE(build_voxel_map(mismatch, options).ok());
  RawCloud nan = test::random_cloud(10, 1, 1.0, Eigen::Vector3d::Zero());
  nan.positions[3].y() = std::nan("");
  EXPECT_FALSE(build_voxel_map(nan, options).ok());
  MapBuilderOptions bad_k;
  bad_k.knn = 0;
  auto r = build_voxel_map(test::random_cloud(10, 1, 1.0, Eigen::Vector3d::Zero()), bad_k);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(std::string(r.status().message()), HasSubstr("builder.knn"));
}

TEST(MapBuilder, DescriptionRecordsTheBuild) {
  RawCloud cloud = test::random_cloud(500, 2, 0.2, Eigen::Vector3d::Zero());
  cloud.source = "scan.ply";
  auto map = build_voxel_map(cloud, MapBuilderOptions{});
  ASSERT_TRUE(map.ok());
  EXPECT_EQ(map->raw_point_count, 500u);
  EXPECT_THAT(map->description, HasSubstr("scan.ply"));
  EXPECT_THAT(map->description, HasSubstr("knn: 16"));
  EXPECT_THAT(map->description, HasSubstr("levels: [0.01, 0.02, 0.03]"));
}

}  // namespace
}  // namespace mrvs::map
