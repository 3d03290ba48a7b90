#pragma once
// Car-like trajectory for the KAIST-like profile (simulator.md section 2.8).
//
// The route lies on a Manhattan grid in the plane z = 0 (the road): axis-aligned straight
// legs joined by 90-degree circular arcs. It starts at start_xy heading along
// initial_heading_deg (a multiple of 90). The speed profile along the arc length s is the
// lowest of: cruise speed; acceleration from rest (+acceleration_mps2); before each arc,
// braking (-braking_mps2) down to the arc speed min(cruise, sqrt(a_lat_max R)); after each
// arc, acceleration back to cruise; braking to a stop at the end of the route. The car
// rests rest_before_s before moving and rest_after_s after stopping.
//
// Body (IMU) frame: x forward, y left, z up. Heading = path tangent (no side slip);
// pitch = -pitch_per_long_accel_deg * a_long + bump pitch; roll = +roll_per_lat_accel_deg *
// a_lat (a_lat > 0 to the left); R_w_b = Rz(heading) Ry(pitch) Rx(roll). Position = road
// point + (0, 0, imu_height_m + bump z). Road bumps are functions of s (so the car at rest is
// exactly still): three sinusoids each for z and pitch, wavelengths around
// cruise_speed / bump_frequency_hz, amplitudes summing to the bump amplitude, drawn from
// Stream::kRoute.
//
// The sampled trajectory is meant to go through SplineTrajectory::fit like the EuRoC one.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/io/types.h"

namespace mrvs::sim {

/// Route and driving knobs. Defaults: the test route of simulator.md 2.8 (180 m straight,
/// right turn R = 18 m, 120 m straight; about 328 m and 44 s).
struct CarRouteOptions : config::OptionsEquality<CarRouteOptions> {
  std::vector<double> straight_lengths_m = {180.0, 120.0};  ///< straight part of each leg, m
  std::vector<int> turn_directions = {-1};                  ///< per corner: +1 left, -1 right
  std::vector<double> turn_radii_m = {18.0};                ///< per corner, m
  Eigen::Vector2d start_xy{0.0, 0.0};                       ///< m
  double initial_heading_deg = 0.0;                         ///< deg from +x, multiple of 90
  double cruise_speed_mps = 10.0;                           ///< m/s
  double acceleration_mps2 = 1.5;                           ///< m/s^2
  double braking_mps2 = 2.0;                                ///< m/s^2 (magnitude)
  double max_lateral_accel_mps2 = 2.5;                      ///< m/s^2 in the arcs
  double rest_before_s = 3.0;                               ///< s at rest before moving
  double rest_after_s = 1.0;                                ///< s at rest after stopping
  double imu_height_m = 1.7;                                ///< above the road, m
  double bump_amplitude_m = 0.005;                          ///< m (0 = flat road)
  double bump_frequency_hz = 1.5;                           ///< at cruise speed, Hz
  double bump_pitch_deg = 0.2;                              ///< deg
  double pitch_per_long_accel_deg = 0.5;                    ///< deg per m/s^2 (nose up when accelerating)
  double roll_per_lat_accel_deg = 0.5;                      ///< deg per m/s^2 (leans out of the turn)
  int sample_rate_hz = 100;                                 ///< Hz of the output trajectory
  std::int64_t start_time_ns = 1'544'590'800'000'000'000;   ///< ns since the epoch of the first sample

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("straight_lengths_m", straight_lengths_m, each_in_range(0.0, 1e5).size(1, 1000), "m per leg");
    v("turn_directions", turn_directions, each_in_range(-1, 1).size(0, 999), "+1 left, -1 right, per corner");
    v("turn_radii_m", turn_radii_m, each_in_range(1.0, 1000.0).size(0, 999), "m per corner");
    v("start_xy", start_xy, any(), "m");
    v("initial_heading_deg", initial_heading_deg, in_range(-360.0, 360.0), "deg, multiple of 90");
    v("cruise_speed_mps", cruise_speed_mps, in_range(0.1, 100.0), "m/s");
    v("acceleration_mps2", acceleration_mps2, in_range(0.01, 20.0), "m/s^2");
    v("braking_mps2", braking_mps2, in_range(0.01, 20.0), "m/s^2");
    v("max_lateral_accel_mps2", max_lateral_accel_mps2, in_range(0.01, 20.0), "m/s^2");
    v("rest_before_s", rest_before_s, in_range(0.0, 3600.0), "s");
    v("rest_after_s", rest_after_s, in_range(0.0, 3600.0), "s");
    v("imu_height_m", imu_height_m, in_range(0.0, 100.0), "m");
    v("bump_amplitude_m", bump_amplitude_m, in_range(0.0, 1.0), "m");
    v("bump_frequency_hz", bump_frequency_hz, in_range(0.01, 100.0), "Hz at cruise speed");
    v("bump_pitch_deg", bump_pitch_deg, in_range(0.0, 10.0), "deg");
    v("pitch_per_long_accel_deg", pitch_per_long_accel_deg, in_range(0.0, 10.0), "deg per m/s^2");
    v("roll_per_lat_accel_deg", roll_per_lat_accel_deg, in_range(0.0, 10.0), "deg per m/s^2");
    v("sample_rate_hz", sample_rate_hz, in_range(1, 10000), "Hz");
    v("start_time_ns", start_time_ns, at_least(std::int64_t{0}), "ns since the epoch");
  }
};

/// The test route (the defaults).
CarRouteOptions test_car_route();
/// A longer staircase route for long sequences (about 800 m, 95 s, four turns):
/// 150 m, right, 120 m, left, 150 m, left, 120 m, right, 150 m, all turns R = 18 m.
CarRouteOptions long_car_route();

/// An axis-aligned straight piece of the road centreline (z = 0).
struct RouteStraight {
  Vec2d start_xy = Vec2d::Zero();  ///< m
  Vec2d end_xy = Vec2d::Zero();    ///< m
  double heading_rad = 0.0;        ///< direction of travel, rad from +x
  double s_begin_m = 0.0;          ///< arc length at start_xy, m
};

/// A 90-degree arc of the road centreline.
struct RouteArc {
  Vec2d center_xy = Vec2d::Zero();  ///< m
  double radius_m = 0.0;            ///< m
  double start_heading_rad = 0.0;   ///< heading at the arc start, rad
  int direction = 1;                ///< +1 left (counter-clockwise), -1 right
  Vec2d corner_xy = Vec2d::Zero();  ///< intersection centre: where the two legs' lines meet, m
  double s_begin_m = 0.0;           ///< arc length at the arc start, m
};

/// The synthesized route.
struct CarRoute {
  io::Trajectory trajectory;  ///< T_w_b samples at sample_rate_hz
  std::vector<RouteStraight> straights;
  std::vector<RouteArc> arcs;  ///< arcs[i] joins straights[i] and straights[i + 1]
  /// Manhattan polyline of the road: start, intersection centres (corners), end. Its
  /// segments are the axis-aligned legs for laying out the road and the buildings.
  std::vector<Vec2d> polyline_xy;
  double length_m = 0.0;            ///< centreline length (straights + arcs), m
  TimestampNs motion_begin_ns = 0;  ///< when the car starts moving
  TimestampNs motion_end_ns = 0;    ///< when it has stopped
};

/// Builds the route, its speed profile and the sampled trajectory. Errors name the bad
/// option (turn lists not matching the legs, heading not a multiple of 90, ...).
StatusOr<CarRoute> synthesize_car_route(const CarRouteOptions& options, std::uint64_t seed);

}  // namespace mrvs::sim
