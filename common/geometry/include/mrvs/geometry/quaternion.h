#pragma once
// Hamilton quaternion helpers on top of Eigen::Quaternion.
//
// Coefficient order used by the matrices below is Eigen's storage order
// [x, y, z, w] (q.coeffs()), the same order as TUM / ROS files.
#include "mrvs/geometry/so3.h"

namespace mrvs::quat {

/// L(p) with (p * q).coeffs() == L(p) * q.coeffs() (Hamilton product).
template <typename S>
Mat4<S> left_multiplication_matrix(const Quat<S>& p) {
  Mat4<S> L;
  L.template topLeftCorner<3, 3>() = p.w() * Mat3<S>::Identity() + skew<S>(p.vec());
  L.template topRightCorner<3, 1>() = p.vec();
  L.template bottomLeftCorner<1, 3>() = -p.vec().transpose();
  L(3, 3) = p.w();
  return L;
}

/// R(q) with (p * q).coeffs() == R(q) * p.coeffs() (Hamilton product).
template <typename S>
Mat4<S> right_multiplication_matrix(const Quat<S>& q) {
  Mat4<S> R;
  R.template topLeftCorner<3, 3>() = q.w() * Mat3<S>::Identity() - skew<S>(q.vec());
  R.template topRightCorner<3, 1>() = q.vec();
  R.template bottomLeftCorner<1, 3>() = -q.vec().transpose();
  R(3, 3) = q.w();
  return R;
}

/// The same rotation with w >= 0 (a unique representative for comparisons and files).
template <typename S>
Quat<S> canonical(const Quat<S>& q) {
  Quat<S> out = q.normalized();
  if (out.w() < S(0)) out.coeffs() = -out.coeffs();
  return out;
}

/// Rotation angle (rad, in [0, pi]) between two orientations.
template <typename S>
S angular_distance(const Quat<S>& a, const Quat<S>& b) {
  return so3::log<S>(a.conjugate() * b).norm();
}

/// Box-plus on the right (local perturbation): q * exp(delta).
template <typename S>
Quat<S> plus_right(const Quat<S>& q, const Vec3<S>& delta) {
  return (q * so3::exp_quat<S>(delta)).normalized();
}

/// Box-minus matching plus_right: log(a^-1 * b), so plus_right(a, minus_right(b, a)) == b.
template <typename S>
Vec3<S> minus_right(const Quat<S>& b, const Quat<S>& a) {
  return so3::log<S>(a.conjugate() * b);
}

}  // namespace mrvs::quat
