#pragma once
// SE(3) rigid transforms.
//
// Frame notation (used everywhere in the project): T_a_b maps points of frame b into
// frame a, p_a = T_a_b * p_b, and composes as T_a_c = T_a_b * T_b_c. R_a_b and p_a_b
// (the position of b's origin in a) are its rotation and translation.
//
// Tangent vectors are ordered xi = [rho; phi] (translation part first, then rotation),
// exp(xi) = [exp(phi), Jl(phi) rho; 0, 1].
#include "mrvs/geometry/so3.h"

namespace mrvs {

template <typename S>
class SE3 {
 public:
  /// Identity.
  SE3() : q_(Quat<S>::Identity()), t_(Vec3<S>::Zero()) {}
  /// From a rotation (normalised here) and a translation.
  SE3(const Quat<S>& q, const Vec3<S>& t) : q_(q.normalized()), t_(t) {}
  /// From a rotation matrix (must be a rotation; see so3::is_rotation_matrix) and a translation.
  SE3(const Mat3<S>& R, const Vec3<S>& t) : q_(Quat<S>(R).normalized()), t_(t) {}

  /// From a homogeneous 4x4 matrix; the caller validates the rotation block.
  static SE3 from_matrix(const Mat4<S>& m) {
    return SE3(Mat3<S>(m.template topLeftCorner<3, 3>()), Vec3<S>(m.template topRightCorner<3, 1>()));
  }

  const Quat<S>& quaternion() const { return q_; }
  Mat3<S> rotation_matrix() const { return q_.toRotationMatrix(); }
  const Vec3<S>& translation() const { return t_; }
  Vec3<S>& translation() { return t_; }
  void set_quaternion(const Quat<S>& q) { q_ = q.normalized(); }

  Mat4<S> matrix() const {
    Mat4<S> m = Mat4<S>::Identity();
    m.template topLeftCorner<3, 3>() = rotation_matrix();
    m.template topRightCorner<3, 1>() = t_;
    return m;
  }

  SE3 inverse() const {
    const Quat<S> qi = q_.conjugate();
    return SE3(qi, -(qi * t_));
  }

  SE3 operator*(const SE3& other) const { return SE3(q_ * other.q_, t_ + q_ * other.t_); }
  Vec3<S> operator*(const Vec3<S>& p) const { return q_ * p + t_; }

  template <typename T>
  SE3<T> cast() const {
    return SE3<T>(q_.template cast<T>(), t_.template cast<T>());
  }

  /// exp([rho; phi]).
  static SE3 exp(const Vec6<S>& xi) {
    const Vec3<S> rho = xi.template head<3>();
    const Vec3<S> phi = xi.template tail<3>();
    return SE3(so3::exp_quat<S>(phi), so3::left_jacobian<S>(phi) * rho);
  }

  /// log(T) = [rho; phi] with exp(log(T)) == T (rotation angle in [0, pi]).
  Vec6<S> log() const {
    const Vec3<S> phi = so3::log<S>(q_);
    Vec6<S> xi;
    xi.template head<3>() = so3::left_jacobian_inverse<S>(phi) * t_;
    xi.template tail<3>() = phi;
    return xi;
  }

  /// Adjoint: T * exp(xi) * T^-1 == exp(Ad(T) xi), Ad = [R, [t]x R; 0, R].
  Mat6<S> adjoint() const {
    const Mat3<S> R = rotation_matrix();
    Mat6<S> ad = Mat6<S>::Zero();
    ad.template topLeftCorner<3, 3>() = R;
    ad.template topRightCorner<3, 3>() = skew<S>(t_) * R;
    ad.template bottomRightCorner<3, 3>() = R;
    return ad;
  }

 private:
  Quat<S> q_;
  Vec3<S> t_;
};

using SE3d = SE3<double>;
using SE3f = SE3<float>;

namespace se3 {

/// The Q block of the SE(3) left Jacobian (Barfoot, State Estimation, eq. 7.86).
template <typename S>
Mat3<S> left_jacobian_q(const Vec3<S>& rho, const Vec3<S>& phi) {
  const Mat3<S> P = skew(phi);
  const Mat3<S> Rh = skew(rho);
  const S theta2 = phi.squaredNorm();
  // The closed forms of c2, c3 cancel like eps / theta^4: use series (to theta^4) below
  // 0.1 rad (double) or 0.5 rad (float).
  const S series_below = sizeof(S) <= sizeof(float) ? S(0.5) : S(0.1);
  S c1, c2, c3;
  if (theta2 < series_below * series_below) {
    const S theta4 = theta2 * theta2;
    c1 = S(1) / S(6) - theta2 / S(120) + theta4 / S(5040);
    c2 = S(1) / S(24) - theta2 / S(720) + theta4 / S(40320);
    c3 = S(1) / S(120) - theta2 / S(2520) + theta4 / S(120960);
  } else {
    const S theta = std::sqrt(theta2);
    const S s = std::sin(theta);
    const S c = std::cos(theta);
    c1 = (theta - s) / (theta2 * theta);
    c2 = (theta2 + S(2) * c - S(2)) / (S(2) * theta2 * theta2);
    c3 = (S(2) * theta - S(3) * s + theta * c) / (S(2) * theta2 * theta2 * theta);
  }
  return S(0.5) * Rh + c1 * (P * Rh + Rh * P + P * Rh * P) +
         c2 * (P * P * Rh + Rh * P * P - S(3) * P * Rh * P) + c3 * (P * Rh * P * P + P * P * Rh * P);
}

/// Left Jacobian of SE(3): exp(xi + d) ~= exp(Jl(xi) d) * exp(xi).
template <typename S>
Mat6<S> left_jacobian(const Vec6<S>& xi) {
  const Vec3<S> rho = xi.template head<3>();
  const Vec3<S> phi = xi.template tail<3>();
  Mat6<S> J = Mat6<S>::Zero();
  const Mat3<S> Jl = so3::left_jacobian<S>(phi);
  J.template topLeftCorner<3, 3>() = Jl;
  J.template bottomRightCorner<3, 3>() = Jl;
  J.template topRightCorner<3, 3>() = left_jacobian_q<S>(rho, phi);
  return J;
}

/// Right Jacobian of SE(3): exp(xi + d) ~= exp(xi) * exp(Jr(xi) d), Jr(xi) = Jl(-xi).
template <typename S>
Mat6<S> right_jacobian(const Vec6<S>& xi) {
  return left_jacobian<S>(-xi);
}

/// Inverse of the left Jacobian of SE(3) (block form, no 6x6 inversion).
template <typename S>
Mat6<S> left_jacobian_inverse(const Vec6<S>& xi) {
  const Vec3<S> rho = xi.template head<3>();
  const Vec3<S> phi = xi.template tail<3>();
  const Mat3<S> Jl_inv = so3::left_jacobian_inverse<S>(phi);
  Mat6<S> J = Mat6<S>::Zero();
  J.template topLeftCorner<3, 3>() = Jl_inv;
  J.template bottomRightCorner<3, 3>() = Jl_inv;
  J.template topRightCorner<3, 3>() = -Jl_inv * left_jacobian_q<S>(rho, phi) * Jl_inv;
  return J;
}

/// Inverse of the right Jacobian of SE(3).
template <typename S>
Mat6<S> right_jacobian_inverse(const Vec6<S>& xi) {
  return left_jacobian_inverse<S>(-xi);
}

}  // namespace se3
}  // namespace mrvs
