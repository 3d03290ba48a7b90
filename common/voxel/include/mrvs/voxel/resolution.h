#pragma once
// Resolution selection, shared by the edge (which picks the level a ray asks for) and the
// cloud (which checks it): r* = argmin over r in R of |r - d / f| (paper eq. voxel_res), with
// d the feature depth (m) and f the focal length (px), so d / f is the metric footprint of
// one pixel at that depth. Ties go to the earlier level in `resolutions` (strict comparison,
// as the reference code). Example (f = 458): 0.01 m below 6.87 m, 0.02 m to 11.45 m, 0.03 m
// beyond.
#include <cmath>
#include <cstddef>
#include <optional>
#include <vector>

namespace mrvs::voxel {

/// Index into `resolutions` of r*; nullopt when the list is empty, or depth or focal is not
/// finite and positive.
inline std::optional<std::size_t> select_level(const std::vector<double>& resolutions, double depth_m,
                                               double focal_px) {
  if (resolutions.empty() || !(depth_m > 0) || !(focal_px > 0) || !std::isfinite(depth_m) ||
      !std::isfinite(focal_px)) {
    return std::nullopt;
  }
  const double footprint = depth_m / focal_px;
  std::size_t best = 0;
  for (std::size_t i = 1; i < resolutions.size(); ++i) {
    if (std::abs(resolutions[i] - footprint) < std::abs(resolutions[best] - footprint)) best = i;
  }
  return best;
}

/// Index of the level whose resolution equals `resolution` within a relative tolerance of
/// 1e-4 (float32 on the wire), or nullopt. The one rule by which the cloud matches a ray's
/// requested resolution to a map level.
inline std::optional<std::size_t> find_level(const std::vector<double>& resolutions, double resolution) {
  if (!(resolution > 0) || !std::isfinite(resolution)) return std::nullopt;
  for (std::size_t i = 0; i < resolutions.size(); ++i) {
    if (std::abs(resolutions[i] - resolution) <= 1e-4 * resolutions[i]) return i;
  }
  return std::nullopt;
}

/// Depth (m) at which select_level switches from level a to level b (a, b adjacent in
/// `resolutions`): the footprint is then the midpoint, d = f (r_a + r_b) / 2.
inline double switch_depth(double r_a, double r_b, double focal_px) { return focal_px * 0.5 * (r_a + r_b); }

}  // namespace mrvs::voxel
