#include "mrvs/edge/stereo_geometry.h"

#include <cmath>

#include "mrvs/geometry/so3.h"

namespace mrvs::edge {

double epipolar_distance(const SE3d& T_c1_c0, const Vec2d& xn0, const Vec2d& xn1) {
  const Mat3d E = skew(T_c1_c0.translation()) * T_c1_c0.rotation_matrix();
  const Vec3d line = E * Vec3d(xn0.x(), xn0.y(), 1.0);
  const double norm = std::hypot(line.x(), line.y());
  if (norm < 1e-15) return 0.0;  // xn0 on the baseline direction: every point is on its line
  return std::abs(line.dot(Vec3d(xn1.x(), xn1.y(), 1.0))) / norm;
}

std::optional<Vec2d> triangulate_depths(const SE3d& T_c1_c0, const Vec2d& xn0, const Vec2d& xn1) {
  // Rays in c1: R * (d0 * f0) + t and d1 * f1; minimise |d0 * a - d1 * f1 + t| over d0, d1.
  const Vec3d a = T_c1_c0.rotation_matrix() * Vec3d(xn0.x(), xn0.y(), 1.0);
  const Vec3d f1(xn1.x(), xn1.y(), 1.0);
  const Vec3d& t = T_c1_c0.translation();
  const double aa = a.dot(a), af = a.dot(f1), ff = f1.dot(f1);
  const double det = aa * ff - af * af;
  if (std::abs(det) < 1e-12 * aa * ff) return std::nullopt;
  const double at = a.dot(t), ft = f1.dot(t);
  const double d0 = (af * ft - ff * at) / det;
  const double d1 = (aa * ft - af * at) / det;
  return Vec2d(d0, d1);
}

}  // namespace mrvs::edge
