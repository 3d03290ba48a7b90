#include "mrvs/sim/car_route.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "mrvs/geometry/angles.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

/// Exact unit vector of the axis direction quadrant q (0: +x, 1: +y, 2: -x, 3: -y).
Vec2d axis_direction(int quadrant) {
  switch (((quadrant % 4) + 4) % 4) {
    case 0:
      return {1.0, 0.0};
    case 1:
      return {0.0, 1.0};
    case 2:
      return {-1.0, 0.0};
    default:
      return {0.0, -1.0};
  }
}

/// One piece of the centreline: a straight or a 90-degree arc.
struct Piece {
  bool is_arc = false;
  double s0 = 0.0;      ///< arc length at the start, m
  double length = 0.0;  ///< m
  Vec2d start = Vec2d::Zero();
  int quadrant = 0;     ///< heading at the start, in quarter turns (unwrapped)
  int direction = 0;    ///< arcs: +1 left, -1 right
  double radius = 0.0;  ///< arcs, m
  Vec2d center = Vec2d::Zero();
};

/// A point of the centreline.
struct PathPoint {
  Vec2d xy = Vec2d::Zero();
  double heading = 0.0;    ///< rad, continuous (unwrapped)
  double curvature = 0.0;  ///< 1/m, > 0 turning left
};

Status validate_route(const CarRouteOptions& o) {
  MRVS_RETURN_IF_ERROR(config::validate_options(o, "car_route"));
  const std::size_t corners = o.straight_lengths_m.size() - 1;
  if (o.turn_directions.size() != corners || o.turn_radii_m.size() != corners) {
    return absl::InvalidArgumentError(fmt::format(
        "car route: {} straight legs need {} turn_directions and {} turn_radii_m, got {} and {}",
        o.straight_lengths_m.size(), corners, corners, o.turn_directions.size(), o.turn_radii_m.size()));
  }
  for (std::size_t i = 0; i < corners; ++i) {
    if (o.turn_directions[i] != 1 && o.turn_directions[i] != -1) {
      return absl::InvalidArgumentError(fmt::format(
          "car route: turn_directions[{}] = {}: use +1 (left) or -1 (right)", i, o.turn_directions[i]));
    }
  }
  const double quarter = o.initial_heading_deg / 90.0;
  if (std::abs(quarter - std::round(quarter)) > 1e-9) {
    return absl::InvalidArgumentError(
        fmt::format("car route: initial_heading_deg = {} is not a multiple of 90 (Manhattan grid)",
                    o.initial_heading_deg));
  }
  if (kNanosecondsPerSecond % o.sample_rate_hz != 0) {
    return absl::InvalidArgumentError(
        fmt::format("car route: sample_rate_hz = {} has no integer ns period", o.sample_rate_hz));
  }
  return absl::OkStatus();
}

/// Appends the straight piece of leg i and (if not the last leg) the arc that follows it.
void add_leg(const CarRouteOptions& o, std::size_t i, int& quadrant, Vec2d& xy, double& s,
             std::vector<Piece>& pieces, CarRoute& route) {
  const Vec2d dir = axis_direction(quadrant);
  Piece straight;
  straight.s0 = s;
  straight.length = o.straight_lengths_m[i];
  straight.start = xy;
  straight.quadrant = quadrant;
  pieces.push_back(straight);
  route.straights.push_back({xy, xy + straight.length * dir, quadrant * kPi / 2.0, s});
  xy += straight.length * dir;
  s += straight.length;
  if (i + 1 == o.straight_lengths_m.size()) return;

  Piece arc;
  arc.is_arc = true;
  arc.s0 = s;
  arc.radius = o.turn_radii_m[i];
  arc.length = arc.radius * kPi / 2.0;
  arc.start = xy;
  arc.quadrant = quadrant;
  arc.direction = o.turn_directions[i];
  arc.center = xy + arc.direction * arc.radius * axis_direction(quadrant + 1);
  pieces.push_back(arc);
  const Vec2d corner = xy + arc.radius * dir;
  route.arcs.push_back({arc.center, arc.radius, quadrant * kPi / 2.0, arc.direction, corner, s});
  route.polyline_xy.push_back(corner);
  quadrant += arc.direction;
  xy = corner + arc.radius * axis_direction(quadrant);
  s += arc.length;
}

std::vector<Piece> build_geometry(const CarRouteOptions& o, CarRoute& route) {
  std::vector<Piece> pieces;
  int quadrant = static_cast<int>(std::lround(o.initial_heading_deg / 90.0));
  Vec2d xy = o.start_xy;
  double s = 0.0;
  route.polyline_xy.push_back(xy);
  for (std::size_t i = 0; i < o.straight_lengths_m.size(); ++i) add_leg(o, i, quadrant, xy, s, pieces, route);
  route.polyline_xy.push_back(xy);
  route.length_m = s;
  return pieces;
}

PathPoint path_at(const std::vector<Piece>& pieces, double s, std::size_t& hint) {
  while (hint + 1 < pieces.size() && s >= pieces[hint + 1].s0) ++hint;
  while (hint > 0 && s < pieces[hint].s0) --hint;
  const Piece& p = pieces[hint];
  const double ds = std::clamp(s - p.s0, 0.0, p.length);
  PathPoint out;
  const double h0 = p.quadrant * kPi / 2.0;
  if (!p.is_arc) {
    out.xy = p.start + ds * axis_direction(p.quadrant);
    out.heading = h0;
    return out;
  }
  out.curvature = p.direction / p.radius;
  out.heading = h0 + out.curvature * ds;
  // point = center - direction * R * left_normal(heading)
  const Vec2d normal(-std::sin(out.heading), std::cos(out.heading));
  out.xy = p.center - p.direction * p.radius * normal;
  return out;
}

/// Speed limit at arc length s: the lowest of the constant-acceleration envelopes.
double speed_limit(const CarRouteOptions& o, const std::vector<Piece>& pieces, double length, double s) {
  double v2 = o.cruise_speed_mps * o.cruise_speed_mps;
  v2 = std::min(v2, 2.0 * o.acceleration_mps2 * s);
  v2 = std::min(v2, 2.0 * o.braking_mps2 * (length - s));
  for (const Piece& p : pieces) {
    if (!p.is_arc) continue;
    const double v_arc2 =
        std::min(o.cruise_speed_mps * o.cruise_speed_mps, o.max_lateral_accel_mps2 * p.radius);
    const double end = p.s0 + p.length;
    if (s < p.s0) {
      v2 = std::min(v2, v_arc2 + 2.0 * o.braking_mps2 * (p.s0 - s));
    } else if (s > end) {
      v2 = std::min(v2, v_arc2 + 2.0 * o.acceleration_mps2 * (s - end));
    } else {
      v2 = std::min(v2, v_arc2);
    }
  }
  return std::sqrt(std::max(v2, 0.0));
}

/// Speed and time at s_i = i * step: t_{i+1} = t_i + 2 step / (v_i + v_{i+1}) (exact for
/// constant acceleration within a cell).
struct SpeedProfile {
  double step_m = 0.0;
  std::vector<double> v;  ///< m/s
  std::vector<double> t;  ///< s since the car started
};

SpeedProfile build_speed_profile(const CarRouteOptions& o, const std::vector<Piece>& pieces, double length) {
  SpeedProfile prof;
  const std::size_t cells = static_cast<std::size_t>(std::ceil(length / 0.01));
  prof.step_m = length / static_cast<double>(cells);
  prof.v.resize(cells + 1);
  prof.t.resize(cells + 1);
  for (std::size_t i = 0; i <= cells; ++i) {
    prof.v[i] = speed_limit(o, pieces, length, i == cells ? length : static_cast<double>(i) * prof.step_m);
  }
  prof.t[0] = 0.0;
  for (std::size_t i = 0; i < cells; ++i)
    prof.t[i + 1] = prof.t[i] + 2.0 * prof.step_m / (prof.v[i] + prof.v[i + 1]);
  return prof;
}

struct MotionState {
  double s = 0.0;  ///< m
  double v = 0.0;  ///< m/s
  double a = 0.0;  ///< m/s^2 along the path
};

MotionState motion_at(const SpeedProfile& prof, double tau, std::size_t& hint) {
  const std::size_t cells = prof.v.size() - 1;
  MotionState m;
  if (tau <= 0.0) return m;
  if (tau >= prof.t[cells]) {
    m.s = static_cast<double>(cells) * prof.step_m;
    return m;
  }
  while (hint + 1 < cells && prof.t[hint + 1] <= tau) ++hint;
  const double v0 = prof.v[hint];
  const double v1 = prof.v[hint + 1];
  m.a = (v1 * v1 - v0 * v0) / (2.0 * prof.step_m);
  const double dt = tau - prof.t[hint];
  m.s = static_cast<double>(hint) * prof.step_m + v0 * dt + 0.5 * m.a * dt * dt;
  m.v = v0 + m.a * dt;
  return m;
}

/// Road bumps as functions of the arc length.
struct Bumps {
  double z_amp[3], z_wavenumber[3], z_phase[3];
  double pitch_amp[3], pitch_wavenumber[3], pitch_phase[3];

  double z(double s) const { return sum(z_amp, z_wavenumber, z_phase, s); }
  double pitch(double s) const { return sum(pitch_amp, pitch_wavenumber, pitch_phase, s); }
  static double sum(const double* amp, const double* k, const double* phase, double s) {
    double out = 0.0;
    for (int j = 0; j < 3; ++j) out += amp[j] * std::sin(k[j] * s + phase[j]);
    return out;
  }
};

void draw_components(SequenceRng& rng, double amplitude, double wavelength, double* amp, double* k,
                     double* phase) {
  double weights[3];
  double total = 0.0;
  for (int j = 0; j < 3; ++j) {
    weights[j] = rng.uniform(0.5, 1.0);
    total += weights[j];
    k[j] = 2.0 * kPi / (wavelength * rng.uniform(0.8, 1.25));
    phase[j] = rng.uniform(0.0, 2.0 * kPi);
  }
  for (int j = 0; j < 3; ++j) amp[j] = amplitude * weights[j] / total;
}

Bumps draw_bumps(const CarRouteOptions& o, std::uint64_t seed) {
  SequenceRng rng(seed, Stream::kRoute);
  const double wavelength = o.cruise_speed_mps / o.bump_frequency_hz;
  Bumps b{};
  draw_components(rng, o.bump_amplitude_m, wavelength, b.z_amp, b.z_wavenumber, b.z_phase);
  draw_components(rng, o.bump_pitch_deg * kDegToRad, wavelength, b.pitch_amp, b.pitch_wavenumber,
                  b.pitch_phase);
  return b;
}

SE3d car_pose(const CarRouteOptions& o, const PathPoint& p, const MotionState& m, const Bumps& bumps) {
  const double a_lat = m.v * m.v * p.curvature;
  const double pitch = -o.pitch_per_long_accel_deg * kDegToRad * m.a + bumps.pitch(m.s);
  const double roll = o.roll_per_lat_accel_deg * kDegToRad * a_lat;
  const Quatd q = Quatd(Eigen::AngleAxisd(p.heading, Vec3d::UnitZ())) *
                  Quatd(Eigen::AngleAxisd(pitch, Vec3d::UnitY())) *
                  Quatd(Eigen::AngleAxisd(roll, Vec3d::UnitX()));
  return SE3d(q, Vec3d(p.xy.x(), p.xy.y(), o.imu_height_m + bumps.z(m.s)));
}

}  // namespace

CarRouteOptions test_car_route() { return CarRouteOptions{}; }

CarRouteOptions long_car_route() {
  CarRouteOptions o;
  o.straight_lengths_m = {150.0, 120.0, 150.0, 120.0, 150.0};
  o.turn_directions = {-1, 1, 1, -1};
  o.turn_radii_m = {18.0, 18.0, 18.0, 18.0};
  return o;
}

StatusOr<CarRoute> synthesize_car_route(const CarRouteOptions& options, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(validate_route(options));
  CarRoute route;
  const std::vector<Piece> pieces = build_geometry(options, route);
  if (!(route.length_m > 0.0)) return absl::InvalidArgumentError("car route: the route has zero length");
  const SpeedProfile profile = build_speed_profile(options, pieces, route.length_m);
  const Bumps bumps = draw_bumps(options, seed);

  const DurationNs period = kNanosecondsPerSecond / options.sample_rate_hz;
  const DurationNs rest_before = from_seconds(options.rest_before_s);
  const DurationNs motion = from_seconds(profile.t.back());
  const DurationNs total = rest_before + motion + from_seconds(options.rest_after_s);
  route.motion_begin_ns = options.start_time_ns + rest_before;
  route.motion_end_ns = route.motion_begin_ns + motion;
  std::size_t path_hint = 0;
  std::size_t motion_hint = 0;
  for (std::int64_t k = 0; k * period <= total; ++k) {
    const double tau = to_seconds(k * period - rest_before);
    const MotionState m = motion_at(profile, tau, motion_hint);
    const PathPoint p = path_at(pieces, m.s, path_hint);
    route.trajectory.push_back({options.start_time_ns + k * period, car_pose(options, p, m, bumps)});
  }
  return route;
}

}  // namespace mrvs::sim
