// Timestamp association of an estimated trajectory with ground truth.
#include <algorithm>
#include <iterator>
#include <limits>

#include <fmt/format.h>

#include "mrvs/eval/trajectory_eval.h"

namespace mrvs::eval {
namespace {

bool is_finite(const SE3d& T) { return T.translation().allFinite() && T.quaternion().coeffs().allFinite(); }

/// Non-empty, finite, strictly increasing in time.
Status validate(const io::Trajectory& trajectory, const char* what) {
  if (trajectory.empty()) {
    return absl::InvalidArgumentError(fmt::format("{} trajectory is empty", what));
  }
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    if (!is_finite(trajectory[i].T_w_b)) {
      return absl::InvalidArgumentError(
          fmt::format("{} trajectory has a non-finite pose at index {} (t = {} s)", what, i,
                      format_seconds(trajectory[i].t_ns)));
    }
    if (i > 0 && trajectory[i].t_ns <= trajectory[i - 1].t_ns) {
      return absl::InvalidArgumentError(
          fmt::format("{} trajectory is not strictly increasing in time at index {} (t = {} s after {} s)",
                      what, i, format_seconds(trajectory[i].t_ns), format_seconds(trajectory[i - 1].t_ns)));
    }
  }
  return absl::OkStatus();
}

/// |a - b|, saturated at the largest DurationNs instead of overflowing.
DurationNs abs_diff(TimestampNs a, TimestampNs b) {
  DurationNs d = 0;
  if (__builtin_sub_overflow(a > b ? a : b, a > b ? b : a, &d)) return std::numeric_limits<DurationNs>::max();
  return d;
}

/// Ground truth at time t, or false when no sample lies within tolerance.
bool lookup(const io::Trajectory& gt, TimestampNs t, DurationNs max_dt, Match* match) {
  const auto next = std::upper_bound(
      gt.begin(), gt.end(), t, [](TimestampNs value, const io::StampedPose& p) { return value < p.t_ns; });
  const bool has_prev = next != gt.begin();
  const bool has_next = next != gt.end();
  if (has_prev && std::prev(next)->t_ns == t) {
    match->T_wgt_b = std::prev(next)->T_w_b;
    match->kind = MatchKind::kExact;
    return true;
  }
  const DurationNs dt_prev = has_prev ? abs_diff(t, std::prev(next)->t_ns) : 0;
  const DurationNs dt_next = has_next ? abs_diff(next->t_ns, t) : 0;
  const bool prev_ok = has_prev && dt_prev <= max_dt;
  const bool next_ok = has_next && dt_next <= max_dt;
  if (prev_ok && next_ok) {
    const auto& a = *std::prev(next);
    const auto& b = *next;
    const double alpha = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
    match->T_wgt_b = interpolate_pose(a.T_w_b, b.T_w_b, alpha);
    match->kind = MatchKind::kInterpolated;
    return true;
  }
  if (prev_ok || next_ok) {
    match->T_wgt_b = prev_ok ? std::prev(next)->T_w_b : next->T_w_b;
    match->kind = MatchKind::kNearest;
    return true;
  }
  return false;
}

Status no_match_error(const io::Trajectory& est, const io::Trajectory& gt,
                      const AssociationOptions& options) {
  return absl::NotFoundError(fmt::format(
      "no estimate pose has ground truth within max_dt = {} s: estimate spans [{}, {}] s (time offset {} s "
      "added), ground truth spans [{}, {}] s",
      format_seconds(options.max_dt_ns), format_seconds(est.front().t_ns), format_seconds(est.back().t_ns),
      format_seconds(options.time_offset_ns), format_seconds(gt.front().t_ns),
      format_seconds(gt.back().t_ns)));
}

}  // namespace

SE3d interpolate_pose(const SE3d& a, const SE3d& b, double alpha) {
  const Vec3d t = (1.0 - alpha) * a.translation() + alpha * b.translation();
  return SE3d(a.quaternion().slerp(alpha, b.quaternion()), t);
}

StatusOr<Association> associate(const io::Trajectory& estimate, const io::Trajectory& ground_truth,
                                const AssociationOptions& options) {
  if (options.max_dt_ns < 0) {
    return absl::InvalidArgumentError(
        fmt::format("max_dt must be >= 0, got {} s", format_seconds(options.max_dt_ns)));
  }
  MRVS_RETURN_IF_ERROR(validate(estimate, "estimate"));
  MRVS_RETURN_IF_ERROR(validate(ground_truth, "ground-truth"));
  Association out;
  out.matches.reserve(estimate.size());
  for (const io::StampedPose& pose : estimate) {
    Match match;
    if (__builtin_add_overflow(pose.t_ns, options.time_offset_ns, &match.t_ns)) {
      return absl::InvalidArgumentError(fmt::format("time offset {} s overflows the estimate stamp {} s",
                                                    format_seconds(options.time_offset_ns),
                                                    format_seconds(pose.t_ns)));
    }
    if (!lookup(ground_truth, match.t_ns, options.max_dt_ns, &match)) {
      ++out.num_unmatched;
      continue;
    }
    match.T_west_b = pose.T_w_b;
    switch (match.kind) {
      case MatchKind::kExact:
        ++out.num_exact;
        break;
      case MatchKind::kInterpolated:
        ++out.num_interpolated;
        break;
      case MatchKind::kNearest:
        ++out.num_nearest;
        break;
    }
    out.matches.push_back(match);
  }
  if (out.matches.empty()) return no_match_error(estimate, ground_truth, options);
  return out;
}

}  // namespace mrvs::eval
