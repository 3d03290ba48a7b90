// Outdoor albedo (simulator.md 3.3): road with lane lines and crosswalks, sidewalk tiles,
// facades with a window grid and shop signs, all box-filtered over the texel footprint and
// modulated by one seamless noise tile.
#include <algorithm>
#include <cmath>

#include "mrvs/sim/rng.h"
#include "street.h"

namespace mrvs::sim::detail {
namespace {

constexpr int kTileSize = 1024;
constexpr std::uint64_t kTagFacade = 2000;
constexpr float kMarking = 0.85f;
constexpr float kFrame = 0.8f;
constexpr double kFloorHeight = 3.2;

/// Mean over [x - f/2, x + f/2] of the indicator of [a, b).
double pulse(double x, double f, double a, double b) {
  if (f < 1e-6) return (x >= a && x < b) ? 1.0 : 0.0;
  const double w = b - a;
  return (std::clamp(x + 0.5 * f - a, 0.0, w) - std::clamp(x - 0.5 * f - a, 0.0, w)) / f;
}

/// Integral from 0 to x of a pulse train: [a, a + w) in every period p.
double train_integral(double x, double p, double a, double w) {
  const double k = std::floor(x / p);
  return k * w + std::clamp(x - k * p - a, 0.0, w);
}

/// Mean over [x - f/2, x + f/2] of the pulse train.
double train(double x, double f, double p, double a, double w) {
  if (f < 1e-6) {
    const double r = x - std::floor(x / p) * p;
    return (r >= a && r < a + w) ? 1.0 : 0.0;
  }
  return (train_integral(x + 0.5 * f, p, a, w) - train_integral(x - 0.5 * f, p, a, w)) / f;
}

float lerp(float a, float b, double t) { return a + static_cast<float>(t) * (b - a); }

/// Lane lines and crosswalks of a corridor at (s, q); returns the marking coverage in [0, 1].
double markings(const StreetCorridor& c, double s, double q, double f) {
  constexpr double kHalfLine = 0.075;
  double cover = 0.0;
  // Intersection squares and crosswalks (3 m wide, 1 m before each square) at corner ends.
  const double square_hi = c.corner_hi ? c.s_hi - 2.0 * kRoadHalfWidth : 1e30;
  const double square_lo = c.corner_lo ? c.s_lo + 2.0 * kRoadHalfWidth : -1e30;
  if (s >= square_hi || s <= square_lo) return 0.0;
  const double zebra = train(q + 50.0, f, 1.0, 0.0, 0.5) * pulse(q, f, -6.5, 6.5);
  if (c.corner_hi) cover = std::max(cover, zebra * pulse(s, f, square_hi - 4.0, square_hi - 1.0));
  if (c.corner_lo) cover = std::max(cover, zebra * pulse(s, f, square_lo + 1.0, square_lo + 4.0));
  const double aq = std::abs(q);
  cover = std::max(cover, pulse(aq, f, 6.6, 6.75));                                // edge lines
  cover = std::max(cover, pulse(aq, f, 0.05, 0.2));                                // double centre line
  const double dash = train(s + 1e4, f, 9.0, 0.0, 3.0);                            // 3 m dash, 6 m gap
  cover = std::max(cover, dash * pulse(aq, f, 3.5 - kHalfLine, 3.5 + kHalfLine));  // lane dividers
  return cover;
}

}  // namespace

StreetAppearance::StreetAppearance(const StreetLayout& layout, const std::vector<Face>& faces,
                                   std::uint64_t seed)
    : corridors_(layout.corridors),
      arcs_(layout.arcs),
      ground_origin_(layout.ground.min()),
      tile_(bake_noise_tile(seed, 0, kTileSize, kStreetTexel)) {
  const CounterRng rng(seed, Stream::kTexture);
  const float period = kTileSize * kStreetTexel;
  materials_.resize(faces.size());
  for (const Face& f : faces) {
    const auto id = static_cast<std::uint64_t>(f.id);
    FaceMaterial& m = materials_[f.id];
    m.off_u = static_cast<float>(rng.uniform(0.0, period, id, kTagFacade, 0));
    m.off_v = static_cast<float>(rng.uniform(0.0, period, id, kTagFacade, 1));
    m.base = static_cast<float>(rng.uniform(0.25, 0.75, id, kTagFacade, 2));
    if (f.id == 0) {
      m.kind = Material::kGround;
    } else {
      const int slot = (f.id - 1) % 6;
      const SceneBox& box = layout.boxes[(f.id - 1) / 6];
      const bool building = box.kind == BoxKind::kBuilding;
      if (slot == 5) m.kind = building ? Material::kRoof : Material::kSidewalkTop;
      if (slot == 4 || (!building && slot < 4)) m.kind = Material::kConcrete;
      if (building && slot < 4) m.kind = Material::kFacade;
    }
    if (f.textureless) m.kind = Material::kFlat;
    if (m.kind != Material::kFacade) continue;
    // Window grid and signs; the building's numbers are keyed by its first face.
    const auto b = static_cast<std::uint64_t>(f.id - (f.id - 1) % 6);
    Facade& g = m.facade;
    g.wall = static_cast<float>(rng.uniform(0.4, 0.8, b, kTagFacade, 10));
    g.window = static_cast<float>(rng.uniform(0.1, 0.3, b, kTagFacade, 11));
    g.pitch = static_cast<float>(rng.uniform(2.5, 4.0, b, kTagFacade, 12));
    g.width = static_cast<float>(rng.uniform(1.2, std::min(1.8, g.pitch - 0.6), b, kTagFacade, 13));
    const int columns = static_cast<int>(std::floor((f.size_u - 1.0) / g.pitch));
    g.margin = columns > 0 ? static_cast<float>(0.5 * (f.size_u - (columns - 1) * g.pitch - g.width)) : 0.0f;
    g.u_end = columns > 0 ? g.margin + static_cast<float>((columns - 1) * g.pitch + g.width) : 0.0f;
    g.top = static_cast<float>(kFloorHeight * std::floor((f.size_v - 0.6) / kFloorHeight));
    m.sign_begin = static_cast<int>(signs_.size());
    const int n_signs = 1 + static_cast<int>(rng.uniform(id, kTagFacade, 20) * 3.0);
    for (int k = 0; k < n_signs; ++k) {
      const double w = std::min(rng.uniform(2.0, 6.0, id, kTagFacade, 21 + 4 * k), f.size_u);
      const double u0 = rng.uniform(0.0, f.size_u - w, id, kTagFacade, 22 + 4 * k);
      signs_.push_back(Sign{static_cast<float>(u0), static_cast<float>(u0 + w), 2.6f, 3.1f,
                            static_cast<float>(rng.uniform(0.05, 0.95, id, kTagFacade, 23 + 4 * k))});
    }
    m.sign_end = static_cast<int>(signs_.size());
  }
}

float StreetAppearance::tile(const FaceMaterial& m, float u, float v, float lod, float scale) const {
  return tile_.sample((u + m.off_u) * scale, (v + m.off_v) * scale, lod + std::log2(scale));
}

float StreetAppearance::ground(float u, float v, float lod) const {
  const FaceMaterial& m = materials_[0];
  const double f = kStreetTexel * std::exp2(static_cast<double>(std::max(lod, 0.0f)));
  const Eigen::Vector2d p = ground_origin_ + Eigen::Vector2d(u, v);
  int inside = 0;  // corridors and arcs containing p
  const StreetCorridor* only = nullptr;
  for (const StreetCorridor& c : corridors_) {
    const double s = c.along(p);
    if (s >= c.s_lo && s <= c.s_hi && std::abs(c.across(p)) <= kRoadHalfWidth) {
      ++inside;
      only = &c;
    }
  }
  for (const StreetArc& a : arcs_) {
    const Eigen::Vector2d d = p - a.centre;
    if (d.dot(a.dir_a) >= 0.0 && d.dot(a.dir_b) >= 0.0 && std::abs(d.norm() - a.radius) <= kRoadHalfWidth) {
      ++inside;
      only = nullptr;  // arcs carry no markings
    }
  }
  if (inside == 0) {
    // Concrete slabs (1 m) with dark joints.
    const double joints = std::max(train(u, f, 1.0, 0.0, 0.02), train(v, f, 1.0, 0.0, 0.02));
    return lerp(0.3f + 0.35f * tile(m, u, v, lod, 1.0f), 0.15f, joints);
  }
  // Fine grain (the tile at 1/16 scale: 16 cm down to 2.5 mm) over faint large patches.
  const float asphalt =
      0.15f + 0.15f * (0.75f * tile(m, u, v, lod, 16.0f) + 0.25f * tile(m, u, v, lod, 0.5f));
  if (inside > 1 || only == nullptr) return asphalt;
  const double cover = markings(*only, only->along(p), only->across(p), f);
  return lerp(asphalt, kMarking, cover);
}

float StreetAppearance::facade(const FaceMaterial& m, float u, float v, float lod) const {
  const Facade& g = m.facade;
  const double f = kStreetTexel * std::exp2(static_cast<double>(std::max(lod, 0.0f)));
  const float wall = g.wall * (0.7f + 0.6f * (tile(m, u, v, lod, 1.0f) - 0.5f));
  const double band_u = pulse(u, f, g.margin - 0.2, g.u_end + 0.2);
  // Upper floors: windows 0.9-2.4 m above each floor, 8 cm frames.
  const double band_v = pulse(v, f, kFloorHeight, g.top);
  const double col_frame = train(u - g.margin + 0.08, f, g.pitch, 0.0, g.width + 0.16);
  const double col_glass = train(u - g.margin, f, g.pitch, 0.0, g.width);
  const double row_frame = train(v, f, kFloorHeight, 0.82, 1.66);
  const double row_glass = train(v, f, kFloorHeight, 0.9, 1.5);
  const double frame = band_u * band_v * col_frame * row_frame;
  const double glass = band_u * band_v * col_glass * row_glass;
  // Per-window glass variation.
  const auto wi = static_cast<std::uint64_t>(std::max(0.0f, std::floor((u - g.margin) / g.pitch)));
  const auto wj = static_cast<std::uint64_t>(std::max(0.0, std::floor(v / kFloorHeight)));
  const float shade =
      g.window + 0.1f * (static_cast<float>(mix64(wi * 1315423911ULL ^ wj) >> 40) / 16777216.0f - 0.5f);
  float a = lerp(lerp(wall, kFrame, frame), shade, glass);
  // Ground floor: shop windows and signs.
  const double shop = pulse(v, f, 0.3, 2.5) * band_u * train(u - g.margin, f, g.pitch, 0.0, 0.75 * g.pitch);
  a = lerp(a, 0.12f, shop);
  for (int k = m.sign_begin; k < m.sign_end; ++k) {
    const Sign& s = signs_[k];
    a = lerp(a, s.value, pulse(u, f, s.u0, s.u1) * pulse(v, f, s.v0, s.v1));
  }
  return a;
}

float StreetAppearance::albedo(int face, float u, float v, float lod) const {
  const FaceMaterial& m = materials_[face];
  float a = 0.5f;
  switch (m.kind) {
    case Material::kGround:
      a = ground(u, v, lod);
      break;
    case Material::kSidewalkTop: {
      const double f = kStreetTexel * std::exp2(static_cast<double>(std::max(lod, 0.0f)));
      const double joints = std::max(train(u, f, 0.5, 0.0, 0.015), train(v, f, 0.5, 0.0, 0.015));
      a = lerp(0.35f + 0.35f * tile(m, u, v, lod, 2.0f), 0.2f, joints);
      break;
    }
    case Material::kConcrete:
      a = 0.3f + 0.4f * tile(m, u, v, lod, 1.0f);
      break;
    case Material::kFacade:
      a = facade(m, u, v, lod);
      break;
    case Material::kRoof:
      a = 0.2f + 0.4f * tile(m, u, v, lod, 1.0f);
      break;
    case Material::kFlat:
      a = m.base * (1.0f + 0.01f * (2.0f * tile(m, u, v, lod, 1.0f / 32.0f) - 1.0f));
      break;
  }
  return std::clamp(a, kAlbedoMin, kAlbedoMax);
}

}  // namespace mrvs::sim::detail
