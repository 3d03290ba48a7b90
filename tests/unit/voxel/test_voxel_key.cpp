#include <random>
#include <set>

#include <gtest/gtest.h>

#include "mrvs/voxel/voxel_key.h"

namespace mrvs::voxel {
namespace {

TEST(VoxelKey, PackUnpackRoundTripOverTheWholeRange) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<std::int32_t> any(kMinIndex, kMaxIndex);
  std::set<std::uint64_t> keys;
  for (int i = 0; i < 100000; ++i) {
    const VoxelIndex v(any(rng), any(rng), any(rng));
    const std::uint64_t key = pack(v);
    ASSERT_EQ(unpack(key), v);
    ASSERT_EQ(key >> 63, 0u);
    keys.insert(key);
  }
  for (const VoxelIndex& v :
       {VoxelIndex(kMinIndex, kMinIndex, kMinIndex), VoxelIndex(kMaxIndex, kMaxIndex, kMaxIndex),
        VoxelIndex(-1, 0, 1), VoxelIndex(0, 0, 0)}) {
    EXPECT_EQ(unpack(pack(v)), v);
  }
  EXPECT_GT(keys.size(), 99990u);  // distinct indices, distinct keys (collisions of random draws only)
}

TEST(VoxelKey, NeighboursHaveDistinctKeys) {
  std::set<std::uint64_t> keys;
  for (int x = -1; x <= 1; ++x)
    for (int y = -1; y <= 1; ++y)
      for (int z = -1; z <= 1; ++z) keys.insert(pack(VoxelIndex(x, y, z)));
  EXPECT_EQ(keys.size(), 27u);
}

TEST(VoxelKey, IndexUsesFloorNotTruncation) {
  EXPECT_EQ(*index_of<double>(Eigen::Vector3d(0.005, -0.005, 0.0), 0.01), VoxelIndex(0, -1, 0));
  EXPECT_EQ(*index_of<double>(Eigen::Vector3d(-0.01, -0.0100001, 0.0299), 0.01), VoxelIndex(-1, -2, 2));
  EXPECT_EQ(*index_of<float>(Eigen::Vector3f(-2.5f, 2.5f, -0.0f), 1.0f), VoxelIndex(-3, 2, 0));
}

TEST(VoxelKey, OutOfRangeOrNonFiniteGivesNothing) {
  EXPECT_FALSE(index_of<double>(Eigen::Vector3d(1e6, 0, 0), 0.01).has_value());  // 1e8 cells
  EXPECT_FALSE(index_of<double>(Eigen::Vector3d(std::nan(""), 0, 0), 0.01).has_value());
  EXPECT_FALSE(index_of<double>(Eigen::Vector3d(0, INFINITY, 0), 0.01).has_value());
  EXPECT_TRUE(index_of<double>(Eigen::Vector3d(10000.0, -10000.0, 0), 0.01).has_value());  // +-10 km at 1 cm
  EXPECT_FALSE(packable(VoxelIndex(kMaxIndex + 1, 0, 0)));
  EXPECT_TRUE(packable(VoxelIndex(kMinIndex, 0, kMaxIndex)));
}

}  // namespace
}  // namespace mrvs::voxel
