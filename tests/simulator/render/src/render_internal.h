#pragma once
// Helpers shared by the renderer's translation units (not installed).
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>

#include "mrvs/sim/stereo_renderer.h"

namespace mrvs::sim {

/// One camera at one pose: what the per-pixel loops need, as plain floats.
struct StereoRenderer::View {
  int cam = 0;
  const RayTable* table = nullptr;
  Eigen::Matrix3f R_w_c = Eigen::Matrix3f::Identity();
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();  ///< camera centre, world, m
  float max_distance = 0.0f;                         ///< m
  float min_cos = 0.2f;                              ///< floor of |n . d|
  bool mip = false;                                  ///< pixel-centre rays sample the mip pyramid
  std::vector<PersonBox> people;                     ///< the crowd at the view's time
  std::vector<Eigen::Vector4i> people_rects;         ///< pixels u0, v0, u1, v1 (inclusive) each may cover
};

namespace detail {

/// Mip level of a pixel-centre hit: log2(t * pixel_angle / max(|n.d|, min_cos) / texel),
/// clamped to >= 0. distance t in m, pixel_angle in rad, inv_texel in 1/m.
inline float mip_level(float distance, float pixel_angle, float cos_incidence, float min_cos,
                       float inv_texel) {
  const float footprint = distance * pixel_angle / std::max(std::abs(cos_incidence), min_cos) * inv_texel;
  return footprint > 1.0f ? std::log2(footprint) : 0.0f;
}

}  // namespace detail
}  // namespace mrvs::sim
