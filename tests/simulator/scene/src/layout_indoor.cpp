// Indoor "Vicon room" layout (simulator.md 3.1).
#include <algorithm>
#include <cmath>
#include <numeric>

#include <fmt/format.h>

#include "layout.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim::detail {
namespace {

constexpr double kMinSize = 0.3;  ///< clutter box edge range, metres
constexpr double kMaxSize = 1.2;
constexpr double kInsideTolerance = 1e-5;  ///< float rounding of boxes flush with a wall

/// Box flush against wall `wall` (0: x-lo, 1: x-hi, 2: y-lo, 3: y-hi) of `room`: `along` is
/// its centre coordinate along the wall, `thickness` its extent away from the wall.
SceneBox against_wall(const Eigen::AlignedBox3d& room, int wall, double along, double width, double thickness,
                      double z0, double height) {
  SceneBox b;
  const bool x_wall = wall < 2;
  const double plane = (wall % 2 == 0) ? (x_wall ? room.min().x() : room.min().y()) + 0.5 * thickness
                                       : (x_wall ? room.max().x() : room.max().y()) - 0.5 * thickness;
  b.centre = x_wall ? Vec3d(plane, along, z0 + 0.5 * height) : Vec3d(along, plane, z0 + 0.5 * height);
  b.half = x_wall ? Vec3d(0.5 * thickness, 0.5 * width, 0.5 * height)
                  : Vec3d(0.5 * width, 0.5 * thickness, 0.5 * height);
  return b;
}

/// Centre coordinate along wall `wall` for a box of `width`, uniform over the wall.
double along_wall(SequenceRng& rng, const Eigen::AlignedBox3d& room, int wall, double width) {
  const int axis = wall < 2 ? 1 : 0;
  const double lo = room.min()[axis] + 0.5 * width;
  const double hi = room.max()[axis] - 0.5 * width;
  return hi > lo ? rng.uniform(lo, hi) : 0.5 * (room.min()[axis] + room.max()[axis]);
}

/// A large "mattress" slab standing on the floor against a wall.
SceneBox propose_slab(SequenceRng& rng, const Eigen::AlignedBox3d& room) {
  const int wall = rng.integer(0, 3);
  const double width = rng.uniform(1.5, 2.5);
  const double height = rng.uniform(1.5, 2.2);
  const double thickness = rng.uniform(0.15, 0.3);
  SceneBox b =
      against_wall(room, wall, along_wall(rng, room, wall, width), width, thickness, room.min().z(), height);
  b.kind = BoxKind::kWallSlab;
  return b;
}

/// A thin panel hanging on a wall.
SceneBox propose_panel(SequenceRng& rng, const Eigen::AlignedBox3d& room) {
  const int wall = rng.integer(0, 3);
  const double width = rng.uniform(kMinSize, kMaxSize);
  const double height = rng.uniform(kMinSize, kMaxSize);
  const double thickness = rng.uniform(0.03, 0.10);
  const double z_lo = room.min().z() + 0.8;
  const double z_hi = std::max(z_lo, std::min(room.min().z() + 2.5, room.max().z() - height));
  const double z0 = rng.uniform(z_lo, z_hi);
  SceneBox b = against_wall(room, wall, along_wall(rng, room, wall, width), width, thickness, z0, height);
  b.kind = BoxKind::kWallPanel;
  return b;
}

double draw_yaw(SequenceRng& rng, double rotated_fraction) {
  const double u = rng.uniform();
  const double yaw = rng.uniform(-0.25 * kPi, 0.25 * kPi);
  return u < rotated_fraction ? yaw : 0.0;
}

/// A box standing on the floor anywhere in the room.
SceneBox propose_floor(SequenceRng& rng, const Eigen::AlignedBox3d& room, double rotated_fraction) {
  SceneBox b;
  b.kind = BoxKind::kFloor;
  b.half = Vec3d(rng.uniform(kMinSize, kMaxSize), rng.uniform(kMinSize, kMaxSize),
                 rng.uniform(kMinSize, kMaxSize)) *
           0.5;
  b.yaw = draw_yaw(rng, rotated_fraction);
  const double c = std::abs(std::cos(b.yaw));
  const double s = std::abs(std::sin(b.yaw));
  const double rx = c * b.half.x() + s * b.half.y();
  const double ry = s * b.half.x() + c * b.half.y();
  b.centre = Vec3d(rng.uniform(room.min().x() + rx, room.max().x() - rx),
                   rng.uniform(room.min().y() + ry, room.max().y() - ry), room.min().z() + b.half.z());
  return b;
}

/// A smaller box on top of `base`.
SceneBox propose_stacked(SequenceRng& rng, const SceneBox& base, double rotated_fraction) {
  SceneBox b;
  b.kind = BoxKind::kStacked;
  b.half = Vec3d(rng.uniform(kMinSize, 0.8), rng.uniform(kMinSize, 0.8), rng.uniform(kMinSize, 0.8)) * 0.5;
  b.yaw = base.yaw + draw_yaw(rng, rotated_fraction);
  const double top = base.centre.z() + base.half.z();
  b.centre = Vec3d(base.centre.x() + rng.uniform(-0.15, 0.15), base.centre.y() + rng.uniform(-0.15, 0.15),
                   top + b.half.z());
  return b;
}

bool inside_room(const SceneBox& box, const Eigen::AlignedBox3d& room) {
  const Eigen::AlignedBox3d a = box_aabb(box);
  return (a.min() - room.min()).minCoeff() >= -kInsideTolerance &&
         (room.max() - a.max()).minCoeff() >= -kInsideTolerance;
}

/// The room: default bounds grown to hold keep_clear + room_margin_m (x, y, ceiling); the
/// floor only moves down when a keep-clear point is closer than clearance_m to z = 0.
Eigen::AlignedBox3d grow_room(const SceneOptions& o, const std::vector<Vec3d>& keep_clear) {
  Eigen::AlignedBox3d room = default_room();
  if (keep_clear.empty()) return round_to_float(room);
  Eigen::AlignedBox3d kc;
  for (const Vec3d& p : keep_clear) kc.extend(p);
  const Vec3d margin(o.room_margin_m, o.room_margin_m, o.room_margin_m);
  room.extend(kc.min() - margin);
  room.extend(kc.max() + margin);
  room.min().z() = std::min(default_room().min().z(), kc.min().z() - o.clearance_m);
  return round_to_float(room);
}

/// One candidate box of clutter index k (the first two are wall slabs).
SceneBox propose(SequenceRng& rng, int k, const Eigen::AlignedBox3d& room,
                 const std::vector<SceneBox>& placed, double rotated_fraction) {
  if (k < 2) return propose_slab(rng, room);
  std::vector<int> floor_boxes;
  for (std::size_t i = 0; i < placed.size(); ++i) {
    if (placed[i].kind == BoxKind::kFloor) floor_boxes.push_back(static_cast<int>(i));
  }
  const double u = rng.uniform();
  if (u < 0.15 && !floor_boxes.empty()) {
    const int base = floor_boxes[rng.integer(0, static_cast<int>(floor_boxes.size()) - 1)];
    return propose_stacked(rng, placed[base], rotated_fraction);
  }
  if (u < 0.30) return propose_panel(rng, room);
  return propose_floor(rng, room, rotated_fraction);
}

}  // namespace

bool keeps_clear(const SceneBox& box, const std::vector<Vec3d>& keep_clear, double clearance) {
  const double reach = clearance + box.half.norm();
  for (const Vec3d& p : keep_clear) {
    if ((p - box.centre).squaredNorm() >= reach * reach) continue;
    if (box_point_distance(box, p) < clearance) return false;
  }
  return true;
}

bool overlap_ok(const SceneBox& box, const std::vector<SceneBox>& placed) {
  for (const SceneBox& other : placed) {
    const double limit = kMaxOverlapShare * std::min(box_volume(box), box_volume(other));
    if (box_overlap_volume(box, other) > limit) return false;
  }
  return true;
}

StatusOr<IndoorLayout> layout_indoor(const SceneOptions& o, const std::vector<Vec3d>& keep_clear,
                                     std::uint64_t seed) {
  IndoorLayout layout;
  layout.room = grow_room(o, keep_clear);
  SequenceRng rng(seed, Stream::kScene);
  for (int k = 0; k < o.num_boxes; ++k) {
    bool placed = false;
    for (int attempt = 0; attempt < kMaxPlacementAttempts && !placed; ++attempt) {
      SceneBox box = propose(rng, k, layout.room, layout.boxes, o.rotated_fraction);
      finalize_box(box);
      if (inside_room(box, layout.room) && keeps_clear(box, keep_clear, o.clearance_m) &&
          overlap_ok(box, layout.boxes)) {
        layout.boxes.push_back(box);
        placed = true;
      }
    }
    if (!placed) {
      return absl::ResourceExhaustedError(fmt::format(
          "could not place box {} of {} in the room after {} attempts: the {} keep-clear points with "
          "clearance {} m leave too little free space; lower num_boxes or clearance_m, or raise "
          "room_margin_m",
          k + 1, o.num_boxes, kMaxPlacementAttempts, keep_clear.size(), o.clearance_m));
    }
  }
  std::vector<int> candidates(layout.boxes.size());
  std::iota(candidates.begin(), candidates.end(), 0);
  MRVS_RETURN_IF_ERROR(assign_object_flags(o, candidates, layout.boxes, seed));
  return layout;
}

Status assign_object_flags(const SceneOptions& o, const std::vector<int>& candidates,
                           std::vector<SceneBox>& boxes, std::uint64_t seed) {
  const int n = static_cast<int>(candidates.size());
  if (o.unmapped_objects + o.removed_objects > n) {
    return absl::InvalidArgumentError(fmt::format(
        "unmapped_objects ({}) + removed_objects ({}) exceed the {} objects of the scene; lower them",
        o.unmapped_objects, o.removed_objects, n));
  }
  // Fisher-Yates shuffle keyed by (seed, kScene, 0xF1A6 << 48 | i): independent of the layout draws.
  std::vector<int> order = candidates;
  const CounterRng rng(seed, Stream::kScene);
  for (int i = n - 1; i > 0; --i) {
    const std::uint64_t draw = rng.bits((std::uint64_t{0xF1A6} << 48) | static_cast<std::uint64_t>(i));
    const auto j = static_cast<int>(draw % static_cast<std::uint64_t>(i + 1));
    std::swap(order[i], order[j]);
  }
  for (int i = 0; i < o.unmapped_objects; ++i) boxes[order[i]].in_map = false;
  for (int i = 0; i < o.removed_objects; ++i) boxes[order[o.unmapped_objects + i]].rendered = false;
  return absl::OkStatus();
}

}  // namespace mrvs::sim::detail
