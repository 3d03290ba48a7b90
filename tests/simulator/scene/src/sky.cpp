// Sky radiance for rays that hit nothing (simulator.md 3.3): vertical gradient from DN 200
// at the horizon to DN 240 at the zenith plus faint low-frequency clouds.
#include <algorithm>
#include <cmath>

#include "mrvs/sim/rng.h"
#include "scene_impl.h"

namespace mrvs::sim::detail {
namespace {

constexpr float kHorizon = 200.0f / 255.0f;
constexpr float kZenith = 240.0f / 255.0f;
constexpr float kCloudAmplitude = 0.03f;
constexpr float kCloudScale = 3.0f;  ///< lattice cells per unit of (dx, dy) / dz

float cloud_noise(const std::vector<float>& lattice, float x, float y) {
  const float fx = std::floor(x);
  const float fy = std::floor(y);
  const int i0 = static_cast<int>(static_cast<long long>(fx) & (kSkyLattice - 1));
  const int j0 = static_cast<int>(static_cast<long long>(fy) & (kSkyLattice - 1));
  const int i1 = (i0 + 1) & (kSkyLattice - 1);
  const int j1 = (j0 + 1) & (kSkyLattice - 1);
  float tx = x - fx;
  float ty = y - fy;
  tx = tx * tx * (3.0f - 2.0f * tx);
  ty = ty * ty * (3.0f - 2.0f * ty);
  const float a =
      lattice[j0 * kSkyLattice + i0] + tx * (lattice[j0 * kSkyLattice + i1] - lattice[j0 * kSkyLattice + i0]);
  const float b =
      lattice[j1 * kSkyLattice + i0] + tx * (lattice[j1 * kSkyLattice + i1] - lattice[j1 * kSkyLattice + i0]);
  return a + ty * (b - a);
}

}  // namespace

void make_sky(Scene::Impl& impl) {
  const CounterRng rng(impl.seed, Stream::kTexture);
  impl.sky_lattice.resize(kSkyLattice * kSkyLattice);
  for (std::size_t i = 0; i < impl.sky_lattice.size(); ++i) {
    impl.sky_lattice[i] = static_cast<float>(rng.uniform(~std::uint64_t{1}, 0x5C1, i));
  }
}

float sky_radiance(const Scene::Impl& impl, const Vec3f& direction) {
  const float n = direction.norm();
  if (!(n > 0.0f) || impl.sky_lattice.empty()) return kHorizon;
  const float up = std::clamp(direction.z() / n, 0.0f, 1.0f);
  float value = kHorizon + (kZenith - kHorizon) * up;
  if (up > 0.02f) {
    // Clouds on a plane above the camera, fading towards the horizon.
    const float x = kCloudScale * direction.x() / (direction.z() + 0.1f * n);
    const float y = kCloudScale * direction.y() / (direction.z() + 0.1f * n);
    const float c = 0.65f * cloud_noise(impl.sky_lattice, x, y) +
                    0.35f * cloud_noise(impl.sky_lattice, 2.3f * x, 2.3f * y);
    value += kCloudAmplitude * std::min(1.0f, up * 5.0f) * (2.0f * c - 1.0f);
  }
  return std::clamp(value, 0.0f, 1.0f);
}

}  // namespace mrvs::sim::detail
