#include "mrvs/sim/surface_coverage.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <fmt/format.h>

#include "mrvs/voxel/voxel_key.h"

namespace mrvs::sim {
namespace {

constexpr double kTileM = 0.25;  ///< faces are walked in tiles of about this size

/// Camera positions within `reach` of `centre`.
std::vector<Vec3d> near(const std::vector<Vec3d>& path, const Vec3d& centre, double reach) {
  std::vector<Vec3d> out;
  for (const Vec3d& p : path) {
    if ((p - centre).squaredNorm() <= reach * reach) out.push_back(p);
  }
  return out;
}

/// Distance from p to the nearest of `candidates` that sees it within `within_m`; < 0 if none.
double seen_distance(const Scene& scene, const Face& f, const Vec3d& p, const std::vector<Vec3d>& candidates,
                     double within_m) {
  double best = -1.0;
  for (const Vec3d& c : candidates) {
    const double d = (c - p).norm();
    if (d > within_m || (c - p).dot(f.normal) <= 0.0 || (best >= 0.0 && d >= best)) continue;
    const Vec3d target = p + 1e-3 * f.normal;
    if (!scene.occluded(c.cast<float>(), target.cast<float>(), Visibility::kCamera)) best = d;
  }
  return best;
}

/// The surface voxels of one tile [u0, u1) x [v0, v1) of face f (key -> nearest distance).
void tile_voxels(const Scene& scene, const Face& f, double u0, double u1, double v0, double v1,
                 const std::vector<Vec3d>& path, const SE3d& T_map_world, const Vec3d& origin,
                 double resolution, double within_m, std::unordered_map<std::uint64_t, float>* out) {
  const Vec3d au = f.axis_u.normalized(), av = f.axis_v.normalized();
  const Vec3d centre = f.origin + 0.5 * (u0 + u1) * au + 0.5 * (v0 + v1) * av;
  const std::vector<Vec3d> candidates = near(path, centre, within_m + std::hypot(u1 - u0, v1 - v0));
  if (candidates.empty()) return;
  const double step = 0.25 * resolution;
  for (double v = v0 + 0.5 * step; v < v1; v += step) {
    for (double u = u0 + 0.5 * step; u < u1; u += step) {
      const Vec3d p = f.origin + u * au + v * av;
      const double d = seen_distance(scene, f, p, candidates, within_m);
      if (d < 0.0) continue;
      const Vec3d local = T_map_world * p - origin;
      const std::optional<voxel::VoxelIndex> index = voxel::index_of(local, resolution);
      if (!index || !voxel::packable(*index)) continue;
      const std::uint64_t key = voxel::pack(*index);
      auto [it, inserted] = out->emplace(key, static_cast<float>(d));
      if (!inserted) it->second = std::min(it->second, static_cast<float>(d));
    }
  }
}

}  // namespace

StatusOr<std::vector<SurfaceVoxel>> true_surface_voxels(const Scene& scene,
                                                        const std::vector<Vec3d>& camera_positions_w,
                                                        const SE3d& T_map_world, const Vec3d& origin_map,
                                                        double resolution, double within_m) {
  if (camera_positions_w.empty() || !(resolution > 0.0) || !(within_m > 0.0)) {
    return absl::InvalidArgumentError(fmt::format(
        "true_surface_voxels: needs camera positions ({}), resolution > 0 ({}) and within_m > 0 ({})",
        camera_positions_w.size(), resolution, within_m));
  }
  const std::vector<Face>& faces = scene.faces();
  std::vector<std::unordered_map<std::uint64_t, float>> per_face(faces.size());
  const auto n = static_cast<std::int64_t>(faces.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (std::int64_t i = 0; i < n; ++i) {
    const Face& f = faces[static_cast<std::size_t>(i)];
    if (!f.rendered || !f.in_map) continue;
    const int nu = std::max(1, static_cast<int>(std::ceil(f.size_u / kTileM)));
    const int nv = std::max(1, static_cast<int>(std::ceil(f.size_v / kTileM)));
    for (int tv = 0; tv < nv; ++tv) {
      for (int tu = 0; tu < nu; ++tu) {
        tile_voxels(scene, f, f.size_u * tu / nu, f.size_u * (tu + 1) / nu, f.size_v * tv / nv,
                    f.size_v * (tv + 1) / nv, camera_positions_w, T_map_world, origin_map, resolution,
                    within_m, &per_face[static_cast<std::size_t>(i)]);
      }
    }
  }
  std::unordered_map<std::uint64_t, float> all;
  for (const auto& m : per_face) {
    for (const auto& [key, d] : m) {
      auto [it, inserted] = all.emplace(key, d);
      if (!inserted) it->second = std::min(it->second, d);
    }
  }
  std::vector<SurfaceVoxel> out;
  out.reserve(all.size());
  for (const auto& [key, d] : all) out.push_back({key, d});
  std::sort(out.begin(), out.end(),
            [](const SurfaceVoxel& a, const SurfaceVoxel& b) { return a.key < b.key; });
  return out;
}

}  // namespace mrvs::sim
