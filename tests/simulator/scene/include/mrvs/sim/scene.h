#pragma once
// The synthetic 3-D scene shared by the renderer, the prior-map sampler and the tests:
// textured rectangles (the faces of axis-aligned boxes, optionally rotated about z, inside
// an inward-facing room, or along a street canyon with a ground plane and sky), a ray
// caster, and the ONE albedo function that both the images and the map intensities read.
//
// Frames: everything is in the world frame w (z up, metres).
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"

namespace mrvs::sim {

using Vec3f = Eigen::Vector3f;

enum class SceneProfile { kIndoor, kOutdoor };

/// A textured rectangle: points origin + u * axis_u + v * axis_v, u in [0, size_u],
/// v in [0, size_v] (metres). normal = axis_u x axis_v points to the side that is seen.
struct Face {
  int id = -1;         ///< index in Scene::faces()
  int object_id = -1;  ///< box index; -1 for the room, the ground and other structure
  Vec3d origin = Vec3d::Zero();
  Vec3d axis_u = Vec3d::UnitX();
  Vec3d axis_v = Vec3d::UnitY();
  Vec3d normal = Vec3d::UnitZ();
  double size_u = 0.0;
  double size_v = 0.0;
  bool rendered = true;      ///< seen by the cameras (false: removed object, map only)
  bool in_map = true;        ///< present in the prior map (false: unmapped object)
  bool textureless = false;  ///< constant albedo with faint low-frequency shading
};

/// A ray-face intersection.
struct Hit {
  float distance = 0.0f;  ///< along the unit ray direction, metres
  int face = -1;          ///< Face::id
  float u = 0.0f;         ///< metres along Face::axis_u
  float v = 0.0f;         ///< metres along Face::axis_v
};

/// Which faces a ray can hit: those the cameras see (rendered), or those the survey
/// scanner saw when the prior map was made (in_map).
enum class Visibility { kCamera, kSurvey };

/// Scene tuning. Defaults are the indoor "Vicon room" of simulator.md section 3.
/// make_scene() rejects values outside the ranges given here.
struct SceneOptions {
  int num_boxes = 20;                 ///< clutter boxes (indoor), [0, 1000]; the first 2 are wall slabs
  double texel_size_m = 0.004;        ///< albedo bake resolution (indoor), [0.001, 1] m
  double clearance_m = 0.6;           ///< min distance of any box from the keep-clear points
  double room_margin_m = 1.5;         ///< room grows to contain the keep-clear points + margin
  double textureless_fraction = 0.0;  ///< share of faces with constant albedo, [0, 1]
  int unmapped_objects = 0;           ///< boxes rendered but absent from the map
  int removed_objects = 0;            ///< boxes in the map but not rendered
  /// Share of the floor and stacked boxes rotated about z by U(-45, 45) degrees, [0, 1].
  double rotated_fraction = 0.3;
};

class Scene {
 public:
  class Impl;
  explicit Scene(std::unique_ptr<Impl> impl);
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;
  ~Scene();

  SceneProfile profile() const;
  const std::vector<Face>& faces() const;
  /// Bounds of all geometry (room, or the built-up area around the route), metres.
  Eigen::AlignedBox3d bounds() const;

  /// Nearest face along origin + t * direction (direction unit), 0 < t <= max_distance.
  /// Faces are one-sided: a ray hits a face only from the side its normal points to, so a
  /// ray starting inside a box does not hit that box. Thread-safe, allocation-free.
  /// Accuracy: float arithmetic, ~1e-5 m for ordinary rays (worse only as |n . d| -> 0).
  std::optional<Hit> intersect(const Vec3f& origin, const Vec3f& direction, float max_distance,
                               Visibility who = Visibility::kCamera) const;
  /// True when a face blocks the open segment from `from` to `to` (shadow ray). Hits within
  /// 1 mm of `from`, or within 1 mm + 1e-4 * |to - from| of `to`, are ignored, so a point on
  /// a face is not occluded by that face.
  bool occluded(const Vec3f& from, const Vec3f& to, Visibility who) const;

  /// Albedo in [0.03, 0.97] of `face` at (u, v) metres. lod = log2(footprint / texel size),
  /// 0 = finest; fractional values blend mip levels (trilinear). The images and the map
  /// intensities both come from this function.
  float albedo(int face, float u, float v, float lod = 0.0f) const;
  /// Size of a level-0 texel of `face`, metres (outdoor: 0.02, the tiled noise texture).
  float texel_size(int face) const;
  /// Radiance in [0, 1] seen along a ray that hits nothing (outdoor sky: DN 200 at the
  /// horizon to 240 at the zenith, faint clouds). Indoor rays always hit the room.
  float background(const Vec3f& direction) const;

  /// The scene as YAML (bounds, every box and face with its flags, texel size, seeds) for
  /// sim0/scene.yaml. Box k: lo/hi = centre -/+ half sizes in the box frame, yaw_rad about
  /// the vertical through the centre; its faces are ids first_face..first_face + 5
  /// (-x, +x, -y, +y, -z, +z). Byte-identical for the same inputs.
  std::string to_yaml() const;

 private:
  std::unique_ptr<Impl> impl_;
};

/// One straight, axis-aligned leg of a car route (outdoor profile): world xy, metres, in
/// driving order (start -> end). Consecutive legs are perpendicular; the route joins them
/// with an arc that starts at the end of one leg and ends at the start of the next.
struct StreetLeg {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
};

/// Infers the legs of a car route from its samples (positions in driving order, any height):
/// samples are thinned to >= 1 m steps, steps within 2 degrees of the x or y axis are grouped
/// into runs, runs of >= 5 m become legs (the leg line is the median cross coordinate of
/// the run), and collinear neighbours are merged. Fails when no leg is found or when two
/// consecutive legs are not perpendicular.
StatusOr<std::vector<StreetLeg>> infer_street_legs(const std::vector<Vec3d>& route);

/// The outdoor street canyon along explicit `legs` (simulator.md 3.3): road plane z = 0,
/// 14 m wide and centred on the legs, 4 m sidewalks 0.15 m high, buildings on both sides,
/// open intersections at the turns, 40 m of street beyond both ends of the route. Buildings
/// stand >= 11 m and sidewalks >= 7 m from the leg lines, and stay >= 10 m and >= 6 m
/// (horizontally) from every `keep_clear` point and from the legs and arcs themselves; options.num_boxes is
/// not used; unmapped/removed objects are buildings. Face 0 is the ground (u = x - x0, v = y - y0 over the
/// built-up area + 20 m); rays leaving it hit nothing (sky). make_scene(kOutdoor, ...) calls this with
/// infer_street_legs(keep_clear).
StatusOr<Scene> make_street_scene(const SceneOptions& options, const std::vector<StreetLeg>& legs,
                                  const std::vector<Vec3d>& keep_clear, std::uint64_t seed);

/// Builds the scene for `profile`, keeping every box at least options.clearance_m away from
/// `keep_clear` (trajectory samples and camera centres; for outdoor, the route). The same
/// (options, keep_clear, seed) always gives the same scene, whatever the thread count.
/// Indoor: the V1 room grown to hold keep_clear + room_margin_m in x, y and up (the floor
/// stays at z = 0 unless a point is closer than clearance_m to it), face ids 0-5 the room
/// (x-lo, x-hi, y-lo, y-hi, floor, ceiling), then 6 per box; layout from
/// SequenceRng(seed, kScene), textures from (seed, kTexture, face id), baked in ~0.3-0.7 s.
/// Outdoor: see make_street_scene(); face 0 is the ground. Errors: options out of range,
/// non-finite points, boxes that cannot be placed, no route legs.
StatusOr<Scene> make_scene(SceneProfile profile, const SceneOptions& options,
                           const std::vector<Vec3d>& keep_clear, std::uint64_t seed);

}  // namespace mrvs::sim
