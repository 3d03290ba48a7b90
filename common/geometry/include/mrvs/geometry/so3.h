#pragma once
// SO(3): skew, exp/log and the left/right Jacobians.
//
// Conventions
// - Quaternions are Hamilton (Eigen::Quaternion): q_a_b rotates vectors of frame b into
//   frame a, v_a = q_a_b * v_b, and R_a_b = q_a_b.toRotationMatrix().
// - exp(phi) is the rotation by |phi| radians about phi/|phi|.
// - Right Jacobian:  exp(phi + d) ~= exp(phi) * exp(Jr(phi) d)
//   Left Jacobian:   exp(phi + d) ~= exp(Jl(phi) d) * exp(phi),  Jl(phi) = Jr(-phi)
//   and log(exp(phi) * exp(d)) ~= phi + Jr^-1(phi) d.
#include <cmath>
#include <limits>

#include "mrvs/geometry/types.h"

namespace mrvs {

/// Below this rotation angle (rad) exp/log switch to Taylor series.
template <typename S>
S small_angle() {
  return std::sqrt(std::numeric_limits<S>::epsilon());
}

/// Angle below which the SO(3) Jacobians use Taylor series (to theta^4). The closed forms
/// cancel catastrophically for small angles (relative error ~ eps / theta^2).
template <typename S>
constexpr S jacobian_series_threshold() {
  return sizeof(S) <= sizeof(float) ? S(0.3) : S(1e-2);
}

/// [v]x : the cross-product matrix, skew(a) * b == a.cross(b).
template <typename S>
Mat3<S> skew(const Vec3<S>& v) {
  Mat3<S> m;
  m << S(0), -v.z(), v.y(),  //
      v.z(), S(0), -v.x(),   //
      -v.y(), v.x(), S(0);
  return m;
}

/// Inverse of skew (uses the antisymmetric part of m).
template <typename S>
Vec3<S> vee(const Mat3<S>& m) {
  return Vec3<S>(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)) * S(0.5);
}

namespace so3 {

/// Unit Hamilton quaternion of the rotation vector phi.
template <typename S>
Quat<S> exp_quat(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const S theta = std::sqrt(theta2);
  S w, k;  // q = (w, k * phi)
  if (theta < small_angle<S>()) {
    w = S(1) - theta2 / S(8);
    k = S(0.5) - theta2 / S(48);
  } else {
    w = std::cos(theta / S(2));
    k = std::sin(theta / S(2)) / theta;
  }
  Quat<S> q(w, k * phi.x(), k * phi.y(), k * phi.z());
  q.normalize();
  return q;
}

/// Rotation matrix of the rotation vector phi (Rodrigues).
template <typename S>
Mat3<S> exp(const Vec3<S>& phi) {
  return exp_quat(phi).toRotationMatrix();
}

/// Rotation vector of a unit quaternion, angle in [0, pi]. q and -q give the same result.
template <typename S>
Vec3<S> log(const Quat<S>& q_in) {
  Quat<S> q = q_in.normalized();
  if (q.w() < S(0)) q.coeffs() = -q.coeffs();
  const Vec3<S> v = q.vec();
  const S n = v.norm();
  if (n < small_angle<S>()) {
    // theta = 2 atan2(n, w) ~ 2 n / w (1 - n^2 / (3 w^2))
    const S w = q.w();
    return v * (S(2) / w) * (S(1) - n * n / (S(3) * w * w));
  }
  const S theta = S(2) * std::atan2(n, q.w());
  return v * (theta / n);
}

/// Rotation vector of a rotation matrix (via a robust quaternion conversion).
template <typename S>
Vec3<S> log(const Mat3<S>& R) {
  return log(Quat<S>(R));
}

/// Right Jacobian of SO(3).
template <typename S>
Mat3<S> right_jacobian(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const Mat3<S> K = skew(phi);
  S a, b;  // Jr = I - a K + b K^2
  if (theta2 < jacobian_series_threshold<S>() * jacobian_series_threshold<S>()) {
    a = S(1) / S(2) - theta2 / S(24) + theta2 * theta2 / S(720);
    b = S(1) / S(6) - theta2 / S(120) + theta2 * theta2 / S(5040);
  } else {
    const S theta = std::sqrt(theta2);
    a = (S(1) - std::cos(theta)) / theta2;
    b = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Mat3<S>::Identity() - a * K + b * K * K;
}

/// Inverse of the right Jacobian of SO(3) (valid for |phi| < 2 pi).
template <typename S>
Mat3<S> right_jacobian_inverse(const Vec3<S>& phi) {
  const S theta2 = phi.squaredNorm();
  const Mat3<S> K = skew(phi);
  S c;  // Jr^-1 = I + K / 2 + c K^2
  if (theta2 < jacobian_series_threshold<S>() * jacobian_series_threshold<S>()) {
    c = S(1) / S(12) + theta2 / S(720) + theta2 * theta2 / S(30240);
  } else {
    const S theta = std::sqrt(theta2);
    c = S(1) / theta2 - (S(1) + std::cos(theta)) / (S(2) * theta * std::sin(theta));
  }
  return Mat3<S>::Identity() + S(0.5) * K + c * K * K;
}

/// Left Jacobian of SO(3): Jl(phi) = Jr(-phi) = R(phi) Jr(phi).
template <typename S>
Mat3<S> left_jacobian(const Vec3<S>& phi) {
  return right_jacobian<S>(-phi);
}

/// Inverse of the left Jacobian of SO(3).
template <typename S>
Mat3<S> left_jacobian_inverse(const Vec3<S>& phi) {
  return right_jacobian_inverse<S>(-phi);
}

/// True when R is a proper rotation: |R^T R - I| <= tol element-wise and det(R) > 0.
template <typename S>
bool is_rotation_matrix(const Mat3<S>& R, S tol) {
  const S err = (R.transpose() * R - Mat3<S>::Identity()).cwiseAbs().maxCoeff();
  return err <= tol && R.determinant() > S(0);
}

}  // namespace so3
}  // namespace mrvs
