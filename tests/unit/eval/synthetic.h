#pragma once
// Synthetic trajectories with known ground truth for the eval tests.
#include <array>
#include <cmath>
#include <random>

#include "mrvs/geometry/se3.h"
#include "mrvs/io/types.h"

namespace mrvs::eval::synthetic {

/// A smooth random trajectory: every position / rotation-vector component is a sum of
/// three sinusoids with random amplitude, frequency and phase (plus a drift in position),
/// so it is curved and non-degenerate in 3-D.
class SmoothTrajectory {
 public:
  explicit SmoothTrajectory(std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> amp(0.5, 2.0), freq(0.05, 0.4), phase(0.0, 2.0 * M_PI);
    std::uniform_real_distribution<double> rot_amp(0.1, 0.6), vel(-0.3, 0.3);
    for (int axis = 0; axis < 6; ++axis) {
      for (int k = 0; k < 3; ++k) {
        terms_[axis][k] = {axis < 3 ? amp(rng) : rot_amp(rng), 2.0 * M_PI * freq(rng), phase(rng)};
      }
    }
    drift_ = Vec3d(vel(rng), vel(rng), vel(rng));
  }

  /// T_w_b at time t_s (seconds).
  SE3d pose(double t_s) const {
    Vec6d v;
    for (int axis = 0; axis < 6; ++axis) {
      v[axis] = 0.0;
      for (const auto& term : terms_[axis]) v[axis] += term[0] * std::sin(term[1] * t_s + term[2]);
    }
    return SE3d(so3::exp_quat<double>(v.tail<3>()), Vec3d(v.head<3>() + drift_ * t_s));
  }
  SE3d operator()(double t_s) const { return pose(t_s); }

 private:
  std::array<std::array<std::array<double, 3>, 3>, 6> terms_{};
  Vec3d drift_ = Vec3d::Zero();
};

/// n poses of `f(t_s)` at t0_ns + k * dt_ns.
template <typename F>
io::Trajectory sample(const F& f, TimestampNs t0_ns, DurationNs dt_ns, int n) {
  io::Trajectory out;
  for (int k = 0; k < n; ++k) {
    const TimestampNs t_ns = t0_ns + k * dt_ns;
    out.push_back({t_ns, f(to_seconds(t_ns - t0_ns))});
  }
  return out;
}

/// Every pose re-expressed in another world frame: T_a_b = T_a_w * T_w_b.
inline io::Trajectory transform(const SE3d& T_a_w, const io::Trajectory& trajectory) {
  io::Trajectory out = trajectory;
  for (io::StampedPose& p : out) p.T_w_b = T_a_w * p.T_w_b;
  return out;
}

/// A random rigid transform with rotation angle up to pi and translation up to max_m.
inline SE3d random_se3(std::mt19937& rng, double max_m) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> angle(0.3, 3.0), len(0.5, max_m);
  const Vec3d axis = Vec3d(n(rng), n(rng), n(rng)).normalized();
  const Vec3d dir = Vec3d(n(rng), n(rng), n(rng)).normalized();
  return SE3d(so3::exp_quat<double>(angle(rng) * axis), Vec3d(len(rng) * dir));
}

}  // namespace mrvs::eval::synthetic
