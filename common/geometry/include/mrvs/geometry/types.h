#pragma once
// Eigen aliases used across the project, templated on the scalar type.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mrvs {

template <typename S>
using Vec2 = Eigen::Matrix<S, 2, 1>;
template <typename S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <typename S>
using Vec4 = Eigen::Matrix<S, 4, 1>;
template <typename S>
using Vec6 = Eigen::Matrix<S, 6, 1>;
template <typename S>
using Mat2 = Eigen::Matrix<S, 2, 2>;
template <typename S>
using Mat3 = Eigen::Matrix<S, 3, 3>;
template <typename S>
using Mat4 = Eigen::Matrix<S, 4, 4>;
template <typename S>
using Mat6 = Eigen::Matrix<S, 6, 6>;
template <typename S>
using Quat = Eigen::Quaternion<S>;

using Vec2d = Vec2<double>;
using Vec3d = Vec3<double>;
using Vec4d = Vec4<double>;
using Vec6d = Vec6<double>;
using Mat2d = Mat2<double>;
using Mat3d = Mat3<double>;
using Mat4d = Mat4<double>;
using Mat6d = Mat6<double>;
using Quatd = Quat<double>;

}  // namespace mrvs
