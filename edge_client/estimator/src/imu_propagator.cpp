#include "mrvs/edge/imu_propagator.h"

#include <algorithm>

#include <fmt/format.h>

#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

struct Derivative {
  Vec3d dtheta;  ///< body rate
  Vec3d dp;
  Vec3d dv;
};

/// Time derivative of (R, p, v) at a state with rates r.
Derivative derivative(const Quatd& q, const Vec3d& v, const ImuRates& r, const Vec3d& g_w) {
  return {r.w, v, q * r.a + g_w};
}

ImuRates lerp(const ImuRates& a, const ImuRates& b, double s) {
  return {a.w + s * (b.w - a.w), a.a + s * (b.a - a.a)};
}

ImuRates corrected(const io::ImuSample& s, const ImuState& x) {
  return {s.gyro_radps - x.bg, s.accel_mps2 - x.ba};
}

}  // namespace

ImuState ImuState::boxplus(const Vec15d& dx) const {
  ImuState out = *this;
  out.q_w_b = quat::plus_right(q_w_b, Vec3d(dx.segment<3>(0)));
  out.p_w_b += dx.segment<3>(3);
  out.v_w_b += dx.segment<3>(6);
  out.bg += dx.segment<3>(9);
  out.ba += dx.segment<3>(12);
  return out;
}

Vec15d ImuState::boxminus(const ImuState& other) const {
  Vec15d dx;
  dx.segment<3>(0) = quat::minus_right(q_w_b, other.q_w_b);
  dx.segment<3>(3) = p_w_b - other.p_w_b;
  dx.segment<3>(6) = v_w_b - other.v_w_b;
  dx.segment<3>(9) = bg - other.bg;
  dx.segment<3>(12) = ba - other.ba;
  return dx;
}

ImuState integrate_step(const ImuState& x, const ImuRates& r0, const ImuRates& r1, const Vec3d& g_w,
                        double dt) {
  // RK4 on (R, p, v); the rotation stages move along the body-rate direction.
  const ImuRates rm = lerp(r0, r1, 0.5);
  const Derivative k1 = derivative(x.q_w_b, x.v_w_b, r0, g_w);
  const Quatd q2 = quat::plus_right(x.q_w_b, Vec3d(0.5 * dt * k1.dtheta));
  const Derivative k2 = derivative(q2, x.v_w_b + 0.5 * dt * k1.dv, rm, g_w);
  const Quatd q3 = quat::plus_right(x.q_w_b, Vec3d(0.5 * dt * k2.dtheta));
  const Derivative k3 = derivative(q3, x.v_w_b + 0.5 * dt * k2.dv, rm, g_w);
  const Quatd q4 = quat::plus_right(x.q_w_b, Vec3d(dt * k3.dtheta));
  const Derivative k4 = derivative(q4, x.v_w_b + dt * k3.dv, r1, g_w);
  ImuState out = x;
  // Rotation: the body rate is linear in time, so the rotation over the step is, to third
  // order, exp of its integral plus the commutator term (w0 x w1) dt^2 / 12.
  const Vec3d phi = 0.5 * dt * (r0.w + r1.w) + dt * dt / 12.0 * r0.w.cross(r1.w);
  out.q_w_b = quat::plus_right(x.q_w_b, phi);
  out.v_w_b = x.v_w_b + dt / 6.0 * (k1.dv + 2.0 * k2.dv + 2.0 * k3.dv + k4.dv);
  out.p_w_b = x.p_w_b + dt / 6.0 * (k1.dp + 2.0 * k2.dp + 2.0 * k3.dp + k4.dp);
  return out;
}

void step_transition(const ImuState& x, const ImuRates& r, double dt, const ImuNoise& noise, Mat15d* Phi,
                     Mat15d* Qd) {
  const Mat3d R = x.q_w_b.toRotationMatrix();
  const Vec3d phi = r.w * dt;
  const Mat3d dR = so3::exp<double>(phi);
  const Mat3d Jr = so3::right_jacobian<double>(phi);
  const Mat3d Ra_x = R * skew<double>(r.a);
  Mat15d F = Mat15d::Identity();
  F.block<3, 3>(0, 0) = dR.transpose();
  F.block<3, 3>(0, 9) = -Jr * dt;
  F.block<3, 3>(3, 0) = -0.5 * Ra_x * dt * dt;
  F.block<3, 3>(3, 6) = Mat3d::Identity() * dt;
  F.block<3, 3>(3, 12) = -0.5 * R * dt * dt;
  F.block<3, 3>(6, 0) = -Ra_x * dt;
  F.block<3, 3>(6, 12) = -R * dt;
  *Phi = F;
  // White noise n (density sigma) over dt enters as G n_d with Cov(n_d) = sigma^2 / dt.
  Eigen::Matrix<double, 15, 12> G = Eigen::Matrix<double, 15, 12>::Zero();
  G.block<3, 3>(0, 0) = -Jr * dt;
  G.block<3, 3>(3, 3) = -0.5 * R * dt * dt;
  G.block<3, 3>(6, 3) = -R * dt;
  G.block<3, 3>(9, 6) = Mat3d::Identity();
  G.block<3, 3>(12, 9) = Mat3d::Identity();
  Eigen::Matrix<double, 12, 1> q;
  q << Vec3d::Constant(noise.gyro_noise * noise.gyro_noise / dt),
      Vec3d::Constant(noise.accel_noise * noise.accel_noise / dt),
      Vec3d::Constant(noise.gyro_walk * noise.gyro_walk * dt),
      Vec3d::Constant(noise.accel_walk * noise.accel_walk * dt);
  *Qd = G * q.asDiagonal() * G.transpose();
}

void apply_first_estimates(const ImuState& x0, const ImuState& x1, const Vec3d& g_w, Mat15d* Phi) {
  const double dt = to_seconds(x1.t_ns - x0.t_ns);
  const Mat3d R0 = x0.q_w_b.toRotationMatrix();
  Phi->block<3, 3>(0, 0) = x1.q_w_b.toRotationMatrix().transpose() * R0;
  const Vec3d dp = x1.p_w_b - x0.p_w_b - x0.v_w_b * dt - 0.5 * g_w * dt * dt;
  const Vec3d dv = x1.v_w_b - x0.v_w_b - g_w * dt;
  Phi->block<3, 3>(3, 0) = -skew<double>(dp) * R0;
  Phi->block<3, 3>(6, 0) = -skew<double>(dv) * R0;
}

io::ImuSample interpolate_sample(const io::ImuSample& a, const io::ImuSample& b, TimestampNs t_ns) {
  const double s =
      b.t_ns == a.t_ns ? 0.0 : static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  return {t_ns, a.gyro_radps + s * (b.gyro_radps - a.gyro_radps),
          a.accel_mps2 + s * (b.accel_mps2 - a.accel_mps2)};
}

StatusOr<Propagation> propagate(const ImuState& x, const std::vector<io::ImuSample>& samples,
                                TimestampNs t_target_ns, const Vec3d& g_w, const ImuNoise& noise) {
  if (t_target_ns < x.t_ns) {
    return absl::InvalidArgumentError(
        fmt::format("propagation backwards in time: from {} ns to {} ns", x.t_ns, t_target_ns));
  }
  const auto by_time = [](const io::ImuSample& s, TimestampNs t) { return s.t_ns < t; };
  // The last sample at or before the start and the first at or after the target.
  auto first = std::lower_bound(samples.begin(), samples.end(), x.t_ns + 1, by_time);
  auto last = std::lower_bound(samples.begin(), samples.end(), t_target_ns, by_time);
  if (first == samples.begin() || last == samples.end()) {
    return absl::OutOfRangeError(fmt::format("no IMU coverage for {} .. {} ns (IMU buffer {} .. {} ns)",
                                             x.t_ns, t_target_ns, samples.empty() ? 0 : samples.front().t_ns,
                                             samples.empty() ? 0 : samples.back().t_ns));
  }
  --first;
  // Sample points of the interval: start, the samples strictly inside, target.
  std::vector<io::ImuSample> pts;
  pts.push_back(interpolate_sample(*first, *(first + 1), x.t_ns));
  for (auto it = first + 1; it != samples.end() && it->t_ns < t_target_ns; ++it) pts.push_back(*it);
  pts.push_back(interpolate_sample(*(last == samples.begin() ? last : last - 1), *last, t_target_ns));
  Propagation out;
  out.state = x;
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const double dt = to_seconds(pts[i + 1].t_ns - pts[i].t_ns);
    if (dt <= 0.0) continue;
    const ImuRates r0 = corrected(pts[i], x), r1 = corrected(pts[i + 1], x);
    Mat15d F, Q;
    step_transition(out.state, lerp(r0, r1, 0.5), dt, noise, &F, &Q);
    out.state = integrate_step(out.state, r0, r1, g_w, dt);
    out.Phi = F * out.Phi;
    out.Qd = F * out.Qd * F.transpose() + Q;
  }
  out.state.t_ns = t_target_ns;
  out.last_rates = corrected(pts.back(), x);
  return out;
}

}  // namespace mrvs::edge
