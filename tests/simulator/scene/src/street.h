#pragma once
// Outdoor street canyon: layout along axis-aligned legs and the analytic / tiled textures of
// its faces (internal to mrvs::sim_scene).
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "box_geometry.h"
#include "mrvs/core/status.h"
#include "mrvs/sim/scene.h"
#include "texture.h"

namespace mrvs::sim::detail {

constexpr double kRoadHalfWidth = 7.0;  ///< 4 x 3.5 m lanes
constexpr double kSidewalkWidth = 4.0;
constexpr double kSidewalkHeight = 0.15;
constexpr double kStreetExtension = 40.0;   ///< street beyond both ends of the route, metres
constexpr double kOuterCornerReach = 41.0;  ///< buildings past a corner on its outer side
constexpr double kGroundMargin = 20.0;      ///< ground beyond the outermost geometry
constexpr float kStreetTexel = 0.02f;       ///< texel of the tiled noise, metres
/// Horizontal clearance of sidewalks and buildings from the route samples, metres: 1 m less
/// than the road half width and the corridor half width, so that a route wandering up to
/// 1 m off its leg line keeps its sidewalks and frontage.
constexpr double kSidewalkClearance = kRoadHalfWidth - 1.0;
constexpr double kBuildingClearance = kRoadHalfWidth + kSidewalkWidth - 1.0;

/// The road of one leg: asphalt over along-coordinate s in [s_lo, s_hi] and |q| <= 7 m,
/// where s = sign * p[axis] grows in driving direction and q is the offset to the left.
struct StreetCorridor {
  int axis = 0;       ///< 0: leg along x, 1: along y
  int sign = 1;       ///< driving direction along the axis
  double line = 0.0;  ///< the other coordinate of the leg's centre line
  double s_lo = 0.0;
  double s_hi = 0.0;
  bool corner_lo = false;  ///< an intersection at s_lo (else the route's open end)
  bool corner_hi = false;

  double along(const Eigen::Vector2d& p) const { return sign * p[axis]; }
  /// Offset to the left of the driving direction.
  double across(const Eigen::Vector2d& p) const {
    return axis == 0 ? sign * (p.y() - line) : -sign * (p.x() - line);
  }
  /// World xy of (s, q).
  Eigen::Vector2d point(double s, double q) const {
    return axis == 0 ? Eigen::Vector2d(sign * s, line + sign * q)
                     : Eigen::Vector2d(line - sign * q, sign * s);
  }
};

/// The quarter circle that joins two legs (road centre line).
struct StreetArc {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  double radius = 0.0;
  Eigen::Vector2d dir_a = Eigen::Vector2d::UnitX();  ///< unit, centre -> arc start
  Eigen::Vector2d dir_b = Eigen::Vector2d::UnitY();  ///< unit, centre -> arc end
};

struct StreetLayout {
  std::vector<StreetLeg> legs;
  std::vector<StreetCorridor> corridors;
  std::vector<StreetArc> arcs;
  std::vector<SceneBox> boxes;  ///< sidewalks, then buildings
  std::vector<int> buildings;   ///< indices into boxes
  Eigen::AlignedBox2d ground;   ///< ground rectangle, world xy
};

/// Lays out corridors, arcs, sidewalks and buildings (SequenceRng(seed, kScene)).
StatusOr<StreetLayout> layout_street(const SceneOptions& options, const std::vector<StreetLeg>& legs,
                                     const std::vector<Vec3d>& keep_clear, std::uint64_t seed);

enum class Material : std::uint8_t { kGround, kSidewalkTop, kConcrete, kFacade, kRoof, kFlat };

/// Per-facade window grid (metres; v = height above the ground).
struct Facade {
  float wall = 0.6f;    ///< wall albedo factor, 0.4-0.8
  float window = 0.2f;  ///< glass albedo, 0.1-0.3
  float pitch = 3.0f;   ///< window spacing along u
  float width = 1.5f;   ///< window width
  float margin = 1.0f;  ///< first window column starts here
  float u_end = 0.0f;   ///< window columns end here
  float top = 0.0f;     ///< windows end below this height
};

/// A shop sign on a facade: rectangle in face (u, v), metres.
struct Sign {
  float u0, u1, v0, v1, value;
};

struct FaceMaterial {
  Material kind = Material::kConcrete;
  float base = 0.5f;
  float off_u = 0.0f;  ///< tile offsets, metres
  float off_v = 0.0f;
  Facade facade;
  int sign_begin = 0;  ///< signs[sign_begin, sign_end)
  int sign_end = 0;
};

/// Albedo of the outdoor faces: analytic patterns (box-filtered over the footprint) times a
/// seamlessly tiled 1024^2 noise texture at 2 cm (simulator.md 3.3).
class StreetAppearance {
 public:
  StreetAppearance() = default;
  /// Materials for `faces` (face 0 = ground, then 6 per box of layout.boxes).
  StreetAppearance(const StreetLayout& layout, const std::vector<Face>& faces, std::uint64_t seed);

  float albedo(int face, float u, float v, float lod) const;

 private:
  float ground(float u, float v, float lod) const;
  float facade(const FaceMaterial& m, float u, float v, float lod) const;
  float tile(const FaceMaterial& m, float u, float v, float lod, float scale) const;

  std::vector<StreetCorridor> corridors_;
  std::vector<StreetArc> arcs_;
  Eigen::Vector2d ground_origin_ = Eigen::Vector2d::Zero();
  MipTexture tile_;
  std::vector<FaceMaterial> materials_;
  std::vector<Sign> signs_;
};

}  // namespace mrvs::sim::detail
