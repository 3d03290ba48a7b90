#pragma once
// Scene::Impl: the data behind mrvs::sim::Scene (internal to mrvs::sim_scene).
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "box_geometry.h"
#include "mrvs/sim/scene.h"
#include "ray_caster.h"
#include "street.h"
#include "texture.h"

namespace mrvs::sim {

class Scene::Impl {
 public:
  SceneProfile profile = SceneProfile::kIndoor;
  SceneOptions options;
  std::uint64_t seed = 0;
  Eigen::AlignedBox3d bounds;
  Eigen::AlignedBox3d room;  ///< indoor only
  std::vector<detail::SceneBox> boxes;
  std::vector<Face> faces;
  detail::RayCaster caster;
  std::vector<detail::MipTexture> textures;  ///< indoor: one per face
  detail::StreetLayout street;               ///< outdoor only
  detail::StreetAppearance street_look;      ///< outdoor only
  std::vector<float> sky_lattice;            ///< 64 x 64 cloud lattice, [0, 1)
  double bake_seconds = 0.0;
};

namespace detail {
/// Size of the periodic cloud lattice of background().
constexpr int kSkyLattice = 64;
/// Fills impl.sky_lattice from (seed, kTexture).
void make_sky(Scene::Impl& impl);
/// Radiance of the sky along `direction` (unit), in [0, 1].
float sky_radiance(const Scene::Impl& impl, const Vec3f& direction);
/// Marks round(fraction * faces) faces textureless, chosen by (seed, kTexture) hash order.
void choose_textureless(std::vector<Face>& faces, double fraction, std::uint64_t seed);
/// scene.yaml text.
std::string scene_yaml(const Scene::Impl& impl);
}  // namespace detail

}  // namespace mrvs::sim
