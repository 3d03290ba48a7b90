// LikelihoodPyramid: the base level against the distance to the nearest occupied cell, every
// pyramid level against the brute-force maximum over its window (negative cells included).
#include <random>

#include <gtest/gtest.h>

#include "likelihood_grid.h"

namespace mrvs::localise {
namespace {

TEST(LikelihoodPyramid, BaseIsTheLikelihoodOfTheNearestOccupiedCell) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 2.0f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 40; ++i) pts.emplace_back(u(rng), u(rng), u(rng));
  const Eigen::AlignedBox3d box(Eigen::Vector3d::Zero(), Eigen::Vector3d::Constant(2.0));
  const auto g = LikelihoodPyramid::build(pts, box, 0.1, 1, 1.0);
  ASSERT_EQ(g.size(), Eigen::Vector3i::Constant(20));
  std::vector<Eigen::Vector3i> occ;
  for (const auto& p : pts) occ.push_back(g.cell_of(p.cast<double>()));
  for (int z = 0; z < 20; ++z) {
    for (int y = 0; y < 20; ++y) {
      for (int x = 0; x < 20; ++x) {
        int d2 = 1 << 30;
        for (const auto& o : occ) d2 = std::min(d2, (o - Eigen::Vector3i(x, y, z)).squaredNorm());
        const double expect = d2 <= 4 ? 255.0 * std::exp(-0.5 * d2) : 0.0;
        ASSERT_NEAR(g.value(0, {x, y, z}), expect, 0.51) << x << " " << y << " " << z;
      }
    }
  }
  EXPECT_EQ(g.value(0, {-1, 0, 0}), 0);
  EXPECT_EQ(g.value(0, {20, 0, 0}), 0);
}

TEST(LikelihoodPyramid, EveryLevelIsTheMaximumOverItsWindow) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.5f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 25; ++i) pts.emplace_back(u(rng), u(rng), 0.5f * u(rng));
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -1, -0.5), Eigen::Vector3d(1.5, 1.5, 0.75));
  const int levels = 4;
  const auto g = LikelihoodPyramid::build(pts, box, 0.1, levels, 1.0);
  ASSERT_EQ(g.levels(), levels);
  const Eigen::Vector3i n = g.size();
  for (int h = 1; h < levels; ++h) {
    const int w = 1 << h;
    for (int z = -w; z < n.z() + 1; ++z) {
      for (int y = -w; y < n.y() + 1; y += 2) {
        for (int x = -w; x < n.x() + 1; x += 3) {
          int best = 0;
          for (int dz = 0; dz < w; ++dz)
            for (int dy = 0; dy < w; ++dy)
              for (int dx = 0; dx < w; ++dx) best = std::max<int>(best, g.value(0, {x + dx, y + dy, z + dz}));
          ASSERT_EQ(g.value(h, {x, y, z}), best) << h << ": " << x << " " << y << " " << z;
        }
      }
    }
  }
}

TEST(LikelihoodPyramid, ACellClampedIntoTheGridReadsWhatValueReads) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.5f);
  std::vector<Eigen::Vector3f> pts;
  for (int i = 0; i < 60; ++i) pts.emplace_back(u(rng), u(rng), 0.5f * u(rng));
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-1, -1, -0.5), Eigen::Vector3d(1.5, 1.5, 0.75));
  for (int levels : {1, 2, 4}) {
    const auto g = LikelihoodPyramid::build(pts, box, 0.1, levels, 1.0);
    const Eigen::Vector3i n = g.size();
    const int far = (1 << levels) + 3;
    int nonzero = 0;
    for (int h = 0; h < levels; ++h) {
      for (int z = -far; z < n.z() + far; ++z) {
        for (int y = -far; y < n.y() + far; ++y) {
          for (int x = -far; x < n.x() + far; ++x) {
            const Eigen::Vector3i c(x, y, z);
            ASSERT_EQ(g.data(h)[g.clamped_linear(c)], g.value(h, c))
                << levels << " levels, level " << h << ": " << x << " " << y << " " << z;
            nonzero += g.value(h, c) > 0;
          }
        }
      }
    }
    EXPECT_GT(nonzero, 0);
  }
}

}  // namespace
}  // namespace mrvs::localise
