#pragma once
// The simulator's ground truth: a uniform cubic B-spline fitted to a trajectory
// (simulator.md section 2.2, "split" variant).
//
// - Translation: ordinary uniform cubic B-spline in R^3,
//     p(t) = P_{i-1} + B0(u) dP_{i-1} + B1(u) dP_i + B2(u) dP_{i+1},  dP_k = P_{k+1} - P_k.
// - Rotation: cumulative cubic B-spline on SO(3),
//     R(t) = R_{i-1} exp(B0(u) W_{i-1}) exp(B1(u) W_i) exp(B2(u) W_{i+1}),  W_k = log(R_k^T R_{k+1}),
//   with the cumulative basis B0 = (5 + 3u - 3u^2 + u^3)/6, B1 = (1 + 3u + 3u^2 - 2u^3)/6,
//   B2 = u^3/6, for t in [t_i, t_i + knot], u = (t - t_i) / knot.
// Control point k sits at t_k = first_control_point_ns + k * knot_ns; the curve at u = 0 is
// (P_{i-1} + 4 P_i + P_{i+1}) / 6 (centred, no time lag): the spline approximates the
// control points, it does not interpolate them. Segment i needs P_{i-1} .. P_{i+2}.
//
// Times: int64 ns everywhere. The segment index and u come from integer ns offsets, so no
// absolute epoch time ever passes through a double.
//
// Ranges:
// - support [support_begin_ns, support_end_ns] = [t_1, t_{N-2}]: where evaluate() works
//   (mathematically defined). Outside it evaluate() returns an OutOfRange error (no clamp).
// - data window [t_begin_ns, t_end_ns] within [t_2, t_{N-2}]: where the generator writes
//   data (section 2.2 "Validity": start >= 2 knots after the first control point, as
//   OpenVINS, stop >= 1 knot before the last). t_begin_ns is t0_ns of section 1.2: a
//   multiple of 1 us. The margin of >= 1 knot before t_begin_ns lets IMU averaging over
//   [t_k - dt, t_k] (dt <= knot) and motion blur look slightly before the window.
#include <cstdint>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/types.h"

namespace mrvs::sim {

/// Smallest knot spacing picked automatically (OpenVINS BsplineSE3 clamps to this), ns.
inline constexpr DurationNs kMinAutoKnotSpacingNs = 50'000'000;

/// Fit and start-handling options (simulator.md sections 2.2 and 2.7). Applied in this
/// order: knot spacing, start_at_motion_m, static_prefix_s, window.
struct TrajectoryOptions : config::OptionsEquality<TrajectoryOptions> {
  /// Knot spacing, s (rounded to 1 us). 0 = automatic: max(mean input dt, 0.05 s).
  double knot_spacing_s = 0.0;
  /// Exact rest prepended before the first (kept) control point, s: the first
  /// static_prefix_s seconds of the data window (closed interval) have exactly zero
  /// velocity, acceleration and angular rate; then a C2 blend of about 3 knots follows.
  /// Implemented as ceil(S / knot) + 3 copies of the first control point. 0 = off.
  double static_prefix_s = 0.0;
  /// Skip forward until the path length of the spline (from the first valid time) exceeds
  /// this many metres; the data window starts at the first knot time where it does
  /// (OpenVINS sim_distance_threshold). 0 = off.
  double start_at_motion_m = 0.0;
  /// Start of the data window, s after the first usable time (after the two options above).
  double window_start_s = 0.0;
  /// Absolute start of the data window, ns since the epoch (same clock as the input);
  /// overrides window_start_s when non-zero.
  std::int64_t window_start_ns = 0;
  /// Length of the data window, s. 0 = up to the end of the valid range.
  double window_duration_s = 0.0;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("knot_spacing_s", knot_spacing_s, in_range(0.0, 10.0), "s, 0 = max(mean input dt, 0.05 s)");
    v("static_prefix_s", static_prefix_s, in_range(0.0, 3600.0), "s of exact rest at the start, 0 = off");
    v("start_at_motion_m", start_at_motion_m, at_least(0.0), "m of path skipped at the start, 0 = off");
    v("window_start_s", window_start_s, at_least(0.0), "s after the first usable time");
    v("window_start_ns", window_start_ns, at_least(std::int64_t{0}),
      "absolute window start, ns (0 = use window_start_s)");
    v("window_duration_s", window_duration_s, at_least(0.0), "s, 0 = to the end of the valid range");
  }
};

/// State of the spline at one instant.
struct Kinematics {
  SE3d T_w_b;                     ///< pose of the body (IMU) in the world
  Vec3d v_w = Vec3d::Zero();      ///< velocity of the body origin in the world frame, m/s
  Vec3d a_w = Vec3d::Zero();      ///< acceleration in the world frame (no gravity), m/s^2
  Vec3d omega_b = Vec3d::Zero();  ///< angular rate in the BODY frame, vee(R^T dR/dt), rad/s
};

class SplineTrajectory {
 public:
  /// Spline through explicit control points: P_k at t_first_ns + k * knot_ns. Needs at least
  /// 5 points (one knot of valid range) and knot_ns > 0. The data window is the whole valid
  /// range [t_2, t_{N-2}] (t_2 rounded up to 1 us). Error on non-finite values.
  static StatusOr<SplineTrajectory> from_control_points(TimestampNs t_first_ns, DurationNs knot_ns,
                                                        std::vector<SE3d> control_points);

  /// Fits the spline to `input` (T_w_b samples, strictly increasing stamps): control points
  /// are the input resampled at the knot step (position lerp + quaternion slerp between the
  /// bracketing samples) on the grid ceil_1us(first stamp) + k * knot, then `options`
  /// (start handling, window) are applied. Errors name the problem: fewer than 2 samples,
  /// non-increasing stamps, non-finite values, a gap longer than max(1 s, 4 knots), an input
  /// too short for the knot spacing, a window outside the valid range (the message gives
  /// the valid range).
  static StatusOr<SplineTrajectory> fit(const io::Trajectory& input, const TrajectoryOptions& options = {});

  /// Pose, velocity, acceleration and body angular rate at t_ns. OutOfRange error outside
  /// [support_begin_ns(), support_end_ns()].
  StatusOr<Kinematics> evaluate(TimestampNs t_ns) const;

  /// First time of the data window (t0_ns of simulator.md 1.2; a multiple of 1 us).
  TimestampNs t_begin_ns() const { return t_begin_ns_; }
  /// Last time of the data window (inclusive).
  TimestampNs t_end_ns() const { return t_end_ns_; }
  /// evaluate() accepts [support_begin_ns(), support_end_ns()] = [t_1, t_{N-2}].
  TimestampNs support_begin_ns() const { return t_first_ns_ + knot_ns_; }
  TimestampNs support_end_ns() const {
    return t_first_ns_ + static_cast<std::int64_t>(control_points_.size() - 2) * knot_ns_;
  }
  /// Knot spacing, ns.
  DurationNs knot_spacing_ns() const { return knot_ns_; }
  /// Time of control point 0, ns.
  TimestampNs first_control_point_ns() const { return t_first_ns_; }
  /// The control points (including static-prefix copies).
  const std::vector<SE3d>& control_points() const { return control_points_; }

  /// Restricts the data window to [t_begin_ns, t_end_ns] (t_begin_ns rounded up to 1 us).
  /// Error, naming the allowed range, unless t_2 <= t_begin <= t_end <= t_{N-2}.
  Status set_window(TimestampNs t_begin_ns, TimestampNs t_end_ns);

 private:
  SplineTrajectory() = default;

  TimestampNs t_first_ns_ = 0;
  DurationNs knot_ns_ = 0;
  std::vector<SE3d> control_points_;
  std::vector<Vec3d> delta_p_;    ///< P_{k+1} - P_k, m
  std::vector<Vec3d> delta_phi_;  ///< log(R_k^T R_{k+1}), rad (exactly 0 for equal rotations)
  std::vector<Quatd> q_;          ///< control rotations, sign-continuous
  TimestampNs t_begin_ns_ = 0;
  TimestampNs t_end_ns_ = 0;
};

/// Rounds t_ns up to the next multiple of 1 us (1000 ns); negative values too.
TimestampNs ceil_to_microsecond(TimestampNs t_ns);

/// Control points of `input` resampled at t_first_ns + k * knot_ns for every such time in
/// [t_first_ns, last stamp] (position lerp + quaternion slerp, sign-continuous). The input
/// must be valid (see SplineTrajectory::fit) and t_first_ns >= its first stamp.
std::vector<SE3d> resample_control_points(const io::Trajectory& input, TimestampNs t_first_ns,
                                          DurationNs knot_ns);

}  // namespace mrvs::sim
