// The internal brick index (cloud_server/query/src/level_index.h): every voxel lookup agrees
// with a plain hash map, with the dense brick bitmap and with the hash table alone.
#include <random>

#include <gtest/gtest.h>

#include "level_index.h"
#include "query_test_maps.h"

namespace mrvs::map::test {
namespace {

void expect_lookups_match(const detail::LevelIndex& index, const MapLevel& level, std::uint64_t seed) {
  const ReferenceLevel reference(level);
  // Every stored point is found at its voxel, with its own position.
  for (std::size_t i = 0; i < level.points.size(); ++i) {
    const voxel::VoxelIndex v = *voxel_of(level.points[i].position, level.resolution);
    const std::uint32_t sorted = index.find_voxel(v.x(), v.y(), v.z());
    ASSERT_NE(sorted, detail::kNoBrick);
    EXPECT_EQ(index.original_index(sorted), i);
    EXPECT_EQ(index.position(sorted), level.points[i].position);
  }
  // Random voxels near the points: occupied exactly when the reference says so.
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, level.points.size() - 1);
  std::uniform_int_distribution<int> offset(-12, 12);
  for (int k = 0; k < 200000; ++k) {
    const voxel::VoxelIndex v = *voxel_of(level.points[pick(rng)].position, level.resolution) +
                                voxel::VoxelIndex(offset(rng), offset(rng), offset(rng));
    const std::uint32_t sorted = index.find_voxel(v.x(), v.y(), v.z());
    const std::int64_t expected = reference.find(v);
    ASSERT_EQ(sorted == detail::kNoBrick, expected < 0);
    if (expected >= 0) {
      EXPECT_EQ(index.original_index(sorted), static_cast<std::uint32_t>(expected));
    }
  }
}

TEST(LevelIndex, SmallMapUsesTheDenseBitmapAndFindsEveryVoxel) {
  const VoxelMap map = random_map({0.01}, 0.5, 60, 3000, 41);
  const StatusOr<detail::LevelIndex> index = detail::LevelIndex::build(map.levels[0], 0);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_TRUE(index->has_dense_bitmap());
  EXPECT_EQ(index->point_count(), map.levels[0].points.size());
  expect_lookups_match(*index, map.levels[0], 1);
}

TEST(LevelIndex, WideMapUsesTheHashTableAloneAndFindsEveryVoxel) {
  VoxelMap map = random_map({0.01}, 0.5, 60, 3000, 43);
  map.levels[0].points.push_back(MapPoint{Eigen::Vector3f(-4000.0f, -4000.0f, -4000.0f)});
  map.levels[0].points.push_back(MapPoint{Eigen::Vector3f(4000.0f, 4000.0f, 4000.0f)});
  const StatusOr<detail::LevelIndex> index = detail::LevelIndex::build(map.levels[0], 0);
  ASSERT_TRUE(index.ok()) << index.status();
  EXPECT_FALSE(index->has_dense_bitmap());
  expect_lookups_match(*index, map.levels[0], 2);
}

TEST(LevelIndex, BrickMaskRankCountsLowerBits) {
  detail::BrickMask mask;
  std::mt19937_64 rng(5);
  std::bernoulli_distribution set(0.3);
  for (int bit = 0; bit < 512; ++bit)
    if (set(rng)) mask.words[static_cast<std::size_t>(bit >> 6)] |= std::uint64_t{1} << (bit & 63);
  std::uint32_t below = 0;
  for (int bit = 0; bit < 512; ++bit) {
    EXPECT_EQ(mask.rank(bit), below);
    below += mask.test(bit) ? 1 : 0;
  }
}

}  // namespace
}  // namespace mrvs::map::test
