#pragma once
// Ray caster over boxes (rotated about z), an optional inward-facing room and an optional
// ground rectangle, with a uniform 2-D grid over xy walked by DDA (internal to
// mrvs::sim_scene). Faces are one-sided: a ray only hits a face whose normal opposes it.
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Geometry>

#include "box_geometry.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim::detail {

/// Visibility bits of a box: rendered (camera) and in_map (survey).
constexpr std::uint8_t kMaskCamera = 1;
constexpr std::uint8_t kMaskSurvey = 2;

inline std::uint8_t visibility_mask(Visibility who) {
  return who == Visibility::kCamera ? kMaskCamera : kMaskSurvey;
}

/// Float copy of a SceneBox for the inner loop.
struct CasterBox {
  float c[3];
  float h[3];
  float cos_yaw;
  float sin_yaw;
  int first_face;
  std::uint8_t mask;
  bool axis_aligned;
};

/// Per grid cell, copies of its boxes as structure of arrays (vectorised slab tests):
/// axis-aligned boxes themselves, rotated boxes as their world AABB.
struct RayCasterItems {
  std::vector<float> cx, cy, cz, hx, hy, hz;
  std::vector<int> mask;
  std::vector<int> box;
  void push(const CasterBox& b, int index);
};

class RayCaster {
 public:
  /// Adds a box whose 6 faces have ids first_face..first_face + 5 (box_faces() order).
  void add_box(const SceneBox& box, int first_face);
  /// Inward-facing room with faces first_face..+5 (room_faces() order).
  void set_room(const Eigen::AlignedBox3d& room, int first_face);
  /// Upward-facing ground rectangle [x0, x1] x [y0, y1] at height z; u = x - x0, v = y - y0.
  void set_ground(double x0, double y0, double x1, double y1, double z, int face);
  /// Builds the 2-D grid with square cells of `cell_size` metres. Call after adding boxes.
  void build(double cell_size);

  /// Nearest hit with t_min < t <= t_max among faces whose visibility mask has `mask`.
  std::optional<Hit> intersect(const Vec3f& origin, const Vec3f& direction, float t_min, float t_max,
                               std::uint8_t mask) const;

  std::size_t num_boxes() const { return boxes_.size(); }
  int grid_nx() const { return nx_; }
  int grid_ny() const { return ny_; }

 private:
  struct Ray;
  struct Best;
  void test_room(const Ray& ray, float t_min, Best& best) const;
  void test_ground(const Ray& ray, float t_min, Best& best) const;
  void walk_grid(const Ray& ray, float t_min, std::uint8_t mask, Best& best) const;
  void test_items(int cell, const Ray& ray, float t_min, std::uint8_t mask, Best& best) const;
  Hit make_hit(const Ray& ray, const Best& best) const;

  std::vector<CasterBox> boxes_;
  bool has_room_ = false;
  float room_lo_[3] = {0, 0, 0};
  float room_hi_[3] = {0, 0, 0};
  int room_face_ = -1;
  bool has_ground_ = false;
  float ground_[5] = {0, 0, 0, 0, 0};  // x0, y0, x1, y1, z
  int ground_face_ = -1;
  // Grid over [gx0, gx0 + nx * cell] x [gy0, gy0 + ny * cell], z in [gz0, gz1].
  float gx0_ = 0, gy0_ = 0, gz0_ = 0, gz1_ = 0, cell_ = 1, inv_cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<int> cell_begin_;  // nx * ny + 1 offsets into items_
  std::vector<int> cell_mid_;    // per cell: axis-aligned items first, rotated from here
  RayCasterItems items_;
};

}  // namespace mrvs::sim::detail
