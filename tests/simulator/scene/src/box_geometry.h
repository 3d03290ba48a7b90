#pragma once
// Boxes of the synthetic scene and their faces (internal to mrvs::sim_scene).
#include <vector>

#include <Eigen/Geometry>

#include "mrvs/sim/scene.h"

namespace mrvs::sim::detail {

/// What a box stands for; decides its placement rules and its texture.
enum class BoxKind { kFloor, kStacked, kWallPanel, kWallSlab, kSidewalk, kBuilding };

/// Name of a kind as written to scene.yaml.
const char* box_kind_name(BoxKind kind);

/// A box rotated by `yaw` about the vertical axis through its centre:
/// p_w = centre + Rz(yaw) * p_local with p_local in [-half, half] (metres, radians).
/// After finalize_box() every number is exactly representable as a float, so the float ray
/// caster and the double Face data describe the same geometry.
struct SceneBox {
  Vec3d centre = Vec3d::Zero();
  Vec3d half = Vec3d::Constant(0.5);
  double yaw = 0.0;      ///< radians about +z
  double cos_yaw = 1.0;  ///< float-rounded cos(yaw)
  double sin_yaw = 0.0;  ///< float-rounded sin(yaw)
  BoxKind kind = BoxKind::kFloor;
  bool rendered = true;
  bool in_map = true;
};

/// Rounds centre, half sizes, cos and sin of `box` to float precision (sets cos_yaw, sin_yaw).
void finalize_box(SceneBox& box);

/// Local x and y axes of the box in the world: (cos, sin, 0) and (-sin, cos, 0).
Vec3d box_axis_x(const SceneBox& box);
Vec3d box_axis_y(const SceneBox& box);

/// World axis-aligned bounding box of `box`.
Eigen::AlignedBox3d box_aabb(const SceneBox& box);

/// Euclidean distance (metres) from `p` to the solid box; 0 inside.
double box_point_distance(const SceneBox& box, const Vec3d& p);

/// Volume (m^3) shared by two boxes (exact: 2-D convex polygon clipping times z overlap).
double box_overlap_volume(const SceneBox& a, const SceneBox& b);

/// Volume of one box, m^3.
double box_volume(const SceneBox& box);

/// The 6 outward faces of `box`, in local order -x, +x, -y, +y, -z, +z; ids first_id..+5.
/// Side faces have axis_v = +z (v = height above the box bottom).
std::vector<Face> box_faces(const SceneBox& box, int object_id, int first_id);

/// The 6 inward faces of the room `room`, in order x-lo, x-hi, y-lo, y-hi, floor, ceiling;
/// ids first_id..+5. Walls have axis_v = +z.
std::vector<Face> room_faces(const Eigen::AlignedBox3d& room, int first_id);

/// Rounds every coordinate of `box` to float precision.
Eigen::AlignedBox3d round_to_float(const Eigen::AlignedBox3d& box);

}  // namespace mrvs::sim::detail
