#pragma once
// Helpers of the scene tests: keep-clear paths, a car route, the brute-force reference ray
// caster over Scene::faces(), and point-to-box distances rebuilt from the faces.
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <vector>

#include "mrvs/sim/rng.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim::test {

/// A closed loop through the middle of the default room, z 0.9-1.9 m (400 samples).
inline std::vector<Vec3d> indoor_path() {
  std::vector<Vec3d> p;
  for (int k = 0; k < 400; ++k) {
    const double t = 2.0 * M_PI * k / 400.0;
    p.emplace_back(-0.3 + 2.0 * std::cos(t), 0.8 + 2.2 * std::sin(t), 1.4 + 0.5 * std::sin(3.0 * t));
  }
  return p;
}

/// The car route of simulator.md 2.8 at 1.7 m: 180 m along +x, a right turn of radius
/// 18 m, 120 m along -y (samples every 0.5 m).
inline std::vector<Vec3d> car_route() {
  constexpr double kR = 18.0;
  std::vector<Vec3d> p;
  for (double s = 0.0; s <= 180.0; s += 0.5) p.emplace_back(s, 0.0, 1.7);
  for (int k = 1; k < 56; ++k) {
    const double a = 0.5 * M_PI * k / 56.0;
    p.emplace_back(180.0 + kR * std::sin(a), -kR + kR * std::cos(a), 1.7);
  }
  for (double s = 0.0; s <= 120.0; s += 0.5) p.emplace_back(180.0 + kR, -kR - s, 1.7);
  return p;
}

/// Reference hit: nearest one-sided face crossing in double precision.
struct RefHit {
  double t = std::numeric_limits<double>::infinity();
  int face = -1;
  double cos_incidence = 0.0;  ///< |n . d| of the hit face
};

inline bool visible_to(const Face& f, Visibility who) {
  return who == Visibility::kCamera ? f.rendered : f.in_map;
}

inline RefHit brute_force(const std::vector<Face>& faces, const Vec3f& of, const Vec3f& df, double t_max,
                          Visibility who, double t_min = 0.0) {
  const Vec3d o = of.cast<double>();
  const Vec3d d = df.cast<double>();
  RefHit best;
  for (const Face& f : faces) {
    if (!visible_to(f, who)) continue;
    const double denom = f.normal.dot(d);
    if (!(denom < 0.0)) continue;
    const double t = f.normal.dot(f.origin - o) / denom;
    if (!(t > t_min && t <= t_max && t < best.t)) continue;
    const Vec3d p = o + t * d - f.origin;
    const double u = p.dot(f.axis_u);
    const double v = p.dot(f.axis_v);
    if (u < 0.0 || u > f.size_u || v < 0.0 || v > f.size_v) continue;
    best = RefHit{t, f.id, -denom};
  }
  return best;
}

/// Distance (metres) of the point p = o + t d from the boundary of face f (after
/// projection onto its plane); negative when outside the rectangle.
inline double edge_distance(const Face& f, const Vec3d& p) {
  const Vec3d q = p - f.origin;
  const double u = q.dot(f.axis_u);
  const double v = q.dot(f.axis_v);
  return std::min(std::min(u, f.size_u - u), std::min(v, f.size_v - v));
}

/// The faces of each object id (boxes), six each.
inline std::map<int, std::vector<Face>> faces_by_object(const std::vector<Face>& faces) {
  std::map<int, std::vector<Face>> out;
  for (const Face& f : faces) {
    if (f.object_id >= 0) out[f.object_id].push_back(f);
  }
  return out;
}

/// True when p is inside the convex box bounded by `box_faces` (outward normals).
inline bool inside_box(const std::vector<Face>& box_faces, const Vec3d& p, double tol = 0.0) {
  for (const Face& f : box_faces) {
    if ((p - f.origin).dot(f.normal) > tol) return false;
  }
  return true;
}

/// Distance from p to the solid box bounded by `box_faces`.
inline double box_distance(const std::vector<Face>& box_faces, const Vec3d& p) {
  if (inside_box(box_faces, p)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (const Face& f : box_faces) {
    const Vec3d q = p - f.origin;
    const double u = std::clamp(q.dot(f.axis_u), 0.0, f.size_u);
    const double v = std::clamp(q.dot(f.axis_v), 0.0, f.size_v);
    best = std::min(best, (q - u * f.axis_u - v * f.axis_v).norm());
  }
  return best;
}

/// Uniform unit vector from three counter-based draws.
inline Vec3f random_direction(const CounterRng& rng, std::uint64_t i) {
  const double z = rng.uniform(-1.0, 1.0, i, 1);
  const double a = rng.uniform(0.0, 2.0 * M_PI, i, 2);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Vec3f(static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a)),
               static_cast<float>(z));
}

}  // namespace mrvs::sim::test
