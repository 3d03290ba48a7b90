#pragma once
// How much of the scene's true surface a prior map covers at a voxel resolution (issue 31:
// "the 0.01 m level is at least 90 % occupied on surfaces within 3 m of the camera path").
//
// The true surface voxels: every face that is both rendered (exists when the cameras fly)
// and in the map (existed at the survey), sampled on a grid of resolution / 4, keeping the
// samples within `within_m` of a camera position and seen from one of them (front side, no
// face in between); each sample's voxel in the map's grid: floor((T_map_world p - origin) / r).
#include <cstdint>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/geometry/types.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim {

struct SurfaceVoxel {
  std::uint64_t key = 0;    ///< mrvs::voxel::pack of the voxel index
  float distance_m = 0.0f;  ///< its nearest sample's distance to the nearest camera position, m
};

/// The true surface voxels of `scene` within `within_m` of `camera_positions_w` (world),
/// sorted by key, each once. InvalidArgument for an empty path, resolution <= 0 or within_m <= 0.
StatusOr<std::vector<SurfaceVoxel>> true_surface_voxels(const Scene& scene,
                                                        const std::vector<Vec3d>& camera_positions_w,
                                                        const SE3d& T_map_world, const Vec3d& origin_map,
                                                        double resolution, double within_m);

}  // namespace mrvs::sim
