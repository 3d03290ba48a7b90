#pragma once
// The map's surfaces as the edge has seen them: every point the cloud answered, kept in a
// voxel hash, and the local plane around a point fitted to them. A hit is a point of the
// prior map itself (a voxel's representative LiDAR point), not an estimate, so the planes
// carry no drift wherever the rays that found them came from. Stage 1's kPlane mode uses
// the normal: a ray from a pose off by e along a surface meets the surface e further along
// it, so only the hit's offset along the normal says something about the pose.
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include "mrvs/geometry/types.h"

namespace mrvs::edge {

/// The plane fitted to the surface points around a point.
struct SurfacePlane {
  Vec3d normal = Vec3d::UnitZ();  ///< unit
  Vec3d centroid = Vec3d::Zero();
  double rms_m = 0.0;  ///< of the points' distances to the plane
  int points = 0;
};

struct SurfaceFitOptions {
  double radius_m = 0.5;    ///< points within this distance of the query take part
  int min_points = 6;       ///< fewer: no plane
  double max_rms_m = 0.05;  ///< rougher: no plane (an edge, a corner, clutter)
  /// The points' standard deviation along their second principal axis at least this * radius
  /// (a full disc: 0.5); less: a line, no plane.
  double min_extent = 0.15;
};

class SurfaceMap {
 public:
  /// Cells of `cell_m` holding at most `per_cell` distinct points (the first ones).
  SurfaceMap(double cell_m, int per_cell) : cell_m_(cell_m), per_cell_(per_cell) {}

  /// Adds a map point; a repeat of one already held (the same voxel's answer) is ignored.
  /// False when nothing was added (repeat, full cell, non-finite point).
  bool add(const Vec3d& p);
  /// The plane of the points around p; nullopt when they are too few, too rough or on a line.
  std::optional<SurfacePlane> plane_at(const Vec3d& p, const SurfaceFitOptions& options) const;
  std::size_t size() const { return size_; }

 private:
  double cell_m_;
  int per_cell_;
  std::size_t size_ = 0;
  std::unordered_map<std::uint64_t, std::vector<Vec3d>> cells_;
};

}  // namespace mrvs::edge
