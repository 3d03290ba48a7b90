// QueryEngine::surface_normal: the plane of the hit level's points within normal_radius_m,
// against a brute-force fit over every map point and the analytic normal of the surface.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "mrvs/geometry/plane_fit.h"
#include "query_test_maps.h"

namespace mrvs::map::test {
namespace {

constexpr double kR = 0.2;  // the outdoor map's coarse level

/// One point per 0.2 m voxel column of the tilted plane z = 0.3 x + 0.2 y + 0.5 over
/// [-3, 3)^2 m, jittered in the column, with `noise_m` (sd) along z.
std::vector<Eigen::Vector3f> tilted_plane(double noise_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(0.1, 0.9);
  std::normal_distribution<double> noise(0.0, noise_m);
  std::vector<Eigen::Vector3f> points;
  for (int i = -15; i < 15; ++i) {
    for (int j = -15; j < 15; ++j) {
      const double x = (i + jitter(rng)) * kR, y = (j + jitter(rng)) * kR;
      points.emplace_back(static_cast<float>(x), static_cast<float>(y),
                          static_cast<float>(0.3 * x + 0.2 * y + 0.5 + noise(rng)));
    }
  }
  return points;
}

Eigen::Vector3d brute_force_normal(const std::vector<Eigen::Vector3f>& points, const Eigen::Vector3f& at,
                                   double radius) {
  std::vector<Vec3d> near;
  for (const Eigen::Vector3f& p : points) {
    if ((p - at).norm() <= radius) near.push_back(p.cast<double>());
  }
  return fit_plane(near)->normal;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / M_PI;
}

TEST(SurfaceNormal, OnANoisyTiltedPlaneItIsTheBruteForceFitAndTheTrueNormal) {
  const auto points = tilted_plane(0.01, 3);
  const QueryEngine engine = make_engine(single_level_map(kR, points));
  const Eigen::Vector3d truth(0.3, 0.2, -1.0);
  std::mt19937_64 rng(4);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  int checked = 0;
  for (int k = 0; k < 40; ++k) {
    const Eigen::Vector3f at = points[pick(rng)];
    if (std::abs(at.x()) > 1.8 || std::abs(at.y()) > 1.8) continue;  // a full disc around it
    const auto n = engine.surface_normal(0, at);
    ASSERT_TRUE(n.has_value()) << at.transpose();
    EXPECT_NEAR(n->norm(), 1.0f, 1e-5f);
    EXPECT_LT(angle_deg(n->cast<double>(), brute_force_normal(points, at, engine.options().normal_radius_m)),
              1e-3);
    EXPECT_LT(angle_deg(n->cast<double>(), truth), 2.0);
    ++checked;
  }
  EXPECT_GE(checked, 10);
}

TEST(SurfaceNormal, NoneAtACornerOnALineWithTooFewPointsOrAnUnknownLevel) {
  // Two perpendicular walls x = 0 and y = 0 meeting at the z axis.
  std::vector<Eigen::Vector3f> corner;
  for (int i = 0; i < 15; ++i) {
    for (int k = 0; k < 15; ++k) {
      corner.emplace_back(0.05f, (i + 0.5f) * kR, (k + 0.5f) * kR);
      if (i > 0) corner.emplace_back((i + 0.5f) * kR, 0.05f, (k + 0.5f) * kR);  // one point per voxel
    }
  }
  const QueryEngine at_corner = make_engine(single_level_map(kR, corner));
  EXPECT_FALSE(at_corner.surface_normal(0, Eigen::Vector3f(0.05f, 0.05f, 1.5f)).has_value());
  EXPECT_TRUE(at_corner.surface_normal(0, Eigen::Vector3f(0.05f, 2.5f, 1.5f)).has_value()) << "on one wall";

  std::vector<Eigen::Vector3f> line;
  for (int i = 0; i < 30; ++i) line.emplace_back((i + 0.5f) * kR, 0.1f, 0.1f);
  const QueryEngine on_line = make_engine(single_level_map(kR, line));
  EXPECT_FALSE(on_line.surface_normal(0, Eigen::Vector3f(3.1f, 0.1f, 0.1f)).has_value());

  const std::vector<Eigen::Vector3f> few = {{0.1f, 0.1f, 0.0f}, {0.3f, 0.1f, 0.0f}, {0.1f, 0.3f, 0.0f}};
  const QueryEngine sparse = make_engine(single_level_map(kR, few));
  EXPECT_FALSE(sparse.surface_normal(0, few[0]).has_value());
  QueryOptions three;
  three.normal_min_points = 3;
  three.normal_min_extent = 0.0;
  EXPECT_TRUE(make_engine(single_level_map(kR, few), three).surface_normal(0, few[0]).has_value());

  EXPECT_FALSE(sparse.surface_normal(1, few[0]).has_value());
  EXPECT_FALSE(sparse.surface_normal(-1, few[0]).has_value());
  EXPECT_FALSE(sparse.surface_normal(0, Eigen::Vector3f(NAN, 0.0f, 0.0f)).has_value());
}

}  // namespace
}  // namespace mrvs::map::test
