#pragma once
// Test maps and the brute-force reference for the ray query engine tests.
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "mrvs/map/query_engine.h"
#include "mrvs/map/voxel_map.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map::test {

/// Voxel -> point index of one level (the reference lookup, independent of the engine).
class ReferenceLevel {
 public:
  explicit ReferenceLevel(const MapLevel& level);
  /// Point index in voxel, or -1.
  std::int64_t find(const voxel::VoxelIndex& v) const;
  double resolution() const { return resolution_; }

 private:
  double resolution_;
  std::unordered_map<std::uint64_t, std::int64_t> voxels_;
};

/// A ray segment in double precision, as the engine sees a float ray.
struct Segment {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;  ///< unit
  double t_start = 0.0;
  double t_end = 0.0;
};

/// origin / direction converted to double, direction normalised (as QueryEngine does).
Segment make_segment(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_start,
                     float t_end);

/// Voxel of the point o + t v at resolution r (floor).
voxel::VoxelIndex voxel_at(const Segment& s, double t, double r);

/// Length of the part of [t_start, t_end] inside voxel `v` of resolution r; negative (minus
/// the gap) when the segment misses it. *entry receives the (unclipped) t where the line
/// enters the voxel.
double chord(const Segment& s, const voxel::VoxelIndex& v, double r, double* entry = nullptr);

/// First occupied voxel found by sampling t = t_start, t_start + step, ..., and t_end.
struct SampledHit {
  voxel::VoxelIndex voxel;
  std::int64_t point = -1;
  double t = 0.0;  ///< first sample inside it
};
std::optional<SampledHit> sample_first_hit(const ReferenceLevel& level, const Segment& s, double step);

/// A point inside voxel v (fractions in [0, 1) of the edge on each axis), as a float
/// position that maps back to v (checked by the caller through voxel_of).
Eigen::Vector3f point_in_voxel(const voxel::VoxelIndex& v, double r, const Eigen::Vector3d& fraction);

/// Random map: per level, `clusters` blobs of occupied voxels (random centres in `box_m`
/// around 0, so negative indices occur) plus `scatter` isolated voxels; one point per voxel
/// at a random position inside it.
VoxelMap random_map(const std::vector<double>& resolutions, double box_m, int clusters, int scatter,
                    std::uint64_t seed);

/// Map with one level and the given points (no validation).
std::shared_ptr<VoxelMap> single_level_map(double resolution, const std::vector<Eigen::Vector3f>& points);

/// QueryEngine::create that fails the test on error.
QueryEngine make_engine(std::shared_ptr<const VoxelMap> map, const QueryOptions& options = {});

}  // namespace mrvs::map::test
