#include "mrvs/edge/preintegration.h"

#include <algorithm>

#include <fmt/format.h>

#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

/// The sample points of [t0, t1]: interpolated ends and every sample strictly inside.
StatusOr<std::vector<io::ImuSample>> sample_points(const std::vector<io::ImuSample>& samples,
                                                   TimestampNs t0_ns, TimestampNs t1_ns) {
  const auto by_time = [](const io::ImuSample& s, TimestampNs t) { return s.t_ns < t; };
  auto first = std::lower_bound(samples.begin(), samples.end(), t0_ns + 1, by_time);
  auto last = std::lower_bound(samples.begin(), samples.end(), t1_ns, by_time);
  if (first == samples.begin() || last == samples.end() || first == samples.end()) {
    return absl::OutOfRangeError(fmt::format("no IMU coverage for {} .. {} ns (IMU buffer {} .. {} ns)",
                                             t0_ns, t1_ns, samples.empty() ? 0 : samples.front().t_ns,
                                             samples.empty() ? 0 : samples.back().t_ns));
  }
  --first;  // the last sample at or before t0
  std::vector<io::ImuSample> pts;
  pts.push_back(interpolate_sample(*first, *(first + 1), t0_ns));
  for (auto it = first + 1; it != samples.end() && it->t_ns < t1_ns; ++it) pts.push_back(*it);
  pts.push_back(last == samples.begin() ? *last : interpolate_sample(*(last - 1), *last, t1_ns));
  return pts;
}

/// One step of length dt with the mean bias-corrected rates (w, a): the deltas, their bias
/// Jacobians and the covariance move forward.
void step(const Vec3d& w, const Vec3d& a, double dt, const ImuNoise& noise, Preintegration* pre) {
  const Vec3d h = w * dt;
  const Mat3d E = so3::exp<double>(h);
  const Mat3d Eh = so3::exp<double>(Vec3d(0.5 * h));
  const Mat3d Jr = so3::right_jacobian<double>(h);
  const Mat3d Jr_half = so3::right_jacobian<double>(Vec3d(0.5 * h));
  const Mat3d R = pre->dq.toRotationMatrix();
  const Mat3d R_mid = R * Eh;
  const Vec3d acc = R_mid * a;
  const Mat3d Ra_x = R_mid * skew<double>(a);
  // Bias Jacobians (the midpoint rotation depends on bg through dR and through Exp(h / 2)).
  const Mat3d dRmid_dbg = Eh.transpose() * pre->dR_dbg - 0.5 * dt * Jr_half;
  const Mat3d dacc_dbg = -Ra_x * dRmid_dbg;
  pre->dp_dbg += pre->dv_dbg * dt + 0.5 * dt * dt * dacc_dbg;
  pre->dp_dba += pre->dv_dba * dt - 0.5 * dt * dt * R_mid;
  pre->dv_dbg += dt * dacc_dbg;
  pre->dv_dba -= dt * R_mid;
  pre->dR_dbg = E.transpose() * pre->dR_dbg - Jr * dt;
  // Covariance of [dtheta, dp, dv] with white noise of variance sigma^2 / dt per step.
  Mat9d A = Mat9d::Identity();
  A.block<3, 3>(0, 0) = E.transpose();
  A.block<3, 3>(3, 0) = -0.5 * dt * dt * Ra_x * Eh.transpose();
  A.block<3, 3>(3, 6) = Mat3d::Identity() * dt;
  A.block<3, 3>(6, 0) = -dt * Ra_x * Eh.transpose();
  Eigen::Matrix<double, 9, 6> B = Eigen::Matrix<double, 9, 6>::Zero();
  B.block<3, 3>(0, 0) = -Jr * dt;
  B.block<3, 3>(3, 0) = 0.25 * dt * dt * dt * Ra_x * Jr_half;
  B.block<3, 3>(3, 3) = -0.5 * dt * dt * R_mid;
  B.block<3, 3>(6, 0) = 0.5 * dt * dt * Ra_x * Jr_half;
  B.block<3, 3>(6, 3) = -dt * R_mid;
  Eigen::Matrix<double, 6, 1> q;
  q << Vec3d::Constant(noise.gyro_noise * noise.gyro_noise / dt),
      Vec3d::Constant(noise.accel_noise * noise.accel_noise / dt);
  pre->cov = A * pre->cov * A.transpose() + B * q.asDiagonal() * B.transpose();
  // The mean.
  pre->dp += pre->dv * dt + 0.5 * dt * dt * acc;
  pre->dv += dt * acc;
  pre->dq = quat::plus_right(pre->dq, h);
}

}  // namespace

Quatd Preintegration::dq_at(const Vec3d& bg) const {
  return quat::plus_right(dq, Vec3d(dR_dbg * (bg - bg_lin)));
}

Vec3d Preintegration::dp_at(const Vec3d& bg, const Vec3d& ba) const {
  return dp + dp_dbg * (bg - bg_lin) + dp_dba * (ba - ba_lin);
}

Vec3d Preintegration::dv_at(const Vec3d& bg, const Vec3d& ba) const {
  return dv + dv_dbg * (bg - bg_lin) + dv_dba * (ba - ba_lin);
}

StatusOr<Preintegration> preintegrate(const std::vector<io::ImuSample>& samples, TimestampNs t0_ns,
                                      TimestampNs t1_ns, const Vec3d& bg, const Vec3d& ba,
                                      const ImuNoise& noise) {
  if (t1_ns <= t0_ns) {
    return absl::InvalidArgumentError(
        fmt::format("pre-integration over an empty interval {} .. {} ns", t0_ns, t1_ns));
  }
  MRVS_ASSIGN_OR_RETURN(const std::vector<io::ImuSample> pts, sample_points(samples, t0_ns, t1_ns));
  Preintegration pre;
  pre.t0_ns = t0_ns;
  pre.t1_ns = t1_ns;
  pre.dt = to_seconds(t1_ns - t0_ns);
  pre.bg_lin = bg;
  pre.ba_lin = ba;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const double dt = to_seconds(pts[i + 1].t_ns - pts[i].t_ns);
    if (dt <= 0.0) continue;
    const Vec3d w = 0.5 * (pts[i].gyro_radps + pts[i + 1].gyro_radps) - bg;
    const Vec3d a = 0.5 * (pts[i].accel_mps2 + pts[i + 1].accel_mps2) - ba;
    step(w, a, dt, noise, &pre);
  }
  pre.cov = 0.5 * (pre.cov + pre.cov.transpose());
  return pre;
}

Vec9d preintegration_residual(const Preintegration& pre, const ImuState& xi, const ImuState& xj,
                              const Vec3d& g_w) {
  const Quatd q_i_inv = xi.q_w_b.conjugate();
  const double dt = pre.dt;
  Vec9d r;
  r.segment<3>(0) = quat::minus_right(Quatd(q_i_inv * xj.q_w_b), pre.dq_at(xi.bg));
  r.segment<3>(3) =
      q_i_inv * (xj.p_w_b - xi.p_w_b - xi.v_w_b * dt - 0.5 * g_w * dt * dt) - pre.dp_at(xi.bg, xi.ba);
  r.segment<3>(6) = q_i_inv * (xj.v_w_b - xi.v_w_b - g_w * dt) - pre.dv_at(xi.bg, xi.ba);
  return r;
}

}  // namespace mrvs::edge
