#pragma once
// Ray queries against a VoxelMap (algorithm.md 2.4-2.6 and decision 3): 3D-DDA
// (Amanatides-Woo) over the level a ray asks for, from d - R to d + R, returning the first
// occupied voxel's point; the in-view acceptance as a perpendicular-distance test on the
// ray; the retry ranges; the optional plane refinement. Read-only and thread-safe without
// locks; no allocation per ray.
//
// All positions are map-local (relative to VoxelMap::origin), as on the wire.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/map/voxel_map.h"
#include "mrvs/voxel/ray_query.h"

namespace mrvs::map {

/// One ray query (the 32-byte wire message, map-local); shared with the edge.
using RayQuery = voxel::RayQuery;

enum class QueryStatus : std::uint8_t {
  kHit,                ///< point accepted
  kMiss,               ///< no occupied voxel in any search range
  kRejected,           ///< occupied voxels found, none passed the in-view test
  kInvalidRay,         ///< non-finite value, zero direction or negative distance
  kUnknownResolution,  ///< resolution matches no level
};

struct QueryResult {
  QueryStatus status = QueryStatus::kMiss;
  /// Map-local, m: the accepted point (kHit) or the last rejected one (kRejected).
  Eigen::Vector3f point = Eigen::Vector3f::Zero();
  std::int8_t level = -1;   ///< level traversed
  std::uint8_t passes = 0;  ///< DDA passes made (1 or 2)
  bool refined = false;     ///< point is a ray-plane intersection
};

/// The surface normal's neighbourhood reaches at most this many voxels from the hit.
inline constexpr double kNormalHalfWidthVoxels = 6.0;

struct QueryOptions : config::OptionsEquality<QueryOptions> {
  double search_range_m = 0.75;            ///< R0: DDA from d - R to d + R (indoor 0.75, outdoor 1.5)
  double threshold_offset_px = 0.5;        ///< in-view: perpendicular distance <= r + offset * d / f
  double focal_length_px = 458.0;          ///< f used by the in-view test (the edge cameras' focal)
  bool refine_plane_intersection = false;  ///< return the ray-plane intersection (algorithm.md 2.6)
  double min_planarity = 0.10;             ///< plane fit acceptance, (s2 - s3) / s1
  int max_rays_per_batch = 256;            ///< requests with more rays are refused
  /// Surface normals (asked per request): the plane of the level's points within this
  /// radius of the hit (at most kNormalHalfWidthVoxels voxels of the level), when at least
  /// normal_min_points, at most normal_max_rms_m rough and spread over normal_min_extent *
  /// radius along their second axis (not a line).
  double normal_radius_m = 1.0;
  int normal_min_points = 6;
  double normal_max_rms_m = 0.1;
  double normal_min_extent = 0.15;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("search_range_m", search_range_m, in_range(0.01, 100.0), "DDA range around d, m (R0)");
    v("threshold_offset_px", threshold_offset_px, in_range(0.0, 100.0), "in-view offset, px");
    v("focal_length_px", focal_length_px, in_range(1.0, 100000.0), "focal length for the in-view test, px");
    v("refine_plane_intersection", refine_plane_intersection, any(), "return ray-plane intersections");
    v("min_planarity", min_planarity, in_range(0.0, 1.0), "plane fit acceptance");
    v("max_rays_per_batch", max_rays_per_batch, in_range(1, 65536), "rays per request");
    v("normal_radius_m", normal_radius_m, in_range(0.01, 10.0), "surface normal: fit radius, m");
    v("normal_min_points", normal_min_points, in_range(3, 100000), "surface normal: points a plane needs");
    v("normal_max_rms_m", normal_max_rms_m, in_range(0.0, 10.0), "surface normal: roughest plane, m");
    v("normal_min_extent", normal_min_extent, in_range(0.0, 1.0), "surface normal: spread per radius");
  }
};

/// The first occupied voxel along a ray segment (for tests and diagnostics).
struct VoxelHit {
  std::uint32_t point_index = 0;  ///< into VoxelMap::levels[level].points
  float t_entry = 0.0f;           ///< ray parameter where the voxel is entered, m (unit direction)
};

/// Work counters accumulated by the counting query() overload (benchmarks, diagnostics).
struct QueryCounters {
  std::uint64_t rays = 0;             ///< queries
  std::uint64_t passes = 0;           ///< DDA passes
  std::uint64_t bricks = 0;           ///< 8x8x8-voxel bricks visited (empty ones are crossed in one step)
  std::uint64_t occupied_bricks = 0;  ///< of those, bricks holding points (walked voxel by voxel)
  std::uint64_t voxels = 0;           ///< voxels tested inside occupied bricks
  std::uint64_t refined = 0;          ///< hits replaced by a ray-plane intersection

  QueryCounters& operator+=(const QueryCounters& o);
};

class QueryEngine {
 public:
  /// Builds the per-level indices. `map` is shared (read-only) with the engine.
  static StatusOr<QueryEngine> create(std::shared_ptr<const VoxelMap> map, const QueryOptions& options);

  /// One query with retries and acceptance. Thread-safe, allocation-free.
  QueryResult query(const RayQuery& ray) const;
  /// The same query, adding the work done to `*counters` (slightly slower).
  QueryResult query(const RayQuery& ray, QueryCounters* counters) const;

  /// First occupied voxel of `level` along origin + t * unit(direction), t in [t_start, t_end]
  /// (a voxel counts when entered at t <= t_end; the voxel holding the start point counts with
  /// t_entry = t_start). nullopt for no hit, an unknown level, non-finite input, a zero
  /// direction or t_start > t_end.
  std::optional<VoxelHit> first_hit(int level, const Eigen::Vector3f& origin,
                                    const Eigen::Vector3f& direction, float t_start, float t_end) const;

  /// The unit normal of the map's surface at `point` (map-local, m; a hit of `level`): the
  /// plane of that level's points within options().normal_radius_m (see QueryOptions);
  /// nullopt when they are not a plane, or for an unknown level. Thread-safe; allocates.
  std::optional<Eigen::Vector3f> surface_normal(int level, const Eigen::Vector3f& point) const;

  const VoxelMap& map() const;
  const QueryOptions& options() const;

  /// Bytes held by the per-level indices (not counting the shared VoxelMap).
  std::size_t index_memory_bytes() const;

 private:
  struct Impl;
  std::shared_ptr<const Impl> impl_;
};

}  // namespace mrvs::map
