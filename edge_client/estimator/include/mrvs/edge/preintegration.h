#pragma once
// IMU pre-integration between two instants (Forster et al., "On-Manifold Preintegration",
// 2017), in the body frame at the start i, with first-order bias corrections.
//
// With R_i = R_w_bi, g_w = (0, 0, -g) and dt = t_j - t_i, the deltas are
//   dR = R_i^T R_j
//   dv = R_i^T (v_j - v_i - g_w dt)
//   dp = R_i^T (p_j - p_i - v_i dt - 0.5 g_w dt^2)
// integrated from the bias-corrected samples (w_m - bg, a_m - ba) at the linearisation
// biases (bg_lin, ba_lin). For other biases the deltas are corrected to first order:
//   dR(bg) = dR Exp(dR_dbg (bg - bg_lin)), dv(bg, ba) = dv + dv_dbg dbg + dv_dba dba, ...
// Error order of the covariance: [dtheta (right perturbation of dR), dp, dv] (the
// ImuState order without the biases). The biases are taken constant over the interval.
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/edge/imu_propagator.h"
#include "mrvs/geometry/types.h"
#include "mrvs/io/types.h"

namespace mrvs::edge {

using Mat9d = Eigen::Matrix<double, 9, 9>;
using Vec9d = Eigen::Matrix<double, 9, 1>;

struct Preintegration {
  TimestampNs t0_ns = 0;  ///< start (IMU clock)
  TimestampNs t1_ns = 0;  ///< end (IMU clock)
  double dt = 0.0;        ///< s
  Vec3d bg_lin = Vec3d::Zero();
  Vec3d ba_lin = Vec3d::Zero();
  Quatd dq = Quatd::Identity();  ///< dR = R_bi_bj
  Vec3d dp = Vec3d::Zero();      ///< m
  Vec3d dv = Vec3d::Zero();      ///< m/s
  Mat3d dR_dbg = Mat3d::Zero();  ///< d dtheta / d bg (right perturbation)
  Mat3d dp_dbg = Mat3d::Zero();
  Mat3d dp_dba = Mat3d::Zero();
  Mat3d dv_dbg = Mat3d::Zero();
  Mat3d dv_dba = Mat3d::Zero();
  Mat9d cov = Mat9d::Zero();  ///< [dtheta, dp, dv], from the white noise densities

  /// The deltas at other biases, first order in (bg - bg_lin, ba - ba_lin).
  Quatd dq_at(const Vec3d& bg) const;
  Vec3d dp_at(const Vec3d& bg, const Vec3d& ba) const;
  Vec3d dv_at(const Vec3d& bg, const Vec3d& ba) const;
};

/// Pre-integrates `samples` (time-ordered, IMU clock) over [t0_ns, t1_ns] with the biases
/// (bg, ba) as linearisation point, interpolating linearly at both ends. Each sample step
/// uses the mean rates of its two ends, the rotation at its midpoint for the acceleration.
/// Errors: InvalidArgument for t1 <= t0, OutOfRange when the samples do not cover the
/// interval (naming it).
StatusOr<Preintegration> preintegrate(const std::vector<io::ImuSample>& samples, TimestampNs t0_ns,
                                      TimestampNs t1_ns, const Vec3d& bg, const Vec3d& ba,
                                      const ImuNoise& noise);

/// The residual [dtheta, dp, dv] of the states xi (at t0) and xj (at t1) against `pre`,
/// with the biases of xi: zero when the states agree with the measurement exactly.
Vec9d preintegration_residual(const Preintegration& pre, const ImuState& xi, const ImuState& xj,
                              const Vec3d& g_w);

}  // namespace mrvs::edge
