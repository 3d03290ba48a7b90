// balance_layer (the coarse search's floor cap) against brute force: the dominant layer is the
// 3-bin height window with the most points, the cap keeps every other point first and the layer
// at share / (1 - share) of them (at least kMinLayerPoints), and without a cap (or under it) the
// points are the plain even spread.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "layer_balance.h"

namespace mrvs::localise {
namespace {

/// A floor of `floor_n` points at z = -1.4 (+- 1 cm) and `wall_n` points spread over 0..2.5 m above it.
std::vector<Eigen::Vector3d> floor_and_walls(int floor_n, int wall_n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-3.0, 3.0), dz(-0.01, 0.01), up(0.1, 2.5);
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < floor_n; ++i) p.emplace_back(xy(rng), xy(rng), -1.4 + dz(rng));
  for (int i = 0; i < wall_n; ++i) p.emplace_back(3.0, xy(rng), -1.4 + up(rng));
  std::shuffle(p.begin(), p.end(), rng);
  return p;
}

/// Brute force: the most points in any window of kLayerBins bins.
std::size_t brute_layer(const std::vector<Eigen::Vector3d>& p) {
  std::size_t best = 0;
  for (int first = -200; first <= 200; ++first) {
    std::size_t n = 0;
    for (const auto& x : p) {
      const int b = static_cast<int>(std::floor(x.z() / kLayerBinM));
      n += (b >= first && b < first + kLayerBins) ? 1 : 0;
    }
    best = std::max(best, n);
  }
  return best;
}

std::size_t on_floor(const std::vector<Eigen::Vector3d>& p) {
  return static_cast<std::size_t>(std::count_if(
      p.begin(), p.end(), [](const Eigen::Vector3d& x) { return std::abs(x.z() + 1.4) < 0.05; }));
}

bool all_from(const std::vector<Eigen::Vector3d>& out, const std::vector<Eigen::Vector3d>& in) {
  return std::all_of(out.begin(), out.end(), [&](const Eigen::Vector3d& x) {
    return std::find(in.begin(), in.end(), x) != in.end();
  });
}

TEST(LayerBalance, AFloorOfManyPointsIsCappedAndEveryWallPointKept) {
  const auto p = floor_and_walls(3000, 60, 1);
  const LayerBalance b = balance_layer(p, 500, 0.3);
  EXPECT_EQ(b.layer_points, brute_layer(p));
  EXPECT_EQ(b.layer_points, on_floor(p));  // the walls start 10 cm above the floor's window
  ASSERT_TRUE(b.capped);
  EXPECT_EQ(b.points.size() - on_floor(b.points), 60u);  // every wall point
  EXPECT_EQ(on_floor(b.points), kMinLayerPoints);        // 0.3 / 0.7 * 60 = 26 < the least kept
  EXPECT_TRUE(all_from(b.points, p));
  // More wall points: the layer gets share / (1 - share) of them, the walls (1 - share) of the total.
  const auto q = floor_and_walls(3000, 1000, 2);
  const LayerBalance c = balance_layer(q, 500, 0.3);
  ASSERT_TRUE(c.capped);
  EXPECT_EQ(c.points.size() - on_floor(c.points), 350u);
  EXPECT_EQ(on_floor(c.points), 150u);
  EXPECT_TRUE(all_from(c.points, q));
}

TEST(LayerBalance, UnderTheShareOrWithoutACapThePointsAreThePlainSpread) {
  const auto p = floor_and_walls(400, 600, 3);  // floor 40 %
  for (const double share : {0.5, 1.0}) {
    const LayerBalance b = balance_layer(p, 300, share);
    EXPECT_FALSE(b.capped);
    ASSERT_EQ(b.points.size(), 300u);
    for (std::size_t i = 0; i < 300; ++i) EXPECT_EQ(b.points[i], p[i * p.size() / 300]) << i;
  }
  // Fewer points than asked for: all of them.
  EXPECT_EQ(balance_layer(p, 5000, 1.0).points.size(), p.size());
  // A cap below the floor's share applies.
  EXPECT_TRUE(balance_layer(p, 300, 0.3).capped);
  EXPECT_TRUE(balance_layer({}, 300, 0.3).points.empty());
}

}  // namespace
}  // namespace mrvs::localise
