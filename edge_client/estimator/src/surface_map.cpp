#include "mrvs/edge/surface_map.h"

#include <algorithm>
#include <cmath>

#include "mrvs/geometry/plane_fit.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::edge {

bool SurfaceMap::add(const Vec3d& p) {
  const auto index = voxel::index_of<double>(p, cell_m_);
  if (!index) return false;
  std::vector<Vec3d>& cell = cells_[voxel::pack(*index)];
  if (static_cast<int>(cell.size()) >= per_cell_) return false;
  // The cloud sends float32 map-local coordinates: a repeat comes back bit-identical, and two
  // distinct map points are never within a micrometre.
  for (const Vec3d& q : cell) {
    if ((q - p).squaredNorm() < 1e-12) return false;
  }
  cell.push_back(p);
  ++size_;
  return true;
}

std::optional<SurfacePlane> SurfaceMap::plane_at(const Vec3d& p, const SurfaceFitOptions& o) const {
  const auto lo = voxel::index_of<double>(p - Vec3d::Constant(o.radius_m), cell_m_);
  const auto hi = voxel::index_of<double>(p + Vec3d::Constant(o.radius_m), cell_m_);
  if (!lo || !hi) return std::nullopt;
  std::vector<Vec3d> near;
  const double r2 = o.radius_m * o.radius_m;
  for (int x = lo->x(); x <= hi->x(); ++x) {
    for (int y = lo->y(); y <= hi->y(); ++y) {
      for (int z = lo->z(); z <= hi->z(); ++z) {
        const voxel::VoxelIndex index(x, y, z);
        if (!voxel::packable(index)) continue;
        const auto it = cells_.find(voxel::pack(index));
        if (it == cells_.end()) continue;
        for (const Vec3d& q : it->second) {
          if ((q - p).squaredNorm() <= r2) near.push_back(q);
        }
      }
    }
  }
  if (static_cast<int>(near.size()) < std::max(o.min_points, 3)) return std::nullopt;
  const std::optional<PlaneFit> fit = fit_plane(near);
  if (!fit || fit->rms_m > o.max_rms_m || fit->extent_m < o.min_extent * o.radius_m) return std::nullopt;
  SurfacePlane out;
  out.normal = fit->normal;
  out.centroid = fit->centroid;
  out.rms_m = fit->rms_m;
  out.points = fit->points;
  return out;
}

}  // namespace mrvs::edge
