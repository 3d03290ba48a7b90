#pragma once
// The pre-integration residual with analytic Jacobians, and its Ceres cost function.
//
// Residual of the states i (at pre.t0_ns) and j (at pre.t1_ns), with the biases of i, as in
// preintegration_residual():
//   r_theta = Log( dR(bg)^T R_i^T R_j )
//   r_p     = R_i^T (p_j - p_i - v_i dt - 0.5 g_w dt^2) - dp(bg, ba)
//   r_v     = R_i^T (v_j - v_i - g_w dt) - dv(bg, ba)
// Orientations are perturbed on the right, q * Exp(delta) (the ImuState convention), and
// quaternions are stored in Eigen order x, y, z, w.
#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>

#include "mrvs/edge/imu_propagator.h"
#include "mrvs/edge/preintegration.h"
#include "mrvs/geometry/types.h"

namespace mrvs::edge {

using Mat93d = Eigen::Matrix<double, 9, 3>;

/// Jacobians of imu_residual(); the orientation blocks are taken w.r.t. delta of q * Exp(delta).
struct ImuResidualJacobians {
  Mat93d q_i, p_i, v_i;
  Mat93d q_j, p_j, v_j;
  Mat93d bg, ba;  ///< the biases of xi
};

/// The residual [r_theta, r_p, r_v] above (not whitened), and optionally its Jacobians.
/// xj's biases and both timestamps are not used.
Vec9d imu_residual(const Preintegration& pre, const ImuState& xi, const ImuState& xj, const Vec3d& g_w,
                   ImuResidualJacobians* J = nullptr);

/// d Plus(q, delta) / d delta at delta = 0 (4 x 3, row-major order of Ceres).
Eigen::Matrix<double, 4, 3> right_quaternion_plus_jacobian(const Quatd& q);
/// d Minus(y, q) / d y at y = q (3 x 4); right_quaternion_minus_jacobian(q) *
/// right_quaternion_plus_jacobian(q) = I for a unit q.
Eigen::Matrix<double, 3, 4> right_quaternion_minus_jacobian(const Quatd& q);

/// Unit quaternion parameter blocks (x y z w) perturbed on the right: Plus(q, d) = q * Exp(d).
class RightQuaternionManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

/// Pre-integration factor: 9 whitened residuals sqrt_info * imu_residual() on the blocks
/// (q_i, p_i, v_i, q_j, p_j, v_j, bg, ba), sqrt_info the upper Cholesky factor of
/// (pre.cov + cov_floor I)^-1. The quaternion blocks' Jacobians are w.r.t. the 4 ambient
/// coordinates: J_tangent * right_quaternion_minus_jacobian(q), for RightQuaternionManifold.
class ImuCostFunction : public ceres::SizedCostFunction<9, 4, 3, 3, 4, 3, 3, 3, 3> {
 public:
  ImuCostFunction(const Preintegration& pre, const Vec3d& g_w, double cov_floor);
  bool Evaluate(const double* const* parameters, double* residuals, double** jacobians) const override;

  const Mat9d& sqrt_information() const { return sqrt_info_; }

 private:
  Preintegration pre_;
  Vec3d g_w_;
  Mat9d sqrt_info_;
};

}  // namespace mrvs::edge
