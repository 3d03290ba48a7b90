#pragma once
// Random inputs for the geometry tests (fixed seeds, deterministic).
#include <random>

#include "mrvs/geometry/se3.h"

namespace mrvs::test {

/// Rotation vector with a uniformly random axis and an angle in [min_angle, max_angle].
template <typename S>
Vec3<S> random_rotation_vector(std::mt19937& rng, double min_angle, double max_angle) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> angle(min_angle, max_angle);
  Eigen::Vector3d axis(normal(rng), normal(rng), normal(rng));
  axis.normalize();
  return (axis * angle(rng)).cast<S>();
}

template <typename S>
Vec3<S> random_vector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return Eigen::Vector3d(u(rng), u(rng), u(rng)).cast<S>();
}

template <typename S>
SE3<S> random_pose(std::mt19937& rng) {
  return SE3<S>(so3::exp_quat<S>(random_rotation_vector<S>(rng, 0.0, 3.1)), random_vector<S>(rng, 5.0));
}

/// Angles used by every Jacobian test: exactly zero, tiny, around the series/closed-form
/// switch points, moderate and close to pi.
inline const double kTestAngles[] = {0.0,  1e-9, 1e-6, 1e-4, 9e-3, 1.1e-2, 0.09, 0.11,
                                     0.29, 0.31, 0.49, 0.51, 1.0,  2.0,    3.0};

}  // namespace mrvs::test
