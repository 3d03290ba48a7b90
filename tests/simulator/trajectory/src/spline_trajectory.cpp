#include "mrvs/sim/spline_trajectory.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <fmt/format.h>

namespace mrvs::sim {
namespace {

/// Cumulative cubic B-spline basis and its first two time derivatives at u in [0, 1].
struct Basis {
  double b[3];    ///< B0, B1, B2
  double db[3];   ///< 1/s
  double ddb[3];  ///< 1/s^2
};

Basis cumulative_basis(double u, double inv_dt) {
  const double u2 = u * u;
  const double u3 = u2 * u;
  const double inv_dt2 = inv_dt * inv_dt;
  Basis basis{};
  basis.b[0] = (5.0 + 3.0 * u - 3.0 * u2 + u3) / 6.0;
  basis.b[1] = (1.0 + 3.0 * u + 3.0 * u2 - 2.0 * u3) / 6.0;
  basis.b[2] = u3 / 6.0;
  basis.db[0] = (3.0 - 6.0 * u + 3.0 * u2) / 6.0 * inv_dt;
  basis.db[1] = (3.0 + 6.0 * u - 6.0 * u2) / 6.0 * inv_dt;
  basis.db[2] = (3.0 * u2) / 6.0 * inv_dt;
  basis.ddb[0] = (-6.0 + 6.0 * u) / 6.0 * inv_dt2;
  basis.ddb[1] = (6.0 - 12.0 * u) / 6.0 * inv_dt2;
  basis.ddb[2] = (6.0 * u) / 6.0 * inv_dt2;
  return basis;
}

bool is_finite(const SE3d& T) { return T.translation().allFinite() && T.quaternion().coeffs().allFinite(); }

/// Fewer than 2 samples, non-finite values, degenerate quaternions, non-increasing stamps.
Status validate_input(const io::Trajectory& input) {
  if (input.size() < 2) {
    return absl::InvalidArgumentError(
        fmt::format("spline fit: the input trajectory needs at least 2 poses, got {}", input.size()));
  }
  for (std::size_t i = 0; i < input.size(); ++i) {
    const io::StampedPose& s = input[i];
    if (!is_finite(s.T_w_b)) {
      return absl::InvalidArgumentError(
          fmt::format("spline fit: pose {} (t = {} ns) has a non-finite value", i, s.t_ns));
    }
    const double norm = s.T_w_b.quaternion().norm();
    if (std::abs(norm - 1.0) > 1e-6) {
      return absl::InvalidArgumentError(fmt::format(
          "spline fit: pose {} (t = {} ns) has a degenerate rotation (|q| = {})", i, s.t_ns, norm));
    }
    if (i > 0 && s.t_ns <= input[i - 1].t_ns) {
      return absl::InvalidArgumentError(
          fmt::format("spline fit: stamps must strictly increase, but pose {} (t = {} ns) is not after "
                      "pose {} (t = {} ns)",
                      i, s.t_ns, i - 1, input[i - 1].t_ns));
    }
  }
  return absl::OkStatus();
}

/// Knot spacing in ns, a multiple of 1 us.
StatusOr<DurationNs> choose_knot_spacing(const io::Trajectory& input, const TrajectoryOptions& options) {
  if (options.knot_spacing_s > 0.0) {
    const DurationNs knot = std::llround(options.knot_spacing_s * 1e6) * 1000;
    if (knot <= 0) {
      return absl::InvalidArgumentError(
          fmt::format("spline fit: knot_spacing_s = {} s rounds to 0 us", options.knot_spacing_s));
    }
    return knot;
  }
  const DurationNs span = input.back().t_ns - input.front().t_ns;
  const DurationNs mean_dt = span / static_cast<std::int64_t>(input.size() - 1);
  return ceil_to_microsecond(std::max(mean_dt, kMinAutoKnotSpacingNs));
}

/// Rejects gaps the spline would silently bridge.
Status check_gaps(const io::Trajectory& input, DurationNs knot_ns) {
  const DurationNs max_gap = std::max<DurationNs>(kNanosecondsPerSecond, 4 * knot_ns);
  for (std::size_t i = 1; i < input.size(); ++i) {
    const DurationNs gap = input[i].t_ns - input[i - 1].t_ns;
    if (gap > max_gap) {
      return absl::InvalidArgumentError(
          fmt::format("spline fit: the input has a gap of {:.3f} s between pose {} (t = {} ns) and pose {}; "
                      "gaps longer than {:.3f} s are rejected",
                      to_seconds(gap), i - 1, input[i - 1].t_ns, i, to_seconds(max_gap)));
    }
  }
  return absl::OkStatus();
}

/// Index of the first knot j >= 2 at which the spline's path length, measured from t_2,
/// exceeds distance_m (10 sub-steps per knot).
StatusOr<std::size_t> first_knot_beyond_path_length(const SplineTrajectory& spline, double distance_m) {
  const std::size_t n = spline.control_points().size();
  const DurationNs knot = spline.knot_spacing_ns();
  const TimestampNs t0 = spline.first_control_point_ns();
  constexpr int kSubSteps = 10;
  double length = 0.0;
  MRVS_ASSIGN_OR_RETURN(Kinematics previous, spline.evaluate(t0 + 2 * knot));
  for (std::size_t j = 3; j + 2 <= n; ++j) {
    const TimestampNs t_start = t0 + static_cast<std::int64_t>(j - 1) * knot;
    for (int s = 1; s <= kSubSteps; ++s) {
      const TimestampNs t = t_start + knot * s / kSubSteps;
      MRVS_ASSIGN_OR_RETURN(Kinematics current, spline.evaluate(t));
      length += (current.T_w_b.translation() - previous.T_w_b.translation()).norm();
      previous = current;
    }
    if (length > distance_m) return j;
  }
  return absl::InvalidArgumentError(fmt::format(
      "start_at_motion_m = {} m: the trajectory's path length is only {:.3f} m", distance_m, length));
}

/// Drops the control points before the motion start (start_at_motion_m).
Status skip_to_motion(double distance_m, DurationNs knot_ns, TimestampNs& t_first_ns,
                      std::vector<SE3d>& cps) {
  MRVS_ASSIGN_OR_RETURN(const SplineTrajectory full,
                        SplineTrajectory::from_control_points(t_first_ns, knot_ns, cps));
  MRVS_ASSIGN_OR_RETURN(const std::size_t j, first_knot_beyond_path_length(full, distance_m));
  // Keep P_{j-2} onwards: the new t_2 is the old t_j.
  const std::size_t drop = j - 2;
  if (cps.size() - drop < 5) {
    return absl::InvalidArgumentError(
        fmt::format("start_at_motion_m = {} m leaves less than one knot of trajectory", distance_m));
  }
  cps.erase(cps.begin(), cps.begin() + static_cast<std::ptrdiff_t>(drop));
  t_first_ns += static_cast<std::int64_t>(drop) * knot_ns;
  return absl::OkStatus();
}

/// Prepends ceil(S / knot) + 3 copies of the first control point.
void prepend_static_prefix(double prefix_s, DurationNs knot_ns, TimestampNs& t_first_ns,
                           std::vector<SE3d>& cps) {
  const DurationNs prefix_ns = from_seconds(prefix_s);
  const std::int64_t copies = (prefix_ns + knot_ns - 1) / knot_ns + 3;
  cps.insert(cps.begin(), static_cast<std::size_t>(copies), cps.front());
  t_first_ns -= copies * knot_ns;
}

/// The data window of `options` (defaults: the whole valid range).
Status apply_window(const TrajectoryOptions& options, SplineTrajectory& spline) {
  const TimestampNs lo = spline.t_begin_ns();
  const TimestampNs hi = spline.t_end_ns();
  const bool absolute = options.window_start_ns != 0;
  const TimestampNs start =
      ceil_to_microsecond(absolute ? options.window_start_ns : lo + from_seconds(options.window_start_s));
  const TimestampNs end =
      options.window_duration_s > 0.0 ? start + from_seconds(options.window_duration_s) : hi;
  if (start < lo || end > hi || start > end) {
    return absl::OutOfRangeError(fmt::format(
        "trajectory window [{} ns, {} ns] (start {:.6f} s after the first usable time, duration {:.6f} s) "
        "lies outside the valid range [{} ns, {} ns] (0 to {:.6f} s)",
        start, end, to_seconds(start - lo), to_seconds(end - start), lo, hi, to_seconds(hi - lo)));
  }
  return spline.set_window(start, end);
}

}  // namespace

TimestampNs ceil_to_microsecond(TimestampNs t_ns) {
  const std::int64_t r = t_ns % 1000;
  if (r == 0) return t_ns;
  return r > 0 ? t_ns - r + 1000 : t_ns - r;
}

std::vector<SE3d> resample_control_points(const io::Trajectory& input, TimestampNs t_first_ns,
                                          DurationNs knot_ns) {
  std::vector<SE3d> out;
  if (input.empty() || knot_ns <= 0) return out;
  const TimestampNs t_last = input.back().t_ns;
  std::size_t j = 0;
  for (TimestampNs t = t_first_ns; t <= t_last;
       t = t_first_ns + static_cast<std::int64_t>(out.size()) * knot_ns) {
    while (j + 1 < input.size() && input[j + 1].t_ns <= t) ++j;
    SE3d pose = input[j].T_w_b;
    if (j + 1 < input.size() && t > input[j].t_ns) {
      const io::StampedPose& a = input[j];
      const io::StampedPose& b = input[j + 1];
      const double lambda = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
      const Vec3d p = (1.0 - lambda) * a.T_w_b.translation() + lambda * b.T_w_b.translation();
      pose = SE3d(a.T_w_b.quaternion().slerp(lambda, b.T_w_b.quaternion()), p);
    }
    if (!out.empty() && pose.quaternion().dot(out.back().quaternion()) < 0.0) {
      Quatd q = pose.quaternion();
      q.coeffs() = -q.coeffs();
      pose.set_quaternion(q);
    }
    out.push_back(pose);
  }
  return out;
}

StatusOr<SplineTrajectory> SplineTrajectory::from_control_points(TimestampNs t_first_ns, DurationNs knot_ns,
                                                                 std::vector<SE3d> control_points) {
  if (knot_ns <= 0) {
    return absl::InvalidArgumentError(fmt::format("spline: knot spacing must be > 0 ns, got {}", knot_ns));
  }
  if (control_points.size() < 5) {
    return absl::InvalidArgumentError(
        fmt::format("spline: a cubic B-spline with one knot of valid range needs at least 5 control points, "
                    "got {} (the input spans less than 4 knots = {:.3f} s)",
                    control_points.size(), to_seconds(4 * knot_ns)));
  }
  SplineTrajectory s;
  s.t_first_ns_ = t_first_ns;
  s.knot_ns_ = knot_ns;
  const std::size_t n = control_points.size();
  s.q_.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    if (!is_finite(control_points[k])) {
      return absl::InvalidArgumentError(fmt::format("spline: control point {} has a non-finite value", k));
    }
    Quatd q = control_points[k].quaternion();
    if (k > 0 && q.dot(s.q_.back()) < 0.0) q.coeffs() = -q.coeffs();
    s.q_.push_back(q);
  }
  s.delta_p_.resize(n - 1);
  s.delta_phi_.resize(n - 1);
  for (std::size_t k = 0; k + 1 < n; ++k) {
    s.delta_p_[k] = control_points[k + 1].translation() - control_points[k].translation();
    // Identical rotations (static prefix) give exactly zero, not a rounding residue.
    s.delta_phi_[k] = s.q_[k].coeffs() == s.q_[k + 1].coeffs()
                          ? Vec3d::Zero()
                          : Vec3d(so3::log(s.q_[k].conjugate() * s.q_[k + 1]));
  }
  s.control_points_ = std::move(control_points);
  s.t_begin_ns_ = ceil_to_microsecond(t_first_ns + 2 * knot_ns);
  s.t_end_ns_ = s.support_end_ns();
  if (s.t_begin_ns_ > s.t_end_ns_) {
    return absl::InvalidArgumentError("spline: the valid range holds no whole microsecond");
  }
  return s;
}

StatusOr<SplineTrajectory> SplineTrajectory::fit(const io::Trajectory& input,
                                                 const TrajectoryOptions& options) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "trajectory"));
  MRVS_RETURN_IF_ERROR(validate_input(input));
  MRVS_ASSIGN_OR_RETURN(const DurationNs knot, choose_knot_spacing(input, options));
  MRVS_RETURN_IF_ERROR(check_gaps(input, knot));
  TimestampNs t_first = ceil_to_microsecond(input.front().t_ns);
  std::vector<SE3d> cps = resample_control_points(input, t_first, knot);
  if (cps.size() < 5) {
    return absl::InvalidArgumentError(fmt::format(
        "spline fit: the input spans {:.6f} s, too short for a cubic B-spline with knot spacing "
        "{:.6f} s (needs at least 4 knots = {:.6f} s)",
        to_seconds(input.back().t_ns - input.front().t_ns), to_seconds(knot), to_seconds(4 * knot)));
  }
  if (options.start_at_motion_m > 0.0) {
    MRVS_RETURN_IF_ERROR(skip_to_motion(options.start_at_motion_m, knot, t_first, cps));
  }
  if (options.static_prefix_s > 0.0) prepend_static_prefix(options.static_prefix_s, knot, t_first, cps);
  MRVS_ASSIGN_OR_RETURN(SplineTrajectory spline, from_control_points(t_first, knot, std::move(cps)));
  MRVS_RETURN_IF_ERROR(apply_window(options, spline));
  return spline;
}

Status SplineTrajectory::set_window(TimestampNs t_begin_ns, TimestampNs t_end_ns) {
  const TimestampNs lo = ceil_to_microsecond(t_first_ns_ + 2 * knot_ns_);
  const TimestampNs hi = support_end_ns();
  const TimestampNs begin = ceil_to_microsecond(t_begin_ns);
  if (begin < lo || t_end_ns > hi || begin > t_end_ns) {
    return absl::OutOfRangeError(
        fmt::format("spline: window [{} ns, {} ns] is outside the valid range [{} ns, {} ns] ({:.6f} s long)",
                    begin, t_end_ns, lo, hi, to_seconds(hi - lo)));
  }
  t_begin_ns_ = begin;
  t_end_ns_ = t_end_ns;
  return absl::OkStatus();
}

StatusOr<Kinematics> SplineTrajectory::evaluate(TimestampNs t_ns) const {
  if (t_ns < support_begin_ns() || t_ns > support_end_ns()) {
    return absl::OutOfRangeError(
        fmt::format("spline: t = {} ns is outside the evaluable range [{} ns, {} ns]", t_ns,
                    support_begin_ns(), support_end_ns()));
  }
  const std::int64_t n = static_cast<std::int64_t>(control_points_.size());
  const std::int64_t rel = t_ns - t_first_ns_;
  const std::int64_t i = std::min(rel / knot_ns_, n - 3);
  const double u = static_cast<double>(rel - i * knot_ns_) / static_cast<double>(knot_ns_);
  const Basis basis = cumulative_basis(u, 1e9 / static_cast<double>(knot_ns_));
  const std::size_t k0 = static_cast<std::size_t>(i - 1);

  Kinematics out;
  Vec3d p = control_points_[k0].translation();
  for (std::size_t j = 0; j < 3; ++j) {
    const Vec3d& d = delta_p_[k0 + j];
    p += basis.b[j] * d;
    out.v_w += basis.db[j] * d;
    out.a_w += basis.ddb[j] * d;
  }
  // R = R_{i-1} A0 A1 A2; omega = A2^T A1^T w0 + A2^T w1 + w2, w_j = dB_j W_j.
  Quatd a[3];
  for (std::size_t j = 0; j < 3; ++j) a[j] = so3::exp_quat<double>(basis.b[j] * delta_phi_[k0 + j]);
  const Quatd q = q_[k0] * a[0] * a[1] * a[2];
  Vec3d omega = basis.db[0] * delta_phi_[k0];
  omega = a[1].conjugate() * omega + basis.db[1] * delta_phi_[k0 + 1];
  omega = a[2].conjugate() * omega + basis.db[2] * delta_phi_[k0 + 2];
  out.omega_b = omega;
  out.T_w_b = SE3d(q, p);
  return out;
}

}  // namespace mrvs::sim
