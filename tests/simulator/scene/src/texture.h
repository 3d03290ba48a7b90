#pragma once
// Baked 8-bit albedo textures with box-filtered mip chains, and the procedural recipes that
// fill them (internal to mrvs::sim_scene).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mrvs/sim/scene.h"

namespace mrvs::sim::detail {

/// Albedo limits of every texture (simulator.md 3.2): DN never saturates.
constexpr float kAlbedoMin = 0.03f;
constexpr float kAlbedoMax = 0.97f;

/// Byte for albedo a (clamped to [kAlbedoMin, kAlbedoMax], then rounded).
std::uint8_t quantize_albedo(float a);

/// An 8-bit albedo grid over [0, size_u] x [0, size_v] metres with texel centres at
/// ((i + 0.5) * texel, (j + 0.5) * texel), plus box-filtered mip levels down to 1 x 1
/// (level k has ceil(w / 2^k) texels; its texel (i, j) is the rounded mean of texels
/// 2i..2i+1, 2j..2j+1 of level k-1, the last one repeated at odd edges).
class MipTexture {
 public:
  MipTexture() = default;
  /// Takes level 0 (row-major, width * height bytes) and builds the mip chain (single
  /// threaded: callers build several textures in parallel). Lookups clamp (u, v) to [0, size_u] x [0, size_v]
  /// metres, or, with `wrap`, tile the plane (width and height must then be powers of two).
  MipTexture(int width, int height, float texel, std::vector<std::uint8_t> level0, float size_u, float size_v,
             bool wrap = false);

  /// Trilinear albedo: bilinear within levels floor(lod) and floor(lod) + 1, blended.
  float sample(float u, float v, float lod) const;
  /// Bilinear albedo within one level.
  float sample_level(int level, float u, float v) const;

  int levels() const { return static_cast<int>(width_.size()); }
  int width(int level) const { return width_[level]; }
  int height(int level) const { return height_[level]; }
  const std::uint8_t* level_data(int level) const { return data_.data() + offset_[level]; }
  float texel() const { return texel_; }
  std::size_t bytes() const { return data_.size(); }

 private:
  float texel_ = 1.0f;
  float size_u_ = 0.0f;
  float size_v_ = 0.0f;
  bool wrap_ = false;
  std::vector<float> inv_texel_;  ///< 1 / texel size of each level
  std::vector<int> width_;
  std::vector<int> height_;
  std::vector<std::size_t> offset_;
  std::vector<std::uint8_t> data_;
};

/// Recipe of the indoor textures (simulator.md 3.2).
struct IndoorTextureRecipe {
  int octaves = 5;
  double base_wavelength_m = 0.40;
  double lacunarity = 2.2;
  double gain = 0.5;
  double contrast = 2.2;  ///< albedo = 0.5 + contrast * (noise - 0.5), noise in [0, 1]
  double posters_per_m2 = 3.0;
  double poster_min_m = 0.05;
  double poster_max_m = 0.55;
  double blobs_per_m2 = 4.0;
  double blob_min_radius_m = 0.02;
  double blob_max_radius_m = 0.17;
  double shading_wavelength_m = 2.0;  ///< textureless faces: +-1 % shading at this wavelength
};

/// Bakes the albedo of every face at `texel` metres per texel (result k for faces[k]); every
/// random value comes from CounterRng(seed, Stream::kTexture) keyed by the face id. Blocks of
/// rows of all faces run in parallel (OpenMP); the result does not depend on the thread count.
std::vector<MipTexture> bake_indoor_faces(const std::vector<Face>& faces, std::uint64_t seed, float texel,
                                          const IndoorTextureRecipe& recipe = {});
/// The same for one face.
MipTexture bake_indoor_face(const Face& face, std::uint64_t seed, float texel,
                            const IndoorTextureRecipe& recipe = {});

/// A square, seamlessly tiling fractal value-noise texture (size texels of `texel` metres,
/// size a power of two), values in [0, 1] mapped to bytes without clamping to albedo limits
/// beyond kAlbedoMin/kAlbedoMax. `salt` selects an independent texture for the same seed.
MipTexture bake_noise_tile(std::uint64_t seed, std::uint64_t salt, int size, float texel);

}  // namespace mrvs::sim::detail
