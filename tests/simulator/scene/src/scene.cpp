#include "mrvs/sim/scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "layout.h"
#include "mrvs/sim/rng.h"
#include "scene_impl.h"

namespace mrvs::sim {
namespace {

constexpr double kIndoorCell = 50.0;   ///< indoor: one cell (brute force over the vectorised boxes)
constexpr double kOutdoorCell = 10.0;  ///< simulator.md 4.2
constexpr double kMinTexel = 1e-3;     ///< finer bakes would need gigabytes
constexpr double kMaxTexel = 1.0;
constexpr double kMaxTexels = 4e8;  ///< level-0 texels of all indoor faces together
/// occluded(): hits closer than this to either end of the segment are ignored, so a point
/// on a face is not occluded by that face (metres, plus kShadowRelative * length at the end).
constexpr float kShadowAbsolute = 1e-3f;
constexpr float kShadowRelative = 1e-4f;

bool finite_points(const std::vector<Vec3d>& points) {
  return std::all_of(points.begin(), points.end(), [](const Vec3d& p) { return p.allFinite(); });
}

Status validate(SceneProfile profile, const SceneOptions& o, const std::vector<Vec3d>& keep_clear) {
  const auto bad = [](const std::string& what) { return absl::InvalidArgumentError(what); };
  if (o.num_boxes < 0 || o.num_boxes > 1000) {
    return bad(fmt::format("num_boxes = {} is outside [0, 1000]", o.num_boxes));
  }
  if (!(o.texel_size_m >= kMinTexel && o.texel_size_m <= kMaxTexel)) {
    return bad(fmt::format("texel_size_m = {} is outside [{}, {}] m", o.texel_size_m, kMinTexel, kMaxTexel));
  }
  if (!(o.clearance_m >= 0.0 && std::isfinite(o.clearance_m))) {
    return bad(fmt::format("clearance_m = {} must be finite and >= 0", o.clearance_m));
  }
  if (!(o.room_margin_m >= 0.0 && std::isfinite(o.room_margin_m))) {
    return bad(fmt::format("room_margin_m = {} must be finite and >= 0", o.room_margin_m));
  }
  if (!(o.textureless_fraction >= 0.0 && o.textureless_fraction <= 1.0)) {
    return bad(fmt::format("textureless_fraction = {} is outside [0, 1]", o.textureless_fraction));
  }
  if (!(o.rotated_fraction >= 0.0 && o.rotated_fraction <= 1.0)) {
    return bad(fmt::format("rotated_fraction = {} is outside [0, 1]", o.rotated_fraction));
  }
  if (o.unmapped_objects < 0 || o.removed_objects < 0) {
    return bad(fmt::format("unmapped_objects ({}) and removed_objects ({}) must be >= 0", o.unmapped_objects,
                           o.removed_objects));
  }
  if (profile == SceneProfile::kIndoor && o.unmapped_objects + o.removed_objects > o.num_boxes) {
    return bad(fmt::format("unmapped_objects ({}) + removed_objects ({}) exceed num_boxes ({}); lower them",
                           o.unmapped_objects, o.removed_objects, o.num_boxes));
  }
  if (!finite_points(keep_clear)) return bad("a keep-clear point is not finite");
  return absl::OkStatus();
}

/// Faces of all boxes after `first` faces; box k gets object id k (or -1 when `structure`).
void append_box_faces(const std::vector<detail::SceneBox>& boxes, std::vector<Face>& faces) {
  for (std::size_t k = 0; k < boxes.size(); ++k) {
    const bool structure = boxes[k].kind == detail::BoxKind::kSidewalk;
    const std::vector<Face> f =
        detail::box_faces(boxes[k], structure ? -1 : static_cast<int>(k), static_cast<int>(faces.size()));
    faces.insert(faces.end(), f.begin(), f.end());
  }
}

void add_boxes_to_caster(Scene::Impl& impl, int first_face) {
  for (std::size_t k = 0; k < impl.boxes.size(); ++k) {
    impl.caster.add_box(impl.boxes[k], first_face + 6 * static_cast<int>(k));
  }
}

Status bake_indoor(Scene::Impl& impl) {
  double texels = 0.0;
  const double t = impl.options.texel_size_m;
  for (const Face& f : impl.faces) texels += std::ceil(f.size_u / t) * std::ceil(f.size_v / t);
  if (texels > kMaxTexels) {
    return absl::ResourceExhaustedError(fmt::format(
        "the scene needs {:.0f} M texels at texel_size_m = {} (limit {:.0f} M); raise texel_size_m",
        texels * 1e-6, t, kMaxTexels * 1e-6));
  }
  const auto start = std::chrono::steady_clock::now();
  impl.textures = detail::bake_indoor_faces(impl.faces, impl.seed, static_cast<float>(t));
  impl.bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return absl::OkStatus();
}

StatusOr<Scene> make_indoor(const SceneOptions& options, const std::vector<Vec3d>& keep_clear,
                            std::uint64_t seed) {
  MRVS_ASSIGN_OR_RETURN(detail::IndoorLayout layout, detail::layout_indoor(options, keep_clear, seed));
  auto impl = std::make_unique<Scene::Impl>();
  impl->profile = SceneProfile::kIndoor;
  impl->options = options;
  impl->seed = seed;
  impl->room = layout.room;
  impl->bounds = layout.room;
  impl->boxes = std::move(layout.boxes);
  impl->faces = detail::room_faces(impl->room, 0);
  append_box_faces(impl->boxes, impl->faces);
  detail::choose_textureless(impl->faces, options.textureless_fraction, seed);
  MRVS_RETURN_IF_ERROR(bake_indoor(*impl));
  impl->caster.set_room(impl->room, 0);
  add_boxes_to_caster(*impl, 6);
  impl->caster.build(kIndoorCell);
  detail::make_sky(*impl);
  return Scene(std::move(impl));
}

Face ground_face(const Eigen::AlignedBox2d& g) {
  Face f;
  f.id = 0;
  f.origin = Vec3d(g.min().x(), g.min().y(), 0.0);
  f.axis_u = Vec3d::UnitX();
  f.axis_v = Vec3d::UnitY();
  f.normal = Vec3d::UnitZ();
  f.size_u = g.sizes().x();
  f.size_v = g.sizes().y();
  return f;
}

}  // namespace

namespace detail {

void choose_textureless(std::vector<Face>& faces, double fraction, std::uint64_t seed) {
  const auto count = static_cast<std::size_t>(std::lround(fraction * static_cast<double>(faces.size())));
  if (count == 0) return;
  const CounterRng rng(seed, Stream::kTexture);
  std::vector<std::pair<std::uint64_t, int>> order;
  for (const Face& f : faces) order.emplace_back(rng.bits(static_cast<std::uint64_t>(f.id), 0x7E1E55), f.id);
  std::sort(order.begin(), order.end());
  for (std::size_t i = 0; i < count && i < order.size(); ++i) faces[order[i].second].textureless = true;
}

}  // namespace detail

Scene::Scene(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;

SceneProfile Scene::profile() const { return impl_->profile; }
const std::vector<Face>& Scene::faces() const { return impl_->faces; }
Eigen::AlignedBox3d Scene::bounds() const { return impl_->bounds; }

std::optional<Hit> Scene::intersect(const Vec3f& origin, const Vec3f& direction, float max_distance,
                                    Visibility who) const {
  return impl_->caster.intersect(origin, direction, 0.0f, max_distance, detail::visibility_mask(who));
}

bool Scene::occluded(const Vec3f& from, const Vec3f& to, Visibility who) const {
  const Vec3f d = to - from;
  const float length = d.norm();
  const float t_max = length - kShadowAbsolute - kShadowRelative * length;
  if (!(t_max > kShadowAbsolute)) return false;
  return impl_->caster.intersect(from, d / length, kShadowAbsolute, t_max, detail::visibility_mask(who))
      .has_value();
}

float Scene::albedo(int face, float u, float v, float lod) const {
  if (face < 0 || face >= static_cast<int>(impl_->faces.size())) return 0.5f;
  if (impl_->profile == SceneProfile::kIndoor) return impl_->textures[face].sample(u, v, lod);
  return impl_->street_look.albedo(face, u, v, lod);
}

float Scene::texel_size(int face) const {
  if (impl_->profile == SceneProfile::kOutdoor) return detail::kStreetTexel;
  if (face < 0 || face >= static_cast<int>(impl_->textures.size())) {
    return static_cast<float>(impl_->options.texel_size_m);
  }
  return impl_->textures[face].texel();
}

float Scene::background(const Vec3f& direction) const { return detail::sky_radiance(*impl_, direction); }

std::string Scene::to_yaml() const { return detail::scene_yaml(*impl_); }

StatusOr<Scene> make_street_scene(const SceneOptions& options, const std::vector<StreetLeg>& legs,
                                  const std::vector<Vec3d>& keep_clear, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(validate(SceneProfile::kOutdoor, options, keep_clear));
  MRVS_ASSIGN_OR_RETURN(detail::StreetLayout layout, detail::layout_street(options, legs, keep_clear, seed));
  auto impl = std::make_unique<Scene::Impl>();
  impl->profile = SceneProfile::kOutdoor;
  impl->options = options;
  impl->seed = seed;
  impl->boxes = layout.boxes;
  impl->faces.push_back(ground_face(layout.ground));
  append_box_faces(impl->boxes, impl->faces);
  detail::choose_textureless(impl->faces, options.textureless_fraction, seed);
  double top = 0.0;
  for (const detail::SceneBox& b : impl->boxes) top = std::max(top, b.centre.z() + b.half.z());
  impl->bounds = Eigen::AlignedBox3d(Vec3d(layout.ground.min().x(), layout.ground.min().y(), 0.0),
                                     Vec3d(layout.ground.max().x(), layout.ground.max().y(), top));
  const auto start = std::chrono::steady_clock::now();
  impl->street_look = detail::StreetAppearance(layout, impl->faces, seed);
  impl->bake_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  impl->street = std::move(layout);
  impl->caster.set_ground(impl->bounds.min().x(), impl->bounds.min().y(), impl->bounds.max().x(),
                          impl->bounds.max().y(), 0.0, 0);
  add_boxes_to_caster(*impl, 1);
  impl->caster.build(kOutdoorCell);
  detail::make_sky(*impl);
  return Scene(std::move(impl));
}

StatusOr<Scene> make_scene(SceneProfile profile, const SceneOptions& options,
                           const std::vector<Vec3d>& keep_clear, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(validate(profile, options, keep_clear));
  if (profile == SceneProfile::kIndoor) return make_indoor(options, keep_clear, seed);
  MRVS_ASSIGN_OR_RETURN(std::vector<StreetLeg> legs, infer_street_legs(keep_clear));
  return make_street_scene(options, legs, keep_clear, seed);
}

}  // namespace mrvs::sim
