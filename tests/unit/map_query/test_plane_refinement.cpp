// refine_plane_intersection (algorithm.md 2.6): the returned point is where the ray meets the
// plane of the hit voxel's 3 x 3 x 3 neighbourhood, when that neighbourhood is planar.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "query_test_maps.h"

namespace mrvs::map::test {
namespace {

constexpr double kR = 0.01;

/// The tilted plane z = 0.5 + 0.3 x + 0.2 y (map-local metres).
double plane_z(double x, double y) { return 0.5 + 0.3 * x + 0.2 * y; }

/// One point on the plane per (x, y) voxel column in [-12, 12)^2, jittered inside the column.
std::shared_ptr<VoxelMap> planar_patch(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> jitter(0.2, 0.8);
  std::vector<Eigen::Vector3f> points;
  for (int i = -12; i < 12; ++i) {
    for (int j = -12; j < 12; ++j) {
      const double x = (i + jitter(rng)) * kR;
      const double y = (j + jitter(rng)) * kR;
      points.emplace_back(static_cast<float>(x), static_cast<float>(y), static_cast<float>(plane_z(x, y)));
    }
  }
  return single_level_map(kR, points);
}

double distance_to_ray(const RayQuery& q, const Eigen::Vector3f& p) {
  const Eigen::Vector3d v = q.direction.cast<double>().normalized();
  const Eigen::Vector3d w = (p - q.origin).cast<double>();
  return (w - w.dot(v) * v).norm();
}

/// Rays from above the patch at random points of its central part, d = true distance.
std::vector<RayQuery> rays_at_patch(int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> target(-0.06, 0.06);
  std::uniform_real_distribution<double> camera(-0.5, 0.5);
  std::vector<RayQuery> rays;
  for (int i = 0; i < count; ++i) {
    const double x = target(rng);
    const double y = target(rng);
    const Eigen::Vector3d hit(x, y, plane_z(x, y));
    const Eigen::Vector3d origin(camera(rng), camera(rng), 1.8);
    RayQuery q;
    q.origin = origin.cast<float>();
    q.direction = (hit - origin).cast<float>();
    q.initial_distance = static_cast<float>((hit - origin).norm());
    q.resolution = static_cast<float>(kR);
    rays.push_back(q);
  }
  return rays;
}

TEST(PlaneRefinement, IntersectionLiesOnTheRayAndOnThePlane) {
  const auto map = planar_patch(1);
  QueryOptions options;
  options.refine_plane_intersection = true;
  const QueryEngine refined = make_engine(map, options);
  const QueryEngine plain = make_engine(map);
  int count = 0;
  for (const RayQuery& q : rays_at_patch(500, 2)) {
    const QueryResult r = refined.query(q);
    const QueryResult p = plain.query(q);
    ASSERT_EQ(p.status, QueryStatus::kHit);
    EXPECT_FALSE(p.refined);
    if (!r.refined) {
      // Fallback: the stored point, exactly as without refinement.
      EXPECT_EQ(r.point, p.point);
      continue;
    }
    ++count;
    EXPECT_EQ(r.status, QueryStatus::kHit);
    EXPECT_LT(distance_to_ray(q, r.point), 2e-6);
    EXPECT_NEAR(r.point.z(), plane_z(r.point.x(), r.point.y()), 2e-6);
    // Within the neighbourhood of the stored point (inside the fitted circle).
    EXPECT_LT((r.point - p.point).norm(), 3 * kR);
  }
  EXPECT_GT(count, 450);  // almost every ray: the patch is exactly planar
}

TEST(PlaneRefinement, NonPlanarNeighbourhoodFallsBackToTheStoredPoint) {
  // A full 3 x 3 x 3 block of voxel-centre points around voxel (200, 0, 0): isotropic, planarity 0.
  std::vector<Eigen::Vector3f> points;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        points.push_back(
            point_in_voxel(voxel::VoxelIndex(200 + dx, dy, dz), kR, Eigen::Vector3d(0.5, 0.5, 0.5)));
  const auto map = single_level_map(kR, points);
  QueryOptions options;
  options.refine_plane_intersection = true;
  options.threshold_offset_px = 5.0;
  const QueryEngine engine = make_engine(map, options);
  // The search starts inside the centre voxel (t_start = d - R0 = 2.0 at the centre point), on
  // an oblique ray that no fitted plane could be parallel to: the hit is the centre voxel.
  RayQuery q;
  const Eigen::Vector3f v = Eigen::Vector3f(1.0f, 0.3f, 0.2f).normalized();
  q.origin = points[13] - 2.0f * v;
  q.direction = v;
  q.initial_distance = 2.75f;
  q.resolution = static_cast<float>(kR);
  const QueryResult r = engine.query(q);
  EXPECT_EQ(r.status, QueryStatus::kHit);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.point, points[13]);  // the centre voxel's point
}

TEST(PlaneRefinement, FewerThanFourNeighboursFallBackToTheStoredPoint) {
  // Three points on the plane z = 0.5: too few for a fit.
  const std::vector<Eigen::Vector3f> points = {Eigen::Vector3f(0.005f, 0.005f, 0.505f),
                                               Eigen::Vector3f(0.015f, 0.005f, 0.505f),
                                               Eigen::Vector3f(0.005f, 0.015f, 0.505f)};
  QueryOptions options;
  options.refine_plane_intersection = true;
  const QueryEngine engine = make_engine(single_level_map(kR, points), options);
  RayQuery q;
  q.origin = Eigen::Vector3f(0.006f, 0.008f, 2.0f);
  q.direction = -Eigen::Vector3f::UnitZ();
  q.initial_distance = 1.5f;
  q.resolution = static_cast<float>(kR);
  const QueryResult r = engine.query(q);
  EXPECT_EQ(r.status, QueryStatus::kHit);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.point, points[0]);
  // A fourth point makes it a plane (circle through the square's corners, centre (0.01, 0.01),
  // radius 0.71 cm): the intersection (0.006, 0.008, 0.505) is returned.
  std::vector<Eigen::Vector3f> four = points;
  four.emplace_back(0.015f, 0.015f, 0.505f);
  const QueryEngine engine4 = make_engine(single_level_map(kR, four), options);
  const QueryResult r4 = engine4.query(q);
  EXPECT_TRUE(r4.refined);
  EXPECT_NEAR(r4.point.x(), 0.006f, 1e-6f);
  EXPECT_NEAR(r4.point.y(), 0.008f, 1e-6f);
  EXPECT_NEAR(r4.point.z(), 0.505f, 1e-6f);
  // The plane behind the ray origin (the ray starts inside the hit voxel, 1 mm past the
  // plane): no intersection in front, the stored point.
  RayQuery behind = q;
  behind.origin.z() = 0.504f;
  behind.initial_distance = 0.1f;
  const QueryResult rb = engine4.query(behind);
  EXPECT_EQ(rb.status, QueryStatus::kHit);
  EXPECT_FALSE(rb.refined);
  EXPECT_EQ(rb.point, points[0]);
}

TEST(PlaneRefinement, AcceptedOnlyInsideTheFittedCircle) {
  // Four points at the corners of a 1 cm square on z = 0.505: the Kasa circle is the square's
  // circumcircle, centre (0.01, 0.01), radius 0.5 sqrt(2) cm. Vertical rays at distance
  // radius -+ 0.1 mm from the centre, both through voxel (0, 0, 50).
  const std::vector<Eigen::Vector3f> points = {
      Eigen::Vector3f(0.005f, 0.005f, 0.505f), Eigen::Vector3f(0.015f, 0.005f, 0.505f),
      Eigen::Vector3f(0.005f, 0.015f, 0.505f), Eigen::Vector3f(0.015f, 0.015f, 0.505f)};
  QueryOptions options;
  options.refine_plane_intersection = true;
  const QueryEngine engine = make_engine(single_level_map(kR, points), options);
  const double radius = 0.005 * std::sqrt(2.0);
  for (const double margin : {-1e-4, 1e-4}) {
    const double xy = 0.01 - (radius + margin) / std::sqrt(2.0);
    RayQuery q;
    q.origin = Eigen::Vector3f(static_cast<float>(xy), static_cast<float>(xy), 2.0f);
    q.direction = -Eigen::Vector3f::UnitZ();
    q.initial_distance = 1.5f;
    q.resolution = static_cast<float>(kR);
    const QueryResult r = engine.query(q);
    ASSERT_EQ(r.status, QueryStatus::kHit);
    EXPECT_EQ(r.refined, margin < 0) << margin;
    if (r.refined) {
      EXPECT_NEAR(r.point.x(), xy, 1e-6);
      EXPECT_NEAR(r.point.z(), 0.505, 1e-6);
    } else {
      EXPECT_EQ(r.point, points[0]);
    }
  }
}

TEST(PlaneRefinement, CircleCentreIsTheFittedOneNotTheCentroid) {
  // Four points on the circle of radius 1.2 cm around (0.015, 0.015) at 0, 90, 135 and 180
  // degrees (centroid elsewhere), z = 0.505. Vertical rays through voxel (1, 2, 50) cross the
  // plane at (0.015, 0.027 -+ 0.1 mm): just inside / outside the circle.
  const double c = 0.015;
  const double rho = 0.012;
  std::vector<Eigen::Vector3f> points;
  for (const double deg : {90.0, 0.0, 135.0, 180.0}) {
    const double a = deg * M_PI / 180.0;
    points.emplace_back(static_cast<float>(c + rho * std::cos(a)), static_cast<float>(c + rho * std::sin(a)),
                        0.505f);
  }
  QueryOptions options;
  options.refine_plane_intersection = true;
  const QueryEngine engine = make_engine(single_level_map(kR, points), options);
  ASSERT_EQ(*voxel_of(points[0], kR), voxel::VoxelIndex(1, 2, 50));
  for (const double margin : {-1e-4, 1e-4}) {
    RayQuery q;
    q.origin = Eigen::Vector3f(static_cast<float>(c), static_cast<float>(c + rho + margin), 2.0f);
    q.direction = -Eigen::Vector3f::UnitZ();
    q.initial_distance = 1.5f;
    q.resolution = static_cast<float>(kR);
    const QueryResult r = engine.query(q);
    ASSERT_EQ(r.status, QueryStatus::kHit);
    EXPECT_EQ(r.refined, margin < 0) << margin;
  }
}

TEST(PlaneRefinement, IntersectionOutsideTheCircleFallsBack) {
  // Four points of a 1 cm square on z = 0.5 (circle radius ~0.7 cm around its centre); the ray
  // enters the square's corner voxel but meets the plane ~55 m away (grazing): not accepted.
  const std::vector<Eigen::Vector3f> points = {
      Eigen::Vector3f(0.005f, 0.005f, 0.505f), Eigen::Vector3f(0.015f, 0.005f, 0.505f),
      Eigen::Vector3f(0.005f, 0.015f, 0.505f), Eigen::Vector3f(0.015f, 0.015f, 0.505f)};
  QueryOptions options;
  options.refine_plane_intersection = true;
  options.threshold_offset_px = 50.0;  // accept whatever comes back
  const QueryEngine engine = make_engine(single_level_map(kR, points), options);
  RayQuery q;
  // Along +x, slightly rising, through voxel (0, 0, 50) at its bottom: meets z = 0.505 at x ~ 55 m.
  q.origin = Eigen::Vector3f(-0.5f, 0.005f, 0.5f);
  q.direction = Eigen::Vector3f(1.0f, 0.0f, 0.00009f);
  q.initial_distance = 0.505f;
  q.resolution = static_cast<float>(kR);
  const QueryResult r = engine.query(q);
  ASSERT_EQ(r.status, QueryStatus::kHit);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.point, points[0]);
}

}  // namespace
}  // namespace mrvs::map::test
