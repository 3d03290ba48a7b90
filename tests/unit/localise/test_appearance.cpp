// The appearance check: Spearman's rank correlation against a brute-force definition (ranks by
// counting, Pearson of the ranks), invariant to any increasing map of either sample; and the
// correlation at the fine stage's inliers high where the submap's brightness follows the map's
// intensity and near zero where it does not.
#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "appearance.h"
#include "localise_scene.h"

namespace mrvs::localise {
namespace {

/// Rank of x[i] by counting (ties: the mean of the ranks they share), then Pearson.
double brute_force_spearman(const std::vector<double>& a, const std::vector<double>& b) {
  auto ranks = [](const std::vector<double>& x) {
    std::vector<double> r(x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      double below = 0.0, equal = 0.0;
      for (double y : x) {
        below += y < x[i];
        equal += y == x[i];
      }
      r[i] = below + 0.5 * (equal + 1.0);
    }
    return r;
  };
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double n = static_cast<double>(a.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += ra[i] / n;
    mb += rb[i] / n;
  }
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (ra[i] - ma) * (rb[i] - mb);
    saa += (ra[i] - ma) * (ra[i] - ma);
    sbb += (rb[i] - mb) * (rb[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

TEST(Appearance, RankCorrelationMatchesBruteForceWithTies) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> grey(0, 20);  // few values: many ties
  std::normal_distribution<double> noise(0.0, 4.0);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> a, b;
    for (int i = 0; i < 200; ++i) {
      a.push_back(grey(rng));
      b.push_back(trial % 2 ? a.back() + noise(rng) : static_cast<double>(grey(rng)));
    }
    EXPECT_NEAR(rank_correlation(a, b), brute_force_spearman(a, b), 1e-12) << trial;
  }
}

TEST(Appearance, RankCorrelationIgnoresIncreasingMapsAndFlipsForDecreasingOnes) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> a, up, down;
  for (int i = 0; i < 100; ++i) {
    a.push_back(u(rng));
    up.push_back(3.0 + 50.0 * std::pow(a.back(), 0.4));  // gain, offset, gamma
    down.push_back(-a.back());
  }
  EXPECT_NEAR(rank_correlation(a, up), 1.0, 1e-12);
  EXPECT_NEAR(rank_correlation(a, down), -1.0, 1e-12);
  EXPECT_EQ(rank_correlation(a, std::vector<double>(100, 2.0)), 0.0);  // constant: no evidence
  EXPECT_EQ(rank_correlation({1.0, 2.0}, {1.0, 2.0}), 0.0);            // too few
}

/// The bare 8 x 6 x 3 m room (a half turn fits its geometry exactly) textured by blob_albedo, its
/// 3 cm level as a MapSurface with intensity, and a submap seen from (4.3, 3.2, 1.4) with the
/// camera's brightness, odometry frame = map frame.
struct TexturedRoom {
  MapSurface surface;
  localisation::Request q;
  std::vector<Eigen::Vector3d> pts;
  std::vector<float> brightness;
};

TexturedRoom textured_room() {
  const auto samples = test::Scene{}.sample(0.01);
  const auto map = test::voxelise(samples, {0.03}, Eigen::Vector3d::Zero(), test::blob_albedo);
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensity;
  for (const auto& p : map->levels[0].points) {
    points.push_back(p.position);
    intensity.push_back(p.intensity);
  }
  TexturedRoom r;
  r.surface = MapSurface::build(points, 12, 0.01, intensity);
  const SE3d T_o_m = test::yaw_pose(0.0, Eigen::Vector3d::Zero());
  r.q = test::submap_request(samples, {4.3, 3.2, 1.4}, 4.0, 3000, 0.005, T_o_m, 3);
  test::add_brightness(&r.q, T_o_m, test::blob_albedo, 4);
  for (std::size_t i = 0; i < r.q.points.size(); ++i) {
    r.pts.push_back(r.q.points[i].cast<double>());
    r.brightness.push_back(r.q.brightness[i]);
  }
  return r;
}

TEST(Appearance, InliersFollowTheMapsTextureOnlyWhereThePoseIsRight) {
  auto [surface, q, pts, brightness] = textured_room();
  FineOptions o;
  o.iterations = 0;  // evaluate the given poses as they are
  const FineResult right = refine_pose(surface, pts, 0.0, q.anchor_o, o);
  // The half turn about the room's centre: the anchor (4.3, 3.2) goes to (3.7, 2.8).
  const FineResult turned = refine_pose(surface, pts, M_PI, Eigen::Vector3d(3.7, 2.8, 1.4), o);
  ASSERT_GT(right.fitness, 0.9);
  ASSERT_GT(turned.fitness, 0.9);  // the geometry cannot tell them apart
  const Appearance a_right = appearance(surface, right, brightness);
  const Appearance a_turned = appearance(surface, turned, brightness);
  EXPECT_GT(a_right.points, 1000);
  EXPECT_GT(a_right.correlation, 0.7);
  EXPECT_LT(std::abs(a_turned.correlation), 0.15);
  // No brightness: no points, no correlation.
  EXPECT_EQ(appearance(surface, right, {}).points, 0);
}

// A pose slid 14 cm along x (as the fine stage slides along a wall it cannot tell apart) is
// brought back by the texture within a step; with brightness unrelated to the map it stays.
TEST(Appearance, ASlideTheGeometryCannotSeeIsUndoneByTheTexture) {
  auto [surface, q, pts, brightness] = textured_room();
  const Eigen::Vector3d along = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d off = q.anchor_o + 0.14 * along;
  const Slide back =
      slide_by_appearance(surface, pts, brightness, 0.0, off, along, FineOptions{}, SlideOptions{});
  EXPECT_NEAR(back.offset_m, -0.14, 0.021);
  EXPECT_NEAR(back.fine.anchor.x(), q.anchor_o.x(), 0.021);
  EXPECT_GT(back.appearance.correlation, back.start.correlation + 0.3);
  EXPECT_FALSE(back.unbracketed);
  // 40 cm off, beyond the 0.3 m range: the best offset is the range's edge, flagged.
  const Slide far = slide_by_appearance(surface, pts, brightness, 0.0, q.anchor_o + 0.4 * along, along,
                                        FineOptions{}, SlideOptions{});
  EXPECT_TRUE(far.unbracketed);
  EXPECT_NEAR(far.offset_m, -0.3, 1e-9);
  // Coarse to fine over a wider range (every third step first, as the indoor config): 14 and
  // 40 cm back within a step, each matching the full search's offset.
  SlideOptions wide;
  wide.range_m = 1.0;
  wide.coarse_stride = 3;
  SlideOptions wide_full = wide;
  wide_full.coarse_stride = 1;
  for (const double d : {0.14, 0.4, -0.52}) {
    const Eigen::Vector3d start = q.anchor_o + d * along;
    const Slide s = slide_by_appearance(surface, pts, brightness, 0.0, start, along, FineOptions{}, wide);
    const Slide full =
        slide_by_appearance(surface, pts, brightness, 0.0, start, along, FineOptions{}, wide_full);
    EXPECT_NEAR(s.offset_m, -d, 0.021) << d;
    EXPECT_NEAR(s.offset_m, full.offset_m, 1e-9) << d;
    EXPECT_FALSE(s.unbracketed) << d;
  }
  // From the right pose nothing moves.
  const Slide stay =
      slide_by_appearance(surface, pts, brightness, 0.0, q.anchor_o, along, FineOptions{}, SlideOptions{});
  EXPECT_NEAR(stay.offset_m, 0.0, 0.021);
  // Brightness unrelated to the map: no gain beyond the margin, the pose stays where it was.
  std::mt19937 rng(2);
  std::shuffle(brightness.begin(), brightness.end(), rng);
  const Slide none =
      slide_by_appearance(surface, pts, brightness, 0.0, off, along, FineOptions{}, SlideOptions{});
  EXPECT_EQ(none.offset_m, 0.0);
  EXPECT_EQ(none.fine.anchor, off);
}

}  // namespace
}  // namespace mrvs::localise
