#include "box_geometry.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace mrvs::sim::detail {
namespace {

double to_float(double x) { return static_cast<double>(static_cast<float>(x)); }

using Polygon = std::vector<Eigen::Vector2d>;

/// Footprint corners of the box in the xy plane, counter-clockwise.
Polygon footprint(const SceneBox& box) {
  const Eigen::Vector2d c = box.centre.head<2>();
  const Eigen::Vector2d ex = box_axis_x(box).head<2>() * box.half.x();
  const Eigen::Vector2d ey = box_axis_y(box).head<2>() * box.half.y();
  return {c - ex - ey, c + ex - ey, c + ex + ey, c - ex + ey};
}

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

/// Sutherland-Hodgman: the part of `poly` left of the directed edge a -> b.
Polygon clip_half_plane(const Polygon& poly, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  Polygon out;
  const std::size_t n = poly.size();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& p = poly[i];
    const Eigen::Vector2d& q = poly[(i + 1) % n];
    const double sp = cross2(b - a, p - a);
    const double sq = cross2(b - a, q - a);
    if (sp >= 0.0) out.push_back(p);
    if ((sp >= 0.0) != (sq >= 0.0)) out.push_back(p + (q - p) * (sp / (sp - sq)));
  }
  return out;
}

double polygon_area(const Polygon& poly) {
  double twice = 0.0;
  for (std::size_t i = 0; i < poly.size(); ++i) twice += cross2(poly[i], poly[(i + 1) % poly.size()]);
  return 0.5 * std::abs(twice);
}

Face make_face(int id, int object_id, const Vec3d& origin, const Vec3d& axis_u, const Vec3d& axis_v,
               double size_u, double size_v) {
  Face f;
  f.id = id;
  f.object_id = object_id;
  f.origin = origin;
  f.axis_u = axis_u;
  f.axis_v = axis_v;
  f.normal = axis_u.cross(axis_v).normalized();
  f.size_u = size_u;
  f.size_v = size_v;
  return f;
}

}  // namespace

const char* box_kind_name(BoxKind kind) {
  switch (kind) {
    case BoxKind::kFloor:
      return "floor";
    case BoxKind::kStacked:
      return "stacked";
    case BoxKind::kWallPanel:
      return "wall_panel";
    case BoxKind::kWallSlab:
      return "wall_slab";
    case BoxKind::kSidewalk:
      return "sidewalk";
    case BoxKind::kBuilding:
      return "building";
  }
  return "unknown";
}

void finalize_box(SceneBox& box) {
  for (int i = 0; i < 3; ++i) {
    box.centre[i] = to_float(box.centre[i]);
    box.half[i] = to_float(box.half[i]);
  }
  box.cos_yaw = to_float(std::cos(box.yaw));
  box.sin_yaw = to_float(std::sin(box.yaw));
}

Vec3d box_axis_x(const SceneBox& box) { return Vec3d(box.cos_yaw, box.sin_yaw, 0.0); }
Vec3d box_axis_y(const SceneBox& box) { return Vec3d(-box.sin_yaw, box.cos_yaw, 0.0); }

Eigen::AlignedBox3d box_aabb(const SceneBox& box) {
  const double rx = std::abs(box.cos_yaw) * box.half.x() + std::abs(box.sin_yaw) * box.half.y();
  const double ry = std::abs(box.sin_yaw) * box.half.x() + std::abs(box.cos_yaw) * box.half.y();
  const Vec3d r(rx, ry, box.half.z());
  return Eigen::AlignedBox3d(box.centre - r, box.centre + r);
}

double box_point_distance(const SceneBox& box, const Vec3d& p) {
  const Vec3d d = p - box.centre;
  const Vec3d local(d.dot(box_axis_x(box)), d.dot(box_axis_y(box)), d.z());
  const Vec3d outside = (local.cwiseAbs() - box.half).cwiseMax(0.0);
  return outside.norm();
}

double box_overlap_volume(const SceneBox& a, const SceneBox& b) {
  const double z0 = std::max(a.centre.z() - a.half.z(), b.centre.z() - b.half.z());
  const double z1 = std::min(a.centre.z() + a.half.z(), b.centre.z() + b.half.z());
  if (z1 <= z0) return 0.0;
  if (!box_aabb(a).intersects(box_aabb(b))) return 0.0;
  Polygon poly = footprint(a);
  const Polygon clip = footprint(b);
  for (std::size_t i = 0; i < clip.size() && !poly.empty(); ++i) {
    poly = clip_half_plane(poly, clip[i], clip[(i + 1) % clip.size()]);
  }
  return poly.size() < 3 ? 0.0 : polygon_area(poly) * (z1 - z0);
}

double box_volume(const SceneBox& box) { return 8.0 * box.half.x() * box.half.y() * box.half.z(); }

std::vector<Face> box_faces(const SceneBox& box, int object_id, int first_id) {
  const Vec3d ex = box_axis_x(box);
  const Vec3d ey = box_axis_y(box);
  const Vec3d ez = Vec3d::UnitZ();
  const Vec3d& c = box.centre;
  const Vec3d hx = ex * box.half.x();
  const Vec3d hy = ey * box.half.y();
  const Vec3d hz = ez * box.half.z();
  const double sx = 2.0 * box.half.x();
  const double sy = 2.0 * box.half.y();
  const double sz = 2.0 * box.half.z();
  std::vector<Face> faces;
  faces.reserve(6);
  int id = first_id;
  faces.push_back(make_face(id++, object_id, c - hx + hy - hz, -ey, ez, sy, sz));  // -x
  faces.push_back(make_face(id++, object_id, c + hx - hy - hz, ey, ez, sy, sz));   // +x
  faces.push_back(make_face(id++, object_id, c - hx - hy - hz, ex, ez, sx, sz));   // -y
  faces.push_back(make_face(id++, object_id, c + hx + hy - hz, -ex, ez, sx, sz));  // +y
  faces.push_back(make_face(id++, object_id, c - hx - hy - hz, ey, ex, sy, sx));   // -z
  faces.push_back(make_face(id++, object_id, c - hx - hy + hz, ex, ey, sx, sy));   // +z
  for (Face& f : faces) {
    f.rendered = box.rendered;
    f.in_map = box.in_map;
  }
  return faces;
}

std::vector<Face> room_faces(const Eigen::AlignedBox3d& room, int first_id) {
  const Vec3d lo = room.min();
  const Vec3d hi = room.max();
  const Vec3d s = hi - lo;
  const Vec3d ex = Vec3d::UnitX();
  const Vec3d ey = Vec3d::UnitY();
  const Vec3d ez = Vec3d::UnitZ();
  std::vector<Face> faces;
  faces.reserve(6);
  int id = first_id;
  faces.push_back(make_face(id++, -1, lo, ey, ez, s.y(), s.z()));                              // x-lo
  faces.push_back(make_face(id++, -1, Vec3d(hi.x(), hi.y(), lo.z()), -ey, ez, s.y(), s.z()));  // x-hi
  faces.push_back(make_face(id++, -1, Vec3d(hi.x(), lo.y(), lo.z()), -ex, ez, s.x(), s.z()));  // y-lo
  faces.push_back(make_face(id++, -1, Vec3d(lo.x(), hi.y(), lo.z()), ex, ez, s.x(), s.z()));   // y-hi
  faces.push_back(make_face(id++, -1, lo, ex, ey, s.x(), s.y()));                              // floor
  faces.push_back(make_face(id++, -1, Vec3d(lo.x(), lo.y(), hi.z()), ey, ex, s.y(), s.x()));   // ceiling
  return faces;
}

Eigen::AlignedBox3d round_to_float(const Eigen::AlignedBox3d& box) {
  Vec3d lo = box.min();
  Vec3d hi = box.max();
  for (int i = 0; i < 3; ++i) {
    lo[i] = to_float(lo[i]);
    hi[i] = to_float(hi[i]);
  }
  return Eigen::AlignedBox3d(lo, hi);
}

}  // namespace mrvs::sim::detail
