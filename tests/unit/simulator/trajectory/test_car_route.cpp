// synthesize_car_route: route geometry, and the car dynamics of its spline fit (speed
// plateau, lateral acceleration, heading continuity, length, rest at the start).
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "mrvs/sim/car_route.h"
#include "mrvs/sim/spline_trajectory.h"
#include "mrvs/sim/test/strapdown.h"

namespace mrvs::sim {
namespace {

constexpr std::uint64_t kSeed = 7;

TEST(CarRoute, TestRouteGeometry) {
  auto route = synthesize_car_route(test_car_route(), kSeed);
  ASSERT_TRUE(route.ok()) << route.status();
  EXPECT_NEAR(route->length_m, 180.0 + 9.0 * kPi + 120.0, 1e-9);
  ASSERT_EQ(route->polyline_xy.size(), 3u);
  EXPECT_EQ(route->polyline_xy[0], Vec2d(0.0, 0.0));
  EXPECT_EQ(route->polyline_xy[1], Vec2d(198.0, 0.0));  // right turn: heading +x -> -y
  EXPECT_EQ(route->polyline_xy[2], Vec2d(198.0, -138.0));
  ASSERT_EQ(route->straights.size(), 2u);
  ASSERT_EQ(route->arcs.size(), 1u);
  EXPECT_EQ(route->straights[0].end_xy, Vec2d(180.0, 0.0));
  EXPECT_EQ(route->straights[1].start_xy, Vec2d(198.0, -18.0));
  EXPECT_EQ(route->arcs[0].center_xy, Vec2d(180.0, -18.0));
  EXPECT_EQ(route->arcs[0].direction, -1);
  // 100 Hz samples with rests at both ends.
  const io::Trajectory& traj = route->trajectory;
  EXPECT_EQ(traj[1].t_ns - traj[0].t_ns, 10'000'000);
  EXPECT_EQ(route->motion_begin_ns - traj.front().t_ns, 3'000'000'000);
  const double duration = to_seconds(traj.back().t_ns - traj.front().t_ns);
  std::printf("[car route] length %.2f m, %zu samples, %.2f s (motion %.2f s)\n", route->length_m,
              traj.size(), duration, to_seconds(route->motion_end_ns - route->motion_begin_ns));
  EXPECT_GT(duration, 30.0);
  EXPECT_NEAR(traj.back().T_w_b.translation().x(), 198.0, 1e-6);
  EXPECT_NEAR(traj.back().T_w_b.translation().y(), -138.0, 1e-6);
}

TEST(CarRoute, SplineHasCarDynamics) {
  auto route = synthesize_car_route(test_car_route(), kSeed);
  ASSERT_TRUE(route.ok()) << route.status();
  auto spline = SplineTrajectory::fit(route->trajectory);
  ASSERT_TRUE(spline.ok()) << spline.status();
  double max_speed = 0.0, max_lat = 0.0, max_dyaw = 0.0, length = 0.0, cruise_s = 0.0, max_rest_v = 0.0;
  double z_min = 1e9, z_max = -1e9, total_yaw = 0.0;
  Kinematics prev = *spline->evaluate(spline->t_begin_ns());
  const DurationNs dt = 10'000'000;
  for (TimestampNs t = spline->t_begin_ns() + dt; t <= spline->t_end_ns(); t += dt) {
    const Kinematics k = *spline->evaluate(t);
    const Vec3d v = k.v_w;
    const double speed = v.head<2>().norm();
    max_speed = std::max(max_speed, speed);
    if (std::abs(speed - 10.0) < 0.05) cruise_s += to_seconds(dt);
    if (speed > 1.0) {  // lateral = horizontal acceleration across the direction of travel
      const Vec2d left(-v.y() / speed, v.x() / speed);
      max_lat = std::max(max_lat, std::abs(k.a_w.head<2>().dot(left)));
    }
    if (t < route->motion_begin_ns - 100'000'000) max_rest_v = std::max(max_rest_v, v.norm());
    const Mat3d R0 = prev.T_w_b.rotation_matrix(), R1 = k.T_w_b.rotation_matrix();
    double dyaw = std::atan2(R1(1, 0), R1(0, 0)) - std::atan2(R0(1, 0), R0(0, 0));
    dyaw = std::remainder(dyaw, 2.0 * kPi);
    max_dyaw = std::max(max_dyaw, std::abs(dyaw));
    total_yaw += dyaw;
    length += (k.T_w_b.translation() - prev.T_w_b.translation()).head<2>().norm();
    z_min = std::min(z_min, k.T_w_b.translation().z());
    z_max = std::max(z_max, k.T_w_b.translation().z());
    prev = k;
  }
  std::printf(
      "[car spline] max speed %.4f m/s, %.1f s at 10 +- 0.05 m/s, max |a_lat| %.3f m/s^2, max yaw step "
      "%.4f deg, turn %.3f deg, length %.3f m, z [%.4f, %.4f] m\n",
      max_speed, cruise_s, max_lat, max_dyaw * kRadToDeg, total_yaw * kRadToDeg, length, z_min, z_max);
  EXPECT_NEAR(max_speed, 10.0, 0.05);
  EXPECT_GT(cruise_s, 15.0);
  EXPECT_LT(max_lat, 2.5 + 0.1);
  EXPECT_GT(max_lat, 2.3);
  EXPECT_LT(max_dyaw * kRadToDeg, 0.5);  // 10 ms at <= 21 deg/s
  EXPECT_NEAR(total_yaw * kRadToDeg, -90.0, 0.1);
  EXPECT_NEAR(length, route->length_m, 0.3);
  EXPECT_LT(max_rest_v, 1e-12);
  EXPECT_GT(z_min, 1.7 - 0.0055);
  EXPECT_LT(z_max, 1.7 + 0.0055);
}

TEST(CarRoute, LongRouteAndDeterminism) {
  auto route = synthesize_car_route(long_car_route(), kSeed);
  ASSERT_TRUE(route.ok()) << route.status();
  EXPECT_NEAR(route->length_m, 690.0 + 4 * 9.0 * kPi, 1e-9);
  for (std::size_t i = 1; i < route->polyline_xy.size(); ++i) {
    const Vec2d d = route->polyline_xy[i] - route->polyline_xy[i - 1];
    EXPECT_TRUE(d.x() == 0.0 || d.y() == 0.0) << "leg " << i << " is not axis-aligned";
  }
  EXPECT_EQ(route->polyline_xy.size(), 6u);
  const double yaw_end = std::atan2(route->trajectory.back().T_w_b.rotation_matrix()(1, 0),
                                    route->trajectory.back().T_w_b.rotation_matrix()(0, 0));
  EXPECT_NEAR(yaw_end, 0.0, 1e-3);  // right, left, left, right: back to +x
  EXPECT_GT(to_seconds(route->motion_end_ns - route->motion_begin_ns), 60.0);

  const auto again = synthesize_car_route(long_car_route(), kSeed);
  const auto other = synthesize_car_route(long_car_route(), kSeed + 1);
  ASSERT_TRUE(again.ok() && other.ok());
  ASSERT_EQ(again->trajectory.size(), route->trajectory.size());
  bool z_differs = false;
  for (std::size_t k = 0; k < route->trajectory.size(); ++k) {
    ASSERT_EQ(again->trajectory[k].T_w_b.translation(), route->trajectory[k].T_w_b.translation());
    ASSERT_EQ(again->trajectory[k].T_w_b.quaternion().coeffs(),
              route->trajectory[k].T_w_b.quaternion().coeffs());
    z_differs |= other->trajectory[k].T_w_b.translation().z() != route->trajectory[k].T_w_b.translation().z();
  }
  EXPECT_TRUE(z_differs);
}

TEST(CarRoute, RejectsBadOptions) {
  CarRouteOptions o = test_car_route();
  o.turn_directions = {};
  EXPECT_FALSE(synthesize_car_route(o, kSeed).ok());
  o = test_car_route();
  o.turn_directions = {0};
  EXPECT_FALSE(synthesize_car_route(o, kSeed).ok());
  o = test_car_route();
  o.initial_heading_deg = 45.0;
  const auto r = synthesize_car_route(o, kSeed);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(std::string(r.status().message()).find("multiple of 90"), std::string::npos);
  o = test_car_route();
  o.sample_rate_hz = 300;
  EXPECT_FALSE(synthesize_car_route(o, kSeed).ok());
}

}  // namespace
}  // namespace mrvs::sim
