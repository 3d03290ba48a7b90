#pragma once
// Sub-voxel refinement of a ray hit (algorithm.md 2.6; not in the paper; internal to
// mrvs::map_query): a PCA plane and a Kasa circle fitted to the stored points of the hit
// voxel's 3 x 3 x 3 neighbourhood, and the query ray's intersection with that disk.
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "level_index.h"

namespace mrvs::map::detail {

/// Most points a 3 x 3 x 3 neighbourhood can hold.
inline constexpr int kMaxNeighbours = 27;

/// Fixed-capacity point list (no allocation per ray).
struct Neighbourhood {
  Eigen::Vector3d points[kMaxNeighbours];
  int count = 0;
};

/// Stored points of the 3 x 3 x 3 voxels around `voxel` (centre included), map-local m.
void gather_neighbourhood(const LevelIndex& index, const Eigen::Vector3i& voxel, Neighbourhood* out);

/// Where the ray o + t v (v unit, m) meets the plane fitted to `n`, when: >= 4 points, the
/// fit is planar ((s2 - s3) / s1 >= min_planarity, s1 >= 1e-8, s_k = sqrt |lambda_k| of the
/// covariance), the in-plane Kasa circle has a radius in (0, 10] m, the ray is not parallel
/// to the plane (|n.v| >= 1e-6), the intersection is in front (t >= 0) and inside the circle.
/// nullopt otherwise (or on any NaN).
std::optional<Eigen::Vector3d> plane_circle_intersection(const Neighbourhood& n, const Eigen::Vector3d& o,
                                                         const Eigen::Vector3d& v, double min_planarity);

/// Stored points of `index` within `radius_m` of `centre` (map-local, m), appended to `out`.
void gather_ball(const LevelIndex& index, const Eigen::Vector3d& centre, double radius_m,
                 std::vector<Eigen::Vector3d>* out);

}  // namespace mrvs::map::detail
