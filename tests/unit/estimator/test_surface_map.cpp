// The edge's memory of the map's surfaces (SurfaceMap: planes fitted to the cloud's answers,
// against the true plane and the degenerate cases) and stage 1's plane mode: a feature on a
// map surface gives the pose along the surface's normal only, where a ray from a pose off
// along the surface meets it off by as much (known_landmark claims both).
#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/msckf_updater.h"
#include "mrvs/edge/surface_map.h"
#include "msckf_scene.h"

namespace mrvs::edge {
namespace {

/// `count` points on the plane through `c` with unit normal n, within `half` of c along both
/// in-plane axes, moved off it by Gaussian noise of `sigma`.
std::vector<Vec3d> plane_points(const Vec3d& c, const Vec3d& n, double half, double sigma, int count,
                                unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  std::normal_distribution<double> g(0.0, sigma);
  const Vec3d a = n.unitOrthogonal(), b = n.cross(a);
  std::vector<Vec3d> out;
  for (int i = 0; i < count; ++i) out.push_back(c + u(rng) * a + u(rng) * b + (sigma > 0 ? g(rng) : 0.0) * n);
  return out;
}

TEST(SurfaceMap, FitsTheTruePlaneOfNoisyPoints) {
  const Vec3d n = Vec3d(1.0, -2.0, 0.5).normalized(), c(3.0, -1.0, 0.7);
  SurfaceMap map(0.5, 50);
  for (const Vec3d& p : plane_points(c, n, 0.6, 0.004, 400, 1)) map.add(p);
  SurfaceFitOptions o;
  o.radius_m = 0.5;
  const auto plane = map.plane_at(c, o);
  ASSERT_TRUE(plane.has_value());
  EXPECT_GT(std::abs(plane->normal.dot(n)), std::cos(2.0 * M_PI / 180.0));
  EXPECT_NEAR(plane->rms_m, 0.004, 0.0015);
  EXPECT_LT(std::abs(n.dot(plane->centroid - c)), 0.003);
  // Brute force: the points within the radius.
  int near = 0;
  for (const Vec3d& p : plane_points(c, n, 0.6, 0.004, 400, 1)) near += (p - c).norm() <= 0.5;
  EXPECT_EQ(plane->points, std::min(near, plane->points));  // at most 50 per cell were kept
  EXPECT_GE(plane->points, o.min_points);
}

TEST(SurfaceMap, RefusesTooFewLinesCornersAndRepeats) {
  SurfaceFitOptions o;
  o.radius_m = 0.5;
  SurfaceMap sparse(0.5, 16);
  for (const Vec3d& p : plane_points(Vec3d::Zero(), Vec3d::UnitZ(), 0.3, 0.0, 5, 2)) sparse.add(p);
  EXPECT_FALSE(sparse.plane_at(Vec3d::Zero(), o).has_value());  // 5 < 6 points
  // The same answer again and again (one voxel's representative point) counts once.
  SurfaceMap repeats(0.5, 16);
  EXPECT_TRUE(repeats.add(Vec3d(0.1, 0.2, 0.3)));
  for (int i = 0; i < 10; ++i) EXPECT_FALSE(repeats.add(Vec3d(0.1, 0.2, 0.3)));
  EXPECT_EQ(repeats.size(), 1u);
  EXPECT_FALSE(repeats.add(Vec3d(NAN, 0.0, 0.0)));
  // Points on a line (a pole, an edge): no plane.
  SurfaceMap line(0.5, 50);
  for (int i = 0; i < 30; ++i) line.add(Vec3d(0.03 * i - 0.45, 0.001 * (i % 3), 0.0));
  EXPECT_FALSE(line.plane_at(Vec3d::Zero(), o).has_value());
  // A corner of two walls: too rough for a plane.
  SurfaceMap corner(0.5, 100);
  for (const Vec3d& p : plane_points(Vec3d(0.2, 0.0, 0.0), Vec3d::UnitX(), 0.4, 0.0, 60, 3)) corner.add(p);
  for (const Vec3d& p : plane_points(Vec3d(0.0, 0.2, 0.0), Vec3d::UnitY(), 0.4, 0.0, 60, 4)) corner.add(p);
  EXPECT_FALSE(corner.plane_at(Vec3d(0.1, 0.1, 0.0), o).has_value());
  // A full cell takes no more.
  SurfaceMap full(10.0, 3);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(full.add(Vec3d(0.1 * i, 0.0, 0.0)));
  EXPECT_FALSE(full.add(Vec3d(0.5, 0.0, 0.0)));
}

TEST(MapMeasurement, ThePlaneRowIsTheFeaturesOffsetAlongTheNormal) {
  const test::Scene s = test::make_scene(0.3);
  MapPoint point{s.p_w + Vec3d(0.01, 0.02, -0.01), 0.003 * 0.003, std::nullopt, Mat3d::Zero(), std::nullopt};
  point.plane = SurfacePlane{Vec3d(1.0, 0.5, 0.2).normalized(), point.p_w, 0.004, 10};
  const Vec3d p_lin = s.p_w + Vec3d(0.002, -0.001, 0.003);
  auto rows = feature_rows(s.state, s.track, p_lin, p_lin, 1.0);
  ASSERT_TRUE(rows.ok());
  const auto before = *rows;
  append_plane_row(point, p_lin, &*rows);
  ASSERT_EQ(rows->m.rows(), before.m.rows() + 1);
  EXPECT_EQ(rows->m.H.topRows(before.m.rows()), before.m.H);
  EXPECT_TRUE(rows->m.H.bottomRows(1).isZero());
  // Numerically: the row's value n.(p - X) / sigma at p_lin + d is the residual minus H_f d.
  const double sigma = std::sqrt(0.003 * 0.003 + 0.004 * 0.004);
  const Vec3d d(0.003, -0.002, 0.001);
  const double value = point.plane->normal.dot(p_lin + d - point.p_w) / sigma;
  EXPECT_NEAR(-value, rows->m.r(before.m.rows()) - (rows->H_f.bottomRows(1) * d)(0), 1e-9);
}

/// A wall with unit normal n through (4, 0, 0) seen by the scene's clones, 20 features on it;
/// the clones shifted together by `shift` (10 cm priors, fully correlated: plain VIO's drift)
/// and updated once with the features' hits along the estimated rays of the newest left
/// camera (where a ray from the shifted pose meets the wall). The newest clone's position
/// error along and across n after the update, and its NEES.
struct WallResult {
  double along_normal = 0.0, along_wall = 0.0, nees = 0.0;
  int with_map = 0;
};
WallResult update_on_a_wall(Stage1Mode mode, const Vec3d& n, const Vec3d& shift) {
  test::Scene s = test::make_scene();
  FeatureDatabase db;
  const Vec3d q(4.0, 0.0, 0.0);
  const std::vector<Vec3d> truth = plane_points(q, n, 1.0, 0.0, 20, 7);
  test::add_observed_points(s.state, truth, 0.3, 8, &db);
  const TimestampNs newest = s.state.newest_clone_ns();
  const Vec3d true_p = s.state.clones.at(newest).T_w_b.translation();
  for (auto& [t, c] : s.state.clones)
    c.T_w_b = c.fej = SE3d(c.T_w_b.quaternion(), c.T_w_b.translation() + shift);
  for (auto& [t, a] : s.state.clones)
    for (auto& [u, b] : s.state.clones)
      s.state.P.block<3, 3>(a.slot.offset + 3, b.slot.offset + 3) = Mat3d::Identity() * 0.1 * 0.1;
  std::vector<FeatureId> ids;
  std::map<FeatureId, MapPoint> map_points;
  const SE3d T_w_c = s.state.T_w_c(newest, 0);
  for (FeatureId id = 1; id <= 20; ++id) {
    const Vec3d v = (truth[id - 1] + shift - T_w_c.translation()).normalized();  // estimated ray
    const Vec3d hit = T_w_c.translation() + v * n.dot(q - T_w_c.translation()) / n.dot(v);
    ids.push_back(id);
    map_points[id] = MapPoint{hit, 0.005 * 0.005, std::nullopt, Mat3d::Zero(), std::nullopt};
    map_points[id].plane = SurfacePlane{n, q, 0.0, 20};
  }
  const MsckfUpdater updater(MsckfOptions{}, TriangulationOptions{});
  const MsckfStats stats = updater.update(s.state, db, ids, map_points, mode);
  EXPECT_TRUE(stats.status.ok()) << stats.status;
  const CloneState& c = s.state.clones.at(newest);
  const Vec3d e = c.T_w_b.translation() - true_p;
  const Mat3d P = s.state.P.block<3, 3>(c.slot.offset + 3, c.slot.offset + 3);
  WallResult out;
  out.along_normal = std::abs(e.dot(n));
  out.along_wall = (e - n * e.dot(n)).norm();
  out.nees = e.dot(P.ldlt().solve(e));
  out.with_map = stats.with_map;
  return out;
}

TEST(MapMeasurement, OnAWallThePlaneModeCorrectsTheNormalOffsetAndClaimsNothingAlongTheWall) {
  // A facade at 45 degrees to the view; the pose is off mostly along it.
  const Vec3d n = Vec3d(1.0, 1.0, 0.0).normalized();
  const Vec3d along(n.y(), -n.x(), 0.0);
  const Vec3d shift = 0.08 * along + 0.03 * n + Vec3d(0.0, 0.0, 0.02);
  const WallResult plane = update_on_a_wall(Stage1Mode::kPlane, n, shift);
  const WallResult known = update_on_a_wall(Stage1Mode::kKnownLandmark, n, shift);
  const WallResult none = update_on_a_wall(Stage1Mode::kMsckfNullspace, n, shift);
  RecordProperty("plane_nees", std::to_string(plane.nees));
  RecordProperty("known_nees", std::to_string(known.nees));
  EXPECT_EQ(plane.with_map, 20);
  // Along the normal the wall holds the pose; plain MSCKF rows cannot.
  EXPECT_LT(plane.along_normal, 0.3 * 0.03);
  EXPECT_GT(none.along_normal, 0.7 * 0.03);
  // Along the wall nothing is known, and the plane mode does not claim it (honest NEES);
  // known landmarks pin the pose where the wrong rays met the wall and claim millimetres.
  EXPECT_LT(plane.nees, 11.3);  // chi-square 3 dof, 99 %
  EXPECT_GT(known.nees, 100.0);
  EXPECT_GT(known.along_wall, 0.5 * (shift - n * shift.dot(n)).norm());
}

TEST(MapMeasurement, WithoutAPlaneThePlaneModeUsesTheFeatureAlone) {
  test::Scene s = test::make_scene(0.3);
  const MsckfUpdater updater(MsckfOptions{}, TriangulationOptions{});
  const MapPoint point{s.p_w + Vec3d(0.5, 0.0, 0.0), 1e-6, std::nullopt, Mat3d::Zero(),
                       std::nullopt};  // no plane
  MsckfStats a, b;
  const auto with = updater.map_measurement(s.state, s.track, point, Stage1Mode::kPlane, &a);
  const auto alone = updater.feature_measurement(s.state, s.track, &b);
  ASSERT_TRUE(with.has_value() && alone.has_value());
  EXPECT_EQ(with->H, alone->H);
  EXPECT_EQ(with->r, alone->r);
}

}  // namespace
}  // namespace mrvs::edge
