#pragma once
// The multi-resolution voxelized prior map (paper section III-A; algorithm.md 1.3):
// one representative point per occupied voxel per level, the finest level chosen by
// photometric saliency among the raw points, every coarser level chosen among the finest
// representatives, so every coarse point is also a fine point.
//
// Coordinates: positions are float32 relative to `origin` (double, map frame), so a map
// with UTM-sized coordinates keeps sub-millimetre precision within +-8 km of the origin.
// Voxel (i, j, k) of level r holds the points with floor((p - origin) / r) == (i, j, k),
// p - origin computed in double (mrvs::voxel::index_of on the local position). For a
// stored point, p - origin is its float32 position converted to double (voxel_of below):
// the builder assigns voxels from the rounded float positions it stores, so a loaded map
// indexes exactly like the builder did.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/geometry/types.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map {

/// One representative point p* = [x, I, S] (paper notation).
struct MapPoint {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< metres, relative to VoxelMap::origin
  float intensity = 0.0f;                              ///< as in the raw cloud
  float saliency = 0.0f;                               ///< S_photo (intensity units per metre)
};

/// One resolution level: at most one point per voxel of size `resolution`.
struct MapLevel {
  double resolution = 0.0;  ///< voxel edge, metres
  std::vector<MapPoint> points;
};

struct VoxelMap {
  Vec3d origin = Vec3d::Zero();       ///< map-frame position of the local origin, metres
  std::vector<MapLevel> levels;       ///< finest first, strictly increasing resolution
  std::uint64_t raw_point_count = 0;  ///< points of the raw cloud it was built from
  std::string description;            ///< free text (source file, options), stored in the file

  /// Index of the level whose resolution equals `resolution` within a relative 1e-4, else -1.
  int level_of(double resolution) const;
  /// Resolutions of all levels, finest first.
  std::vector<double> resolutions() const;
  /// Total number of points over all levels.
  std::uint64_t point_count() const;
};

/// Voxel of a stored, map-local position at `resolution` (metres): floor(double(p) / r) per
/// axis. nullopt when p is not finite or the index cannot be packed (mrvs::voxel::pack).
std::optional<voxel::VoxelIndex> voxel_of(const Eigen::Vector3f& local_position, double resolution);

}  // namespace mrvs::map
