// Error statistics, absolute trajectory error and relative pose error.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/quaternion.h"

namespace mrvs::eval {
namespace {

/// Rotation angle (deg) between two orientations.
double angle_deg(const Quatd& a, const Quatd& b) { return quat::angular_distance(a, b) * kRadToDeg; }

}  // namespace

double heading_about_z_deg(const Quatd& q) {
  // The twist about z of q = (w, x, y, z) is the rotation (cos(a / 2), 0, 0, sin(a / 2)) with
  // a = 2 atan2(z, w); q and -q are the same rotation, so a is wrapped into (-180, 180].
  double a = 2.0 * std::atan2(q.z(), q.w()) * kRadToDeg;
  if (a > 180.0) a -= 360.0;
  if (a <= -180.0) a += 360.0;
  return a;
}

StatusOr<ErrorStats> compute_stats(const std::vector<double>& errors) {
  if (errors.empty()) return absl::InvalidArgumentError("no errors to summarise (empty set)");
  ErrorStats s;
  s.count = errors.size();
  const double n = static_cast<double>(s.count);
  double sum = 0.0;
  double sum_sq = 0.0;
  for (double e : errors) {
    sum += e;
    sum_sq += e * e;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  double var = 0.0;
  for (double e : errors) var += (e - s.mean) * (e - s.mean);
  s.std = std::sqrt(var / n);
  const auto [min_it, max_it] = std::minmax_element(errors.begin(), errors.end());
  s.min = *min_it;
  s.max = *max_it;
  std::vector<double> sorted = errors;
  const std::size_t mid = sorted.size() / 2;
  std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid), sorted.end());
  s.median = sorted[mid];
  if (sorted.size() % 2 == 0) {
    const double lower = *std::max_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(mid));
    s.median = 0.5 * (s.median + lower);
  }
  return s;
}

StatusOr<AteResult> compute_ate(const Association& association, const Alignment& alignment) {
  if (association.matches.empty())
    return absl::InvalidArgumentError("ATE needs at least 1 associated pose, got 0");
  AteResult out;
  out.alignment = alignment;
  out.position_errors_m.reserve(association.matches.size());
  out.rotation_errors_deg.reserve(association.matches.size());
  out.heading_errors_deg.reserve(association.matches.size());
  std::vector<double> heading_magnitudes;
  for (const Match& m : association.matches) {
    const SE3d T_wgt_b_est = alignment.apply(m.T_west_b);
    out.position_errors_m.push_back((m.T_wgt_b.translation() - T_wgt_b_est.translation()).norm());
    out.rotation_errors_deg.push_back(angle_deg(m.T_wgt_b.quaternion(), T_wgt_b_est.quaternion()));
    const Quatd world_error = m.T_wgt_b.quaternion() * T_wgt_b_est.quaternion().conjugate();
    out.heading_errors_deg.push_back(heading_about_z_deg(world_error));
    heading_magnitudes.push_back(std::abs(out.heading_errors_deg.back()));
  }
  MRVS_ASSIGN_OR_RETURN(out.position_m, compute_stats(out.position_errors_m));
  MRVS_ASSIGN_OR_RETURN(out.rotation_deg, compute_stats(out.rotation_errors_deg));
  MRVS_ASSIGN_OR_RETURN(out.heading_deg, compute_stats(heading_magnitudes));
  return out;
}

std::vector<std::pair<std::size_t, std::size_t>> select_rpe_pairs(const std::vector<double>& key,
                                                                  double delta) {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i + 1 < key.size(); ++i) {
    const double target = key[i] + delta;
    const auto first = key.begin() + static_cast<std::ptrdiff_t>(i + 1);
    const auto it = std::lower_bound(first, key.end(), target);
    if (it == key.end()) break;  // key is non-decreasing: no later i reaches delta either
    std::size_t j = static_cast<std::size_t>(it - key.begin());
    if (j - 1 > i && std::abs(key[j - 1] - target) < std::abs(key[j] - target)) --j;
    pairs.emplace_back(i, j);
  }
  return pairs;
}

std::vector<double> ground_truth_path_length(const Association& association) {
  std::vector<double> length(association.matches.size(), 0.0);
  for (std::size_t i = 1; i < length.size(); ++i) {
    const Vec3d step =
        association.matches[i].T_wgt_b.translation() - association.matches[i - 1].T_wgt_b.translation();
    length[i] = length[i - 1] + step.norm();
  }
  return length;
}

StatusOr<RpeResult> compute_rpe(const Association& association, const RpeOptions& options, double scale) {
  const char* unit = options.unit == RpeUnit::kMetres ? "m" : "s";
  if (!(options.delta > 0.0) || !std::isfinite(options.delta)) {
    return absl::InvalidArgumentError(fmt::format("RPE delta must be > 0, got {} {}", options.delta, unit));
  }
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    return absl::InvalidArgumentError(fmt::format("RPE scale must be > 0, got {}", scale));
  }
  const std::vector<Match>& m = association.matches;
  std::vector<double> key;
  if (options.unit == RpeUnit::kMetres) {
    key = ground_truth_path_length(association);
  } else {
    key.reserve(m.size());
    for (const Match& match : m) key.push_back(to_seconds(match.t_ns - m.front().t_ns));
  }
  const auto pairs = select_rpe_pairs(key, options.delta);
  if (pairs.empty()) {
    return absl::FailedPreconditionError(
        fmt::format("RPE: no pose pair is {} {} apart (the {} associated poses span {} {})", options.delta,
                    unit, m.size(), key.empty() ? 0.0 : key.back() - key.front(), unit));
  }
  RpeResult out;
  out.options = options;
  out.num_pairs = pairs.size();
  std::vector<double> trans;
  std::vector<double> rot;
  trans.reserve(pairs.size());
  rot.reserve(pairs.size());
  double delta_sum = 0.0;
  for (const auto& [i, j] : pairs) {
    SE3d est_i = m[i].T_west_b;
    SE3d est_j = m[j].T_west_b;
    est_i.translation() *= scale;
    est_j.translation() *= scale;
    const SE3d E = (m[i].T_wgt_b.inverse() * m[j].T_wgt_b).inverse() * (est_i.inverse() * est_j);
    trans.push_back(E.translation().norm());
    rot.push_back(angle_deg(Quatd::Identity(), E.quaternion()));
    delta_sum += key[j] - key[i];
  }
  out.mean_pair_delta = delta_sum / static_cast<double>(pairs.size());
  MRVS_ASSIGN_OR_RETURN(out.translation_m, compute_stats(trans));
  MRVS_ASSIGN_OR_RETURN(out.rotation_deg, compute_stats(rot));
  return out;
}

}  // namespace mrvs::eval
