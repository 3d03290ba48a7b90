// sim0/scene.yaml (simulator.md 1.8): the whole scene as plain YAML, fixed number format.
#include <iterator>
#include <string>

#include <fmt/format.h>

#include "mrvs/sim/rng.h"
#include "scene_impl.h"

namespace mrvs::sim::detail {
namespace {

std::string vec(const Vec3d& v) { return fmt::format("[{:.9g}, {:.9g}, {:.9g}]", v.x(), v.y(), v.z()); }
const char* flag(bool b) { return b ? "true" : "false"; }

void write_header(const Scene::Impl& s, std::string& out) {
  const SceneOptions& o = s.options;
  int unmapped = 0;
  int removed = 0;
  int textureless = 0;
  for (const SceneBox& b : s.boxes) {
    unmapped += b.in_map ? 0 : 1;
    removed += b.rendered ? 0 : 1;
  }
  for (const Face& f : s.faces) textureless += f.textureless ? 1 : 0;
  const bool indoor = s.profile == SceneProfile::kIndoor;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "# Synthetic scene of mrvs::sim::make_scene (world frame, z up, metres).\n");
  fmt::format_to(it,
                 "# Box k: p_w = centre + Rz(yaw_rad) * p_box with p_box in [lo - centre, hi - centre];\n");
  fmt::format_to(it, "# its faces are ids first_face..first_face+5 (-x, +x, -y, +y, -z, +z of the box).\n");
  fmt::format_to(it, "# Albedo: CounterRng(texture_seed, stream {}) keyed by the face id.\n",
                 static_cast<int>(Stream::kTexture));
  fmt::format_to(it, "profile: {}\nseed: {}\ntexture_seed: {}\n", indoor ? "indoor" : "outdoor", s.seed,
                 s.seed);
  fmt::format_to(it, "texel_size_m: {:.9g}\n", indoor ? o.texel_size_m : static_cast<double>(kStreetTexel));
  fmt::format_to(
      it,
      "options: {{num_boxes: {}, clearance_m: {:.9g}, room_margin_m: {:.9g}, textureless_fraction: "
      "{:.9g}, unmapped_objects: {}, removed_objects: {}, rotated_fraction: {:.9g}}}\n",
      o.num_boxes, o.clearance_m, o.room_margin_m, o.textureless_fraction, o.unmapped_objects,
      o.removed_objects, o.rotated_fraction);
  fmt::format_to(it, "bounds: {{min: {}, max: {}}}\n", vec(s.bounds.min()), vec(s.bounds.max()));
  if (indoor) fmt::format_to(it, "room: {{min: {}, max: {}}}\n", vec(s.room.min()), vec(s.room.max()));
  fmt::format_to(
      it, "counts: {{boxes: {}, faces: {}, unmapped: {}, removed: {}, textureless_faces: {}, dynamic: 0}}\n",
      s.boxes.size(), s.faces.size(), unmapped, removed, textureless);
}

void write_streets(const Scene::Impl& s, std::string& out) {
  auto it = std::back_inserter(out);
  fmt::format_to(it, "legs:\n");
  for (const StreetLeg& l : s.street.legs) {
    fmt::format_to(it, "  - {{start: [{:.9g}, {:.9g}], end: [{:.9g}, {:.9g}]}}\n", l.start.x(), l.start.y(),
                   l.end.x(), l.end.y());
  }
  fmt::format_to(it, "arcs:\n");
  for (const StreetArc& a : s.street.arcs) {
    fmt::format_to(it, "  - {{centre: [{:.9g}, {:.9g}], radius: {:.9g}}}\n", a.centre.x(), a.centre.y(),
                   a.radius);
  }
}

void write_boxes(const Scene::Impl& s, int first_face, std::string& out) {
  auto it = std::back_inserter(out);
  fmt::format_to(it, "boxes:\n");
  for (std::size_t k = 0; k < s.boxes.size(); ++k) {
    const SceneBox& b = s.boxes[k];
    fmt::format_to(it,
                   "  - {{id: {}, kind: {}, lo: {}, hi: {}, centre: {}, yaw_rad: {:.9g}, first_face: {}, "
                   "rendered: {}, in_map: {}, dynamic: false}}\n",
                   k, box_kind_name(b.kind), vec(b.centre - b.half), vec(b.centre + b.half), vec(b.centre),
                   b.yaw, first_face + 6 * static_cast<int>(k), flag(b.rendered), flag(b.in_map));
  }
}

void write_faces(const Scene::Impl& s, std::string& out) {
  auto it = std::back_inserter(out);
  fmt::format_to(it, "faces:\n");
  for (const Face& f : s.faces) {
    fmt::format_to(it,
                   "  - {{id: {}, object: {}, origin: {}, axis_u: {}, axis_v: {}, size: [{:.9g}, {:.9g}], "
                   "rendered: {}, in_map: {}, textureless: {}}}\n",
                   f.id, f.object_id, vec(f.origin), vec(f.axis_u), vec(f.axis_v), f.size_u, f.size_v,
                   flag(f.rendered), flag(f.in_map), flag(f.textureless));
  }
}

}  // namespace

std::string scene_yaml(const Scene::Impl& s) {
  std::string out;
  write_header(s, out);
  const bool indoor = s.profile == SceneProfile::kIndoor;
  if (!indoor) write_streets(s, out);
  write_boxes(s, indoor ? 6 : 1, out);
  write_faces(s, out);
  return out;
}

}  // namespace mrvs::sim::detail
