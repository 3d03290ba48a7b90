#pragma once
// Scene layouts: where the room, the boxes, the road and the buildings go (internal to
// mrvs::sim_scene). Both layouts draw from SequenceRng(seed, Stream::kScene).
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "box_geometry.h"
#include "mrvs/core/status.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim::detail {

/// Default V1 room (simulator.md 3.1, floor clamped to 0).
inline Eigen::AlignedBox3d default_room() {
  return Eigen::AlignedBox3d(Vec3d(-4.73, -3.49, 0.0), Vec3d(4.10, 5.16, 4.13));
}

/// Most attempts spent on one box before make_scene gives up.
constexpr int kMaxPlacementAttempts = 4000;
/// Largest overlap allowed between two boxes, as a share of the smaller volume.
constexpr double kMaxOverlapShare = 0.10;

struct IndoorLayout {
  Eigen::AlignedBox3d room;
  std::vector<SceneBox> boxes;
};

/// Room grown around `keep_clear` and options.num_boxes boxes placed by rejection sampling.
StatusOr<IndoorLayout> layout_indoor(const SceneOptions& options, const std::vector<Vec3d>& keep_clear,
                                     std::uint64_t seed);

/// Marks options.unmapped_objects boxes in_map = false and options.removed_objects other
/// boxes rendered = false, chosen at random among the boxes whose index is in `candidates`.
Status assign_object_flags(const SceneOptions& options, const std::vector<int>& candidates,
                           std::vector<SceneBox>& boxes, std::uint64_t seed);

/// True when `box` keeps `clearance` metres from every keep-clear point.
bool keeps_clear(const SceneBox& box, const std::vector<Vec3d>& keep_clear, double clearance);

/// True when `box` overlaps no box of `placed` by more than kMaxOverlapShare of the smaller
/// volume.
bool overlap_ok(const SceneBox& box, const std::vector<SceneBox>& placed);

}  // namespace mrvs::sim::detail
