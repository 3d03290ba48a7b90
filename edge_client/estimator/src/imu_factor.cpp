// Pre-integration residual with analytic Jacobians (derivation in the comments below) and
// its Ceres cost function, replacing automatic differentiation of a 26-parameter factor.
#include "mrvs/edge/imu_factor.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {

Vec9d imu_residual(const Preintegration& pre, const ImuState& xi, const ImuState& xj, const Vec3d& g_w,
                   ImuResidualJacobians* J) {
  const double dt = pre.dt;
  const Vec3d dbg = xi.bg - pre.bg_lin;
  const Vec3d phi_bg = pre.dR_dbg * dbg;  // dR(bg) = dR Exp(phi_bg)
  const Quatd q_i_inv = xi.q_w_b.conjugate();
  const Vec3d a_p = xj.p_w_b - xi.p_w_b - xi.v_w_b * dt - 0.5 * g_w * dt * dt;  // world frame
  const Vec3d a_v = xj.v_w_b - xi.v_w_b - g_w * dt;
  const Vec3d b_p = q_i_inv * a_p, b_v = q_i_inv * a_v;  // body frame i
  Vec9d r;
  r.segment<3>(0) = quat::minus_right(Quatd(q_i_inv * xj.q_w_b), quat::plus_right(pre.dq, phi_bg));
  r.segment<3>(3) = b_p - pre.dp_at(xi.bg, xi.ba);
  r.segment<3>(6) = b_v - pre.dv_at(xi.bg, xi.ba);
  if (J == nullptr) return r;

  // E = dR(bg)^T R_i^T R_j, r_theta = Log(E).
  //  q_i Exp(d):  E Exp(-R_j^T R_i d)                  -> -Jr^-1(r) R_j^T R_i
  //  q_j Exp(d):  E Exp(d)                              ->  Jr^-1(r)
  //  bg + d:      Exp(-Jr(phi_bg) dR_dbg d) E           -> -Jl^-1(r) Jr(phi_bg) dR_dbg
  //  R_i Exp(d) in R_i^T a:  (I - [d]x) R_i^T a          ->  [R_i^T a]x
  const Vec3d r_theta = r.segment<3>(0);
  const Mat3d Jr_inv = so3::right_jacobian_inverse<double>(r_theta);
  const Mat3d R_i_T = q_i_inv.toRotationMatrix();
  const Mat3d R_j_T_R_i = (xj.q_w_b.conjugate() * xi.q_w_b).toRotationMatrix();
  const Mat3d Z = Mat3d::Zero();

  J->q_i << -Jr_inv * R_j_T_R_i, skew<double>(b_p), skew<double>(b_v);
  J->p_i << Z, -R_i_T, Z;
  J->v_i << Z, -R_i_T * dt, -R_i_T;
  J->q_j << Jr_inv, Z, Z;
  J->p_j << Z, R_i_T, Z;
  J->v_j << Z, Z, R_i_T;
  J->bg << -so3::left_jacobian_inverse<double>(r_theta) * so3::right_jacobian<double>(phi_bg) * pre.dR_dbg,
      -pre.dp_dbg, -pre.dv_dbg;
  J->ba << Z, -pre.dp_dba, -pre.dv_dba;
  return r;
}

Eigen::Matrix<double, 4, 3> right_quaternion_plus_jacobian(const Quatd& q) {
  // q * Exp(d) ~= q * (d / 2, 1): half the first three columns of L(q).
  return 0.5 * quat::left_multiplication_matrix(q).leftCols<3>();
}

Eigen::Matrix<double, 3, 4> right_quaternion_minus_jacobian(const Quatd& q) {
  // Log(q^-1 y) ~= 2 vec(q^-1 y) near y = q, and (q^-1 y).coeffs() = L(q)^T y.coeffs().
  return 2.0 * quat::left_multiplication_matrix(q).transpose().topRows<3>();
}

bool RightQuaternionManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  Eigen::Map<Quatd> out(x_plus_delta);
  out = quat::plus_right(Quatd(x), Vec3d(delta));
  return true;
}

bool RightQuaternionManifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> J(jacobian);
  J = right_quaternion_plus_jacobian(Quatd(x));
  return true;
}

bool RightQuaternionManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<Vec3d> out(y_minus_x);
  out = quat::minus_right(Quatd(y), Quatd(x));
  return true;
}

bool RightQuaternionManifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, 3, 4, Eigen::RowMajor>> J(jacobian);
  J = right_quaternion_minus_jacobian(Quatd(x));
  return true;
}

ImuCostFunction::ImuCostFunction(const Preintegration& pre, const Vec3d& g_w, double cov_floor)
    : pre_(pre), g_w_(g_w) {
  const Mat9d info = (pre.cov + cov_floor * Mat9d::Identity()).inverse();
  sqrt_info_ = Eigen::LLT<Mat9d>(0.5 * (info + info.transpose())).matrixU();
}

bool ImuCostFunction::Evaluate(const double* const* parameters, double* residuals, double** jacobians) const {
  const auto state = [&](int q, int p, int v) {
    ImuState x;
    x.q_w_b = Quatd(parameters[q]);
    x.p_w_b = Vec3d(parameters[p]);
    x.v_w_b = Vec3d(parameters[v]);
    x.bg = Vec3d(parameters[6]);
    x.ba = Vec3d(parameters[7]);
    return x;
  };
  const ImuState xi = state(0, 1, 2), xj = state(3, 4, 5);
  ImuResidualJacobians J;
  const Vec9d r = imu_residual(pre_, xi, xj, g_w_, jacobians != nullptr ? &J : nullptr);
  Eigen::Map<Vec9d> out(residuals);
  out = sqrt_info_ * r;
  if (jacobians == nullptr) return true;

  using Ambient = Eigen::Map<Eigen::Matrix<double, 9, 4, Eigen::RowMajor>>;
  using Euclidean = Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>>;
  const Quatd* quats[8] = {&xi.q_w_b, nullptr, nullptr, &xj.q_w_b, nullptr, nullptr, nullptr, nullptr};
  const Mat93d* blocks[8] = {&J.q_i, &J.p_i, &J.v_i, &J.q_j, &J.p_j, &J.v_j, &J.bg, &J.ba};
  for (int k = 0; k < 8; ++k) {
    if (jacobians[k] == nullptr) continue;
    if (quats[k] != nullptr) {
      Ambient J_k(jacobians[k]);
      J_k = sqrt_info_ * *blocks[k] * right_quaternion_minus_jacobian(*quats[k]);
    } else {
      Euclidean J_k(jacobians[k]);
      J_k = sqrt_info_ * *blocks[k];
    }
  }
  return true;
}

}  // namespace mrvs::edge
