#include <gtest/gtest.h>

#include "mrvs/voxel/resolution.h"

namespace mrvs::voxel {
namespace {

// algorithm.md 2.3: EuRoC (f ~ 458): 0.01 m below 6.9 m, 0.02 m to 11.5 m, 0.03 m beyond;
// KAIST (f ~ 815): 0.05 below 61 m, 0.10 to 102 m, 0.15 to 143 m, 0.20 beyond.
TEST(Resolution, SwitchDepthsOfTheDesignNotes) {
  const std::vector<double> indoor = {0.01, 0.02, 0.03};
  const double f = 458.0;
  EXPECT_NEAR(switch_depth(0.01, 0.02, f), 6.87, 1e-9);
  EXPECT_NEAR(switch_depth(0.02, 0.03, f), 11.45, 1e-9);
  EXPECT_EQ(*select_level(indoor, 0.3, f), 0u);
  EXPECT_EQ(*select_level(indoor, 6.86, f), 0u);
  EXPECT_EQ(*select_level(indoor, 6.88, f), 1u);
  EXPECT_EQ(*select_level(indoor, 11.44, f), 1u);
  EXPECT_EQ(*select_level(indoor, 11.46, f), 2u);
  EXPECT_EQ(*select_level(indoor, 100.0, f), 2u);
  const std::vector<double> outdoor = {0.05, 0.10, 0.15, 0.20};
  const double g = 815.0;
  EXPECT_EQ(*select_level(outdoor, 61.0, g), 0u);
  EXPECT_EQ(*select_level(outdoor, 61.2, g), 1u);
  EXPECT_EQ(*select_level(outdoor, 101.8, g), 1u);
  EXPECT_EQ(*select_level(outdoor, 102.1, g), 2u);
  EXPECT_EQ(*select_level(outdoor, 142.5, g), 2u);
  EXPECT_EQ(*select_level(outdoor, 143.0, g), 3u);
}

TEST(Resolution, TiesGoToTheEarlierLevelAndOrderIsTheListsOrder) {
  // Footprint 0.375 exactly between 0.25 and 0.5 (binary-exact values, a true tie): the
  // strict comparison keeps the first level of the list.
  EXPECT_EQ(*select_level({0.25, 0.5}, 375.0, 1000.0), 0u);
  EXPECT_EQ(*select_level({0.5, 0.25}, 375.0, 1000.0), 0u);
  EXPECT_EQ(*select_level({0.05}, 1000.0, 1.0), 0u);  // a single level is always chosen
}

TEST(Resolution, InvalidInputsGiveNothing) {
  EXPECT_FALSE(select_level({}, 1.0, 458.0).has_value());
  EXPECT_FALSE(select_level({0.01}, 0.0, 458.0).has_value());
  EXPECT_FALSE(select_level({0.01}, -1.0, 458.0).has_value());
  EXPECT_FALSE(select_level({0.01}, 1.0, 0.0).has_value());
  EXPECT_FALSE(select_level({0.01}, std::nan(""), 458.0).has_value());
  EXPECT_FALSE(select_level({0.01}, INFINITY, 458.0).has_value());
}

TEST(Resolution, FindLevelMatchesFloat32ResolutionsOnly) {
  const std::vector<double> levels = {0.01, 0.02, 0.03};
  EXPECT_EQ(*find_level(levels, static_cast<double>(0.02f)), 1u);  // as sent on the wire
  EXPECT_EQ(*find_level(levels, 0.0300001), 2u);
  EXPECT_FALSE(find_level(levels, 0.015).has_value());
  EXPECT_FALSE(find_level(levels, 0.0201).has_value());
  EXPECT_FALSE(find_level(levels, 0.0).has_value());
  EXPECT_FALSE(find_level(levels, std::nan("")).has_value());
  EXPECT_FALSE(find_level({}, 0.01).has_value());
}

}  // namespace
}  // namespace mrvs::voxel
