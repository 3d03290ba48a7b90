#pragma once
// IMU propagation (algorithm.md 3.2): the mean by RK4 with rates varying linearly between
// samples, the discrete error-state transition and noise from the continuous densities.
//
// Error state of the IMU, 15 values in this order (the State's IMU block):
//   [dtheta (3), dp (3), dv (3), dbg (3), dba (3)]
// with R_w_b = R^_w_b * Exp(dtheta) (a rotation in the body frame), p_w_b = p^ + dp,
// v_w_b = v^ + dv and additive biases. Gravity g_w points down: (0, 0, -g).
// Measurements: w_m = w_b + bg + n_g, a_m = R_w_b^T (a_w - g_w) + ba + n_a.
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/io/types.h"

namespace mrvs::edge {

using Mat15d = Eigen::Matrix<double, 15, 15>;
using Vec15d = Eigen::Matrix<double, 15, 1>;

/// Continuous-time noise densities (Kalibr / EuRoC naming).
struct ImuNoise {
  double gyro_noise = 0.0;   ///< rad / s / sqrt(Hz)
  double accel_noise = 0.0;  ///< m / s^2 / sqrt(Hz)
  double gyro_walk = 0.0;    ///< rad / s^2 / sqrt(Hz)
  double accel_walk = 0.0;   ///< m / s^3 / sqrt(Hz)
};

/// The IMU part of the state.
struct ImuState {
  TimestampNs t_ns = 0;  ///< IMU clock
  Quatd q_w_b = Quatd::Identity();
  Vec3d p_w_b = Vec3d::Zero();
  Vec3d v_w_b = Vec3d::Zero();
  Vec3d bg = Vec3d::Zero();  ///< gyro bias, rad/s
  Vec3d ba = Vec3d::Zero();  ///< accelerometer bias, m/s^2

  /// This state moved by the error `dx` (see the order above).
  ImuState boxplus(const Vec15d& dx) const;
  /// The error taking `other` to this state: this == other.boxplus(boxminus(other)).
  Vec15d boxminus(const ImuState& other) const;
};

/// Bias-corrected body rates and accelerations at one instant.
struct ImuRates {
  Vec3d w = Vec3d::Zero();  ///< rad/s
  Vec3d a = Vec3d::Zero();  ///< specific force, m/s^2
};

/// Mean of one step of length dt (s) by RK4, rates varying linearly from r0 to r1.
/// Biases and time are not changed.
ImuState integrate_step(const ImuState& x, const ImuRates& r0, const ImuRates& r1, const Vec3d& g_w,
                        double dt);

/// Discrete error transition of a step from `x` (the state at its start) with the step's
/// mean rates `r` (bias corrected) and length dt, and the noise it adds.
void step_transition(const ImuState& x, const ImuRates& r, double dt, const ImuNoise& noise, Mat15d* Phi,
                     Mat15d* Qd);

/// Result of propagating over an interval.
struct Propagation {
  ImuState state;                   ///< at the target time
  Mat15d Phi = Mat15d::Identity();  ///< d(error at the end) / d(error at the start)
  Mat15d Qd = Mat15d::Zero();       ///< noise added over the interval
  ImuRates last_rates;              ///< bias-corrected rates at the target time
};

/// Propagates `x` from x.t_ns to `t_target_ns` with `samples` (time-ordered, IMU clock),
/// interpolating linearly at both ends. The samples must cover [x.t_ns, t_target_ns]:
/// OutOfRange naming the gap otherwise. t_target_ns == x.t_ns gives the identity.
StatusOr<Propagation> propagate(const ImuState& x, const std::vector<io::ImuSample>& samples,
                                TimestampNs t_target_ns, const Vec3d& g_w, const ImuNoise& noise);

/// First-estimate Jacobians for the transition of an interval (OpenVINS' FEJ, in this
/// file's body-frame errors): the orientation blocks are replaced by their closed forms
///   Phi_tt = R_1^T R_0,  Phi_pt = -[p_1 - p_0 - v_0 dt - g dt^2 / 2]x R_0,
///   Phi_vt = -[v_1 - v_0 - g dt]x R_0,
/// evaluated at the first estimate `x0_fej` of the start (the estimate the measurements at
/// that time were linearised at) and the propagated end `x1`. With x0_fej equal to the
/// start they are the exact blocks; with it they map the unobservable global-yaw direction
/// of the start's first estimate onto that of the end, which keeps the filter consistent.
void apply_first_estimates(const ImuState& x0_fej, const ImuState& x1, const Vec3d& g_w, Mat15d* Phi);

/// The sample at t_ns linearly interpolated between its neighbours (t inside the range).
io::ImuSample interpolate_sample(const io::ImuSample& a, const io::ImuSample& b, TimestampNs t_ns);

}  // namespace mrvs::edge
