#include "texture.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "mrvs/sim/rng.h"

namespace mrvs::sim::detail {
namespace {

// Keys of the kTexture stream: (face, tag + sub-index, index).
constexpr std::uint64_t kTagLattice = 100;  // + octave
constexpr std::uint64_t kTagOffsets = 150;  // + octave
constexpr std::uint64_t kTagPoster = 200;
constexpr std::uint64_t kTagBlob = 300;
constexpr std::uint64_t kTagCounts = 400;
constexpr std::uint64_t kTagFlat = 500;
constexpr std::uint64_t kTagTile = 1000;  // + salt * 64 + octave; face key = ~0

inline float smooth(float t) { return t * t * (3.0f - 2.0f * t); }

/// One octave of value noise: a lattice of uniform [0, 1) values, smoothstep-interpolated.
struct Octave {
  float freq = 1.0f;  ///< lattice cells per metre
  float off_u = 0.0f;
  float off_v = 0.0f;  ///< lattice offsets, cells
  float weight = 1.0f;
  int nu = 0;
  int nv = 0;
  std::vector<float> lattice;  ///< nv rows of nu values

  /// Fills `line` (nu values) with the lattice interpolated along v at `v` metres.
  void row(float v, std::vector<float>& line) const {
    const float y = std::max(0.0f, v * freq + off_v);  // >= 0: truncation is floor
    const int j0 = std::min(static_cast<int>(y), nv - 2);
    const float ty = smooth(std::clamp(y - static_cast<float>(j0), 0.0f, 1.0f));
    const float* r0 = lattice.data() + static_cast<std::size_t>(j0) * nu;
    const float* r1 = r0 + nu;
    line.resize(nu);
    for (int i = 0; i < nu; ++i) line[i] = r0[i] + ty * (r1[i] - r0[i]);
  }
  /// Value at u metres on a row prepared by row().
  float at(float u, const std::vector<float>& line) const {
    const float x = std::max(0.0f, u * freq + off_u);  // >= 0: truncation is floor
    const int i0 = std::min(static_cast<int>(x), nu - 2);
    const float tx = smooth(std::clamp(x - static_cast<float>(i0), 0.0f, 1.0f));
    return line[i0] + tx * (line[i0 + 1] - line[i0]);
  }
};

/// Octaves covering [0, size_u + 1] x [0, size_v + 1] metres for one face.
std::vector<Octave> make_octaves(const CounterRng& rng, std::uint64_t face, double size_u, double size_v,
                                 int count, double wavelength, double lacunarity, double gain) {
  std::vector<Octave> octaves;
  double freq = 1.0 / wavelength;
  double weight = 1.0;
  for (int k = 0; k < count; ++k) {
    Octave o;
    o.freq = static_cast<float>(freq);
    o.weight = static_cast<float>(weight);
    o.off_u = static_cast<float>(rng.uniform(face, kTagOffsets + k, 0));
    o.off_v = static_cast<float>(rng.uniform(face, kTagOffsets + k, 1));
    o.nu = static_cast<int>(std::ceil((size_u + 1.0) * freq)) + 3;
    o.nv = static_cast<int>(std::ceil((size_v + 1.0) * freq)) + 3;
    o.lattice.resize(static_cast<std::size_t>(o.nu) * o.nv);
    for (std::size_t i = 0; i < o.lattice.size(); ++i) {
      o.lattice[i] = static_cast<float>(rng.uniform(face, kTagLattice + k, i));
    }
    octaves.push_back(std::move(o));
    freq *= lacunarity;
    weight *= gain;
  }
  return octaves;
}

/// Weighted octave sum over one texel row, normalised to [0, 1].
void fractal_row(const std::vector<Octave>& octaves, float v, float texel, int width,
                 std::vector<float>& line, std::vector<float>& out) {
  out.assign(width, 0.0f);
  float total = 0.0f;
  for (const Octave& o : octaves) {
    o.row(v, line);
    for (int i = 0; i < width; ++i) out[i] += o.weight * o.at((static_cast<float>(i) + 0.5f) * texel, line);
    total += o.weight;
  }
  for (float& x : out) x /= total;
}

struct Poster {
  float u0, u1, v0, v1, value;
};
struct Blob {
  float cu, cv, r, value;
};

std::vector<Poster> make_posters(const CounterRng& rng, const Face& face, const IndoorTextureRecipe& rc) {
  const std::uint64_t id = static_cast<std::uint64_t>(face.id);
  const double area = face.size_u * face.size_v;
  const int n = static_cast<int>(std::floor(rc.posters_per_m2 * area + rng.uniform(id, kTagCounts, 0)));
  std::vector<Poster> posters(n);
  for (int k = 0; k < n; ++k) {
    const std::uint64_t base = 8 * static_cast<std::uint64_t>(k);
    const double w = rng.uniform(rc.poster_min_m, rc.poster_max_m, id, kTagPoster, base + 0);
    const double h = rng.uniform(rc.poster_min_m, rc.poster_max_m, id, kTagPoster, base + 1);
    const double cu = rng.uniform(0.0, face.size_u, id, kTagPoster, base + 2);
    const double cv = rng.uniform(0.0, face.size_v, id, kTagPoster, base + 3);
    posters[k] = Poster{static_cast<float>(cu - 0.5 * w), static_cast<float>(cu + 0.5 * w),
                        static_cast<float>(cv - 0.5 * h), static_cast<float>(cv + 0.5 * h),
                        static_cast<float>(rng.uniform(id, kTagPoster, base + 4))};
  }
  return posters;
}

std::vector<Blob> make_blobs(const CounterRng& rng, const Face& face, const IndoorTextureRecipe& rc) {
  const std::uint64_t id = static_cast<std::uint64_t>(face.id);
  const double area = face.size_u * face.size_v;
  const int n = static_cast<int>(std::floor(rc.blobs_per_m2 * area + rng.uniform(id, kTagCounts, 1)));
  std::vector<Blob> blobs(n);
  for (int k = 0; k < n; ++k) {
    const std::uint64_t base = 8 * static_cast<std::uint64_t>(k);
    blobs[k] = Blob{
        static_cast<float>(rng.uniform(0.0, face.size_u, id, kTagBlob, base + 0)),
        static_cast<float>(rng.uniform(0.0, face.size_v, id, kTagBlob, base + 1)),
        static_cast<float>(rng.uniform(rc.blob_min_radius_m, rc.blob_max_radius_m, id, kTagBlob, base + 2)),
        rng.uniform(id, kTagBlob, base + 3) < 0.5 ? 0.05f : 0.95f};
  }
  return blobs;
}

/// First and one-past-last texel whose centre lies in [a, b) metres.
inline std::pair<int, int> texel_span(float a, float b, float texel, int width) {
  const int i0 = std::max(0, static_cast<int>(std::ceil(a / texel - 0.5f)));
  const int i1 = std::min(width, static_cast<int>(std::ceil(b / texel - 0.5f)));
  return {i0, i1};
}

/// Posters, then blobs, painted over one row of base albedo `row` (noise albedo in `noise`).
void paint_row(const std::vector<Poster>& posters, const std::vector<Blob>& blobs, float v, float texel,
               const std::vector<float>& noise, std::vector<float>& row) {
  const int width = static_cast<int>(row.size());
  for (const Poster& p : posters) {
    if (v < p.v0 || v >= p.v1) continue;
    const auto [i0, i1] = texel_span(p.u0, p.u1, texel, width);
    for (int i = i0; i < i1; ++i) row[i] = 0.35f * noise[i] + 0.65f * p.value;
  }
  for (const Blob& b : blobs) {
    const float dv = v - b.cv;
    if (std::abs(dv) >= b.r) continue;
    const float half_chord = std::sqrt(b.r * b.r - dv * dv);
    const auto [i0, i1] = texel_span(b.cu - half_chord, b.cu + half_chord, texel, width);
    for (int i = i0; i < i1; ++i) row[i] = b.value;
  }
}

/// Everything needed to fill the rows of one face.
struct FaceRecipe {
  const Face* face = nullptr;
  int width = 0;
  int height = 0;
  float flat_base = 0.0f;  ///< textureless faces: constant albedo
  std::vector<Octave> octaves;
  std::vector<Poster> posters;
  std::vector<Blob> blobs;
  std::vector<std::uint8_t> level0;
};

FaceRecipe make_recipe(const Face& face, const CounterRng& rng, float texel, const IndoorTextureRecipe& rc) {
  FaceRecipe r;
  const auto id = static_cast<std::uint64_t>(face.id);
  r.face = &face;
  r.width = std::max(1, static_cast<int>(std::ceil(face.size_u / texel - 1e-6)));
  r.height = std::max(1, static_cast<int>(std::ceil(face.size_v / texel - 1e-6)));
  r.level0.resize(static_cast<std::size_t>(r.width) * r.height);
  if (face.textureless) {
    r.octaves = make_octaves(rng, id, face.size_u, face.size_v, 1, rc.shading_wavelength_m, 2.0, 0.5);
    r.flat_base = static_cast<float>(rng.uniform(0.25, 0.75, id, kTagFlat, 0));
  } else {
    r.octaves = make_octaves(rng, id, face.size_u, face.size_v, rc.octaves, rc.base_wavelength_m,
                             rc.lacunarity, rc.gain);
    r.posters = make_posters(rng, face, rc);
    r.blobs = make_blobs(rng, face, rc);
  }
  return r;
}

/// Row buffers of one thread.
struct RowScratch {
  std::vector<float> line;
  std::vector<float> noise;
  std::vector<float> row;
};

/// Texel row j of a face: fractal noise (contrast-stretched), posters, blobs; or the
/// textureless constant with +-1 % shading.
void fill_row(FaceRecipe& r, int j, float texel, float contrast, RowScratch& s) {
  const float v = (static_cast<float>(j) + 0.5f) * texel;
  fractal_row(r.octaves, v, texel, r.width, s.line, s.noise);
  std::uint8_t* dst = r.level0.data() + static_cast<std::size_t>(j) * r.width;
  if (r.face->textureless) {
    for (int i = 0; i < r.width; ++i)
      dst[i] = quantize_albedo(r.flat_base * (1.0f + 0.01f * (2.0f * s.noise[i] - 1.0f)));
    return;
  }
  for (float& n : s.noise) n = 0.5f + contrast * (n - 0.5f);
  s.row = s.noise;
  paint_row(r.posters, r.blobs, v, texel, s.noise, s.row);
  for (int i = 0; i < r.width; ++i) dst[i] = quantize_albedo(s.row[i]);
}

}  // namespace

std::uint8_t quantize_albedo(float a) {
  const float c = std::clamp(a, kAlbedoMin, kAlbedoMax);
  return static_cast<std::uint8_t>(static_cast<int>(c * 255.0f + 0.5f));  // round half up, c > 0
}

MipTexture::MipTexture(int width, int height, float texel, std::vector<std::uint8_t> level0, float size_u,
                       float size_v, bool wrap)
    : texel_(texel), size_u_(size_u), size_v_(size_v), wrap_(wrap) {
  std::size_t total = 0;
  int w = width;
  int h = height;
  while (true) {
    width_.push_back(w);
    height_.push_back(h);
    inv_texel_.push_back(1.0f / std::ldexp(texel, static_cast<int>(inv_texel_.size())));
    offset_.push_back(total);
    total += static_cast<std::size_t>(w) * h;
    if (w == 1 && h == 1) break;
    w = (w + 1) / 2;
    h = (h + 1) / 2;
  }
  level0.resize(total);
  data_ = std::move(level0);
  for (int k = 1; k < levels(); ++k) {
    const std::uint8_t* src = data_.data() + offset_[k - 1];
    std::uint8_t* dst = data_.data() + offset_[k];
    const int sw = width_[k - 1];
    const int sh = height_[k - 1];
    const int dw = width_[k];
    const int dh = height_[k];
    for (int j = 0; j < dh; ++j) {
      const std::uint8_t* r0 = src + static_cast<std::size_t>(2 * j) * sw;
      const std::uint8_t* r1 = src + static_cast<std::size_t>(std::min(2 * j + 1, sh - 1)) * sw;
      for (int i = 0; i < dw; ++i) {
        const int i1 = std::min(2 * i + 1, sw - 1);
        const int sum = r0[2 * i] + r0[i1] + r1[2 * i] + r1[i1];
        dst[static_cast<std::size_t>(j) * dw + i] = static_cast<std::uint8_t>((sum + 2) / 4);
      }
    }
  }
}

float MipTexture::sample_level(int level, float u, float v) const {
  const int w = width_[level];
  const int h = height_[level];
  const float inv = inv_texel_[level];
  const std::uint8_t* d = data_.data() + offset_[level];
  float x;
  float y;
  int i0;
  int i1;
  int j0;
  int j1;
  if (wrap_) {
    x = u * inv - 0.5f;
    y = v * inv - 0.5f;
    const float fx = std::floor(x);
    const float fy = std::floor(y);
    i0 = static_cast<int>(static_cast<long long>(fx) & (w - 1));
    j0 = static_cast<int>(static_cast<long long>(fy) & (h - 1));
    i1 = (i0 + 1) & (w - 1);
    j1 = (j0 + 1) & (h - 1);
    x -= fx;
    y -= fy;
  } else {
    x = std::clamp(std::clamp(u, 0.0f, size_u_) * inv - 0.5f, 0.0f, static_cast<float>(w - 1));
    y = std::clamp(std::clamp(v, 0.0f, size_v_) * inv - 0.5f, 0.0f, static_cast<float>(h - 1));
    i0 = static_cast<int>(x);
    j0 = static_cast<int>(y);
    i1 = std::min(i0 + 1, w - 1);
    j1 = std::min(j0 + 1, h - 1);
    x -= static_cast<float>(i0);
    y -= static_cast<float>(j0);
  }
  const std::uint8_t* r0 = d + static_cast<std::size_t>(j0) * w;
  const std::uint8_t* r1 = d + static_cast<std::size_t>(j1) * w;
  const float top = static_cast<float>(r0[i0]) + x * static_cast<float>(r0[i1] - r0[i0]);
  const float bottom = static_cast<float>(r1[i0]) + x * static_cast<float>(r1[i1] - r1[i0]);
  return (top + y * (bottom - top)) * (1.0f / 255.0f);
}

float MipTexture::sample(float u, float v, float lod) const {
  const float max_level = static_cast<float>(levels() - 1);
  const float l = std::clamp(lod, 0.0f, max_level);  // NaN-free callers; NaN gives level 0
  const int l0 = static_cast<int>(l);
  const float f = l - static_cast<float>(l0);
  const float a = sample_level(l0, u, v);
  if (f <= 0.0f || l0 + 1 >= levels()) return a;
  return a + f * (sample_level(l0 + 1, u, v) - a);
}

std::vector<MipTexture> bake_indoor_faces(const std::vector<Face>& faces, std::uint64_t seed, float texel,
                                          const IndoorTextureRecipe& rc) {
  const CounterRng rng(seed, Stream::kTexture);
  std::vector<FaceRecipe> recipes;
  recipes.reserve(faces.size());
  for (const Face& f : faces) recipes.push_back(make_recipe(f, rng, texel, rc));
  // One flat job list of (face, block of rows) over all faces: two parallel regions per
  // scene, whatever the number of faces (each region costs a barrier on a busy machine).
  constexpr int kRowsPerJob = 32;
  std::vector<std::pair<int, int>> jobs;
  for (std::size_t k = 0; k < recipes.size(); ++k) {
    for (int j = 0; j < recipes[k].height; j += kRowsPerJob) jobs.emplace_back(static_cast<int>(k), j);
  }
  const auto contrast = static_cast<float>(rc.contrast);
  const auto n_jobs = static_cast<int>(jobs.size());
#pragma omp parallel
  {
    RowScratch scratch;
#pragma omp for schedule(dynamic, 1)
    for (int job = 0; job < n_jobs; ++job) {
      FaceRecipe& r = recipes[jobs[job].first];
      const int end = std::min(r.height, jobs[job].second + kRowsPerJob);
      for (int j = jobs[job].second; j < end; ++j) fill_row(r, j, texel, contrast, scratch);
    }
  }
  std::vector<MipTexture> out(recipes.size());
  const auto n_faces = static_cast<int>(recipes.size());
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < n_faces; ++k) {
    FaceRecipe& r = recipes[k];
    out[k] = MipTexture(r.width, r.height, texel, std::move(r.level0), static_cast<float>(r.face->size_u),
                        static_cast<float>(r.face->size_v));
  }
  return out;
}

MipTexture bake_indoor_face(const Face& face, std::uint64_t seed, float texel,
                            const IndoorTextureRecipe& rc) {
  return std::move(bake_indoor_faces({face}, seed, texel, rc).front());
}

MipTexture bake_noise_tile(std::uint64_t seed, std::uint64_t salt, int size, float texel) {
  const CounterRng rng(seed, Stream::kTexture);
  const std::uint64_t key = ~std::uint64_t{0};
  // Octave k has a lattice period of 8 * 2^k cells over the tile, so the tile is seamless.
  std::vector<Octave> octaves;
  float weight = 1.0f;
  const float tile_m = static_cast<float>(size) * texel;
  for (int period = 8, k = 0; period <= size / 2; period *= 2, ++k) {
    Octave o;
    o.freq = static_cast<float>(period) / tile_m;
    o.weight = weight;
    o.nu = o.nv = period + 2;
    o.lattice.resize(static_cast<std::size_t>(o.nu) * o.nv);
    for (int j = 0; j < o.nv; ++j) {
      for (int i = 0; i < o.nu; ++i) {
        const auto cell = static_cast<std::uint64_t>((j % period) * period + (i % period));
        o.lattice[static_cast<std::size_t>(j) * o.nu + i] =
            static_cast<float>(rng.uniform(key, kTagTile + salt * 64 + k, cell));
      }
    }
    octaves.push_back(std::move(o));
    weight *= 0.5f;
  }
  std::vector<std::uint8_t> level0(static_cast<std::size_t>(size) * size);
#pragma omp parallel
  {
    std::vector<float> line;
    std::vector<float> noise;
#pragma omp for schedule(static)
    for (int j = 0; j < size; ++j) {
      fractal_row(octaves, (static_cast<float>(j) + 0.5f) * texel, texel, size, line, noise);
      for (int i = 0; i < size; ++i) {
        level0[static_cast<std::size_t>(j) * size + i] = quantize_albedo(0.5f + 2.0f * (noise[i] - 0.5f));
      }
    }
  }
  return MipTexture(size, size, texel, std::move(level0), tile_m, tile_m, true);
}

}  // namespace mrvs::sim::detail
