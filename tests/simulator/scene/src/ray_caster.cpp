#include "ray_caster.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace mrvs::sim::detail {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
/// Registered box footprints and the grid's z range are inflated by this (metres) so that
/// rounding in the DDA can never skip a box.
constexpr double kGridInflate = 1e-3;

/// 1 / x, with |x| kept >= 1e-30 (sign preserved, -0 counts as negative): no inf or NaN.
/// Branchless so that the batch loop vectorises.
inline float safe_inv(float x) {
  constexpr float kTiny = 1e-30f;
  const float a = std::fabs(x);
  return 1.0f / std::copysign(a < kTiny ? kTiny : a, x);
}

/// The smallest float above x (x > 0 finite; +inf stays +inf).
inline float next_up(float x) {
  if (!(x < kInf)) return x;
  std::uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  ++bits;
  std::memcpy(&x, &bits, sizeof bits);
  return x;
}

/// (u, v) on face `slot` (box_faces() order) of a box with half sizes h, from the local hit
/// point p (box centre at the origin, box axes), clamped to the face.
inline void uv_from_local(int slot, const float p[3], const float h[3], float& u, float& v) {
  switch (slot) {
    case 0:
      u = h[1] - p[1], v = p[2] + h[2];
      break;
    case 1:
      u = p[1] + h[1], v = p[2] + h[2];
      break;
    case 2:
      u = p[0] + h[0], v = p[2] + h[2];
      break;
    case 3:
      u = h[0] - p[0], v = p[2] + h[2];
      break;
    case 4:
      u = p[1] + h[1], v = p[0] + h[0];
      break;
    default:
      u = p[0] + h[0], v = p[1] + h[1];
      break;
  }
  const float su = (slot <= 1 || slot == 4) ? 2.0f * h[1] : 2.0f * h[0];
  const float sv = slot <= 3 ? 2.0f * h[2] : (slot == 4 ? 2.0f * h[0] : 2.0f * h[1]);
  u = std::clamp(u, 0.0f, su);
  v = std::clamp(v, 0.0f, sv);
}

}  // namespace

struct RayCaster::Ray {
  float o[3];
  float d[3];
  float inv[3];
};

struct RayCaster::Best {
  float t;
  int kind = 0;  // 0 none, 1 box, 2 room, 3 ground
  int index = -1;
  int slot = -1;
};

namespace {

/// Ray in the local frame of box b (centre at the origin, box axes); the same arithmetic
/// as slab_batch().
inline void to_box_frame(const CasterBox& b, const float o[3], const float d[3], float lo[3], float ld[3]) {
  const float px = o[0] - b.c[0];
  const float py = o[1] - b.c[1];
  lo[0] = b.cos_yaw * px + b.sin_yaw * py;
  lo[1] = b.cos_yaw * py - b.sin_yaw * px;
  lo[2] = o[2] - b.c[2];
  ld[0] = b.cos_yaw * d[0] + b.sin_yaw * d[1];
  ld[1] = b.cos_yaw * d[1] - b.sin_yaw * d[0];
  ld[2] = d[2];
}

/// Face slot (box_faces() order) through which the ray enters box b: the axis whose slab
/// gives slab_batch()'s t_near (same arithmetic and tie order), on the side facing the ray.
inline int entry_slot(const CasterBox& b, const float lo[3], const float ld[3], float inv_z) {
  const float ix = safe_inv(ld[0]);
  const float iy = safe_inv(ld[1]);
  const float x0 = (-b.h[0] - lo[0]) * ix;
  const float x1 = (b.h[0] - lo[0]) * ix;
  const float y0 = (-b.h[1] - lo[1]) * iy;
  const float y1 = (b.h[1] - lo[1]) * iy;
  const float z0 = (-b.h[2] - lo[2]) * inv_z;
  const float z1 = (b.h[2] - lo[2]) * inv_z;
  const float nx = x1 < x0 ? x1 : x0;
  const float ny = y1 < y0 ? y1 : y0;
  const float nz = z1 < z0 ? z1 : z0;
  const float nxy = ny > nx ? ny : nx;
  if (nz > nxy) return 4 + (inv_z >= 0.0f ? 0 : 1);
  if (ny > nx) return 2 + (iy >= 0.0f ? 0 : 1);
  return ix >= 0.0f ? 0 : 1;
}

}  // namespace

void RayCaster::add_box(const SceneBox& box, int first_face) {
  CasterBox b{};
  for (int i = 0; i < 3; ++i) {
    b.c[i] = static_cast<float>(box.centre[i]);
    b.h[i] = static_cast<float>(box.half[i]);
  }
  b.cos_yaw = static_cast<float>(box.cos_yaw);
  b.sin_yaw = static_cast<float>(box.sin_yaw);
  b.first_face = first_face;
  b.mask = static_cast<std::uint8_t>((box.rendered ? kMaskCamera : 0) | (box.in_map ? kMaskSurvey : 0));
  b.axis_aligned = b.cos_yaw == 1.0f && b.sin_yaw == 0.0f;
  boxes_.push_back(b);
}

void RayCaster::set_room(const Eigen::AlignedBox3d& room, int first_face) {
  has_room_ = true;
  for (int i = 0; i < 3; ++i) {
    room_lo_[i] = static_cast<float>(room.min()[i]);
    room_hi_[i] = static_cast<float>(room.max()[i]);
  }
  room_face_ = first_face;
}

void RayCaster::set_ground(double x0, double y0, double x1, double y1, double z, int face) {
  has_ground_ = true;
  ground_[0] = static_cast<float>(x0);
  ground_[1] = static_cast<float>(y0);
  ground_[2] = static_cast<float>(x1);
  ground_[3] = static_cast<float>(y1);
  ground_[4] = static_cast<float>(z);
  ground_face_ = face;
}

void RayCaster::build(double cell_size) {
  cell_begin_.clear();
  cell_mid_.clear();
  items_ = RayCasterItems{};
  if (boxes_.empty()) {
    nx_ = ny_ = 0;
    return;
  }
  Eigen::AlignedBox3d all;
  std::vector<Eigen::AlignedBox3d> aabbs;
  for (const CasterBox& b : boxes_) {
    SceneBox s;
    s.centre = Vec3d(b.c[0], b.c[1], b.c[2]);
    s.half = Vec3d(b.h[0], b.h[1], b.h[2]);
    s.cos_yaw = b.cos_yaw;
    s.sin_yaw = b.sin_yaw;
    Eigen::AlignedBox3d a = box_aabb(s);
    a.min().array() -= kGridInflate;
    a.max().array() += kGridInflate;
    aabbs.push_back(a);
    all.extend(a);
  }
  double cell = std::max(cell_size, 1e-3);
  const Vec3d ext = all.sizes();
  // Keep the grid at most ~1 M cells whatever the extent.
  while ((ext.x() / cell + 1.0) * (ext.y() / cell + 1.0) > 1e6) cell *= 2.0;
  cell_ = static_cast<float>(cell);
  inv_cell_ = 1.0f / cell_;
  gx0_ = static_cast<float>(all.min().x());
  gy0_ = static_cast<float>(all.min().y());
  gz0_ = static_cast<float>(all.min().z());
  gz1_ = static_cast<float>(all.max().z());
  nx_ = std::max(1, static_cast<int>(std::ceil(ext.x() / cell_)));
  ny_ = std::max(1, static_cast<int>(std::ceil(ext.y() / cell_)));
  std::vector<std::vector<int>> cells(static_cast<std::size_t>(nx_) * ny_);
  for (std::size_t k = 0; k < boxes_.size(); ++k) {
    const auto lo_x =
        std::clamp(static_cast<int>(std::floor((aabbs[k].min().x() - gx0_) / cell_)), 0, nx_ - 1);
    const auto hi_x =
        std::clamp(static_cast<int>(std::floor((aabbs[k].max().x() - gx0_) / cell_)), 0, nx_ - 1);
    const auto lo_y =
        std::clamp(static_cast<int>(std::floor((aabbs[k].min().y() - gy0_) / cell_)), 0, ny_ - 1);
    const auto hi_y =
        std::clamp(static_cast<int>(std::floor((aabbs[k].max().y() - gy0_) / cell_)), 0, ny_ - 1);
    for (int iy = lo_y; iy <= hi_y; ++iy) {
      for (int ix = lo_x; ix <= hi_x; ++ix)
        cells[static_cast<std::size_t>(iy) * nx_ + ix].push_back(static_cast<int>(k));
    }
  }
  cell_begin_.reserve(cells.size() + 1);
  cell_mid_.reserve(cells.size());
  for (const auto& c : cells) {
    cell_begin_.push_back(static_cast<int>(items_.box.size()));
    for (const int k : c) {
      if (boxes_[k].axis_aligned) items_.push(boxes_[k], k);
    }
    cell_mid_.push_back(static_cast<int>(items_.box.size()));
    for (const int k : c) {
      if (boxes_[k].axis_aligned) continue;
      // Rotated boxes are found through their (inflated) world AABB, then tested exactly.
      CasterBox bound = boxes_[k];
      for (int a = 0; a < 3; ++a) {
        bound.c[a] = static_cast<float>(aabbs[k].center()[a]);
        bound.h[a] = static_cast<float>(0.5 * aabbs[k].sizes()[a]);
      }
      items_.push(bound, k);
    }
  }
  cell_begin_.push_back(static_cast<int>(items_.box.size()));
}

void RayCasterItems::push(const CasterBox& b, int index) {
  cx.push_back(b.c[0]);
  cy.push_back(b.c[1]);
  cz.push_back(b.c[2]);
  hx.push_back(b.h[0]);
  hy.push_back(b.h[1]);
  hz.push_back(b.h[2]);
  mask.push_back(b.mask);
  box.push_back(index);
}

void RayCaster::test_room(const Ray& r, float t_min, Best& best) const {
  const bool inside = r.o[0] > room_lo_[0] && r.o[0] < room_hi_[0] && r.o[1] > room_lo_[1] &&
                      r.o[1] < room_hi_[1] && r.o[2] > room_lo_[2] && r.o[2] < room_hi_[2];
  float t_near = -kInf;
  float t_far = kInf;
  int axis = 0;
  for (int a = 0; a < 3; ++a) {
    // Exit plane chosen by index (no data-dependent branch): hi when moving +, else lo.
    const int neg = std::signbit(r.inv[a]) ? 1 : 0;
    const float exit = ((neg != 0 ? room_lo_[a] : room_hi_[a]) - r.o[a]) * r.inv[a];
    axis = exit < t_far ? a : axis;
    t_far = exit < t_far ? exit : t_far;
    if (!inside) {
      const float entry = ((neg != 0 ? room_hi_[a] : room_lo_[a]) - r.o[a]) * r.inv[a];
      t_near = entry > t_near ? entry : t_near;
    }
  }
  if (t_near <= t_far && t_far > t_min && t_far < best.t) {
    best.t = t_far;
    best.kind = 2;
    best.slot = 2 * axis + (r.inv[axis] >= 0.0f ? 1 : 0);  // leaving through the hi side: face x-hi etc.
  }
}

void RayCaster::test_ground(const Ray& r, float t_min, Best& best) const {
  if (!(r.d[2] < 0.0f) || !(r.o[2] > ground_[4])) return;
  const float t = (ground_[4] - r.o[2]) * r.inv[2];
  if (!(t > t_min && t < best.t)) return;
  const float x = r.o[0] + t * r.d[0];
  const float y = r.o[1] + t * r.d[1];
  if (x < ground_[0] || x > ground_[2] || y < ground_[1] || y > ground_[3]) return;
  best.t = t;
  best.kind = 3;
}

namespace {

/// Items are tested in chunks of this many (stack buffer).
constexpr int kChunk = 32;

/// Slab test of n axis-aligned items (structure of arrays from item c): the entry distance
/// t_near, or +inf when the item is invisible to `mask`, missed, or lies outside
/// (t_min, t_best). Returns the number of finite results.
/// Written without branches so that the compiler vectorises it; the arithmetic equals
/// entry_slot() for cos = 1, sin = 0.
inline int slab_batch(int n, const RayCasterItems& it, int c, const float o[3], const float inv[3],
                      float t_min, float t_best, int mask, float* cand) {
  int count = 0;
  const float* cx = &it.cx[c];
  const float* cy = &it.cy[c];
  const float* cz = &it.cz[c];
  const float* hx = &it.hx[c];
  const float* hy = &it.hy[c];
  const float* hz = &it.hz[c];
  const int* vis = &it.mask[c];
  for (int k = 0; k < n; ++k) {
    const float lx = o[0] - cx[k];
    const float ly = o[1] - cy[k];
    const float lz = o[2] - cz[k];
    const float x0 = (-hx[k] - lx) * inv[0];
    const float x1 = (hx[k] - lx) * inv[0];
    const float y0 = (-hy[k] - ly) * inv[1];
    const float y1 = (hy[k] - ly) * inv[1];
    const float z0 = (-hz[k] - lz) * inv[2];
    const float z1 = (hz[k] - lz) * inv[2];
    // Canonical a < b ? a : b / a > b ? a : b forms compile to minps / maxps.
    const float nx = x1 < x0 ? x1 : x0;
    const float fx = x1 > x0 ? x1 : x0;
    const float ny = y1 < y0 ? y1 : y0;
    const float fy = y1 > y0 ? y1 : y0;
    const float nz = z1 < z0 ? z1 : z0;
    const float fz = z1 > z0 ? z1 : z0;
    const float nxy = ny > nx ? ny : nx;
    const float fxy = fy < fx ? fy : fx;
    const float tn = nz > nxy ? nz : nxy;
    const float tf = fz < fxy ? fz : fxy;
    const bool ok = ((vis[k] & mask) != 0) & (tn <= tf) & (tf > t_min) & (tn < t_best);
    cand[k] = ok ? tn : kInf;
    count += ok ? 1 : 0;
  }
  return count;
}

/// Exact entry distance into the rotated box b (same arithmetic as entry_slot()), or +inf.
inline float rotated_entry(const CasterBox& b, const float o[3], const float d[3], float inv_z, float t_min) {
  float lo[3];
  float ld[3];
  to_box_frame(b, o, d, lo, ld);
  const float ix = safe_inv(ld[0]);
  const float iy = safe_inv(ld[1]);
  const float x0 = (-b.h[0] - lo[0]) * ix;
  const float x1 = (b.h[0] - lo[0]) * ix;
  const float y0 = (-b.h[1] - lo[1]) * iy;
  const float y1 = (b.h[1] - lo[1]) * iy;
  const float z0 = (-b.h[2] - lo[2]) * inv_z;
  const float z1 = (b.h[2] - lo[2]) * inv_z;
  const float nxy = std::max(std::min(x0, x1), std::min(y0, y1));
  const float fxy = std::min(std::max(x0, x1), std::max(y0, y1));
  const float tn = std::max(std::min(z0, z1), nxy);
  const float tf = std::min(std::max(z0, z1), fxy);
  return (tn > t_min && tn <= tf) ? tn : kInf;
}

}  // namespace

void RayCaster::test_items(int cell, const Ray& r, float t_min, std::uint8_t mask, Best& best) const {
  float cand[kChunk];
  const int begin = cell_begin_[cell];
  const int mid = cell_mid_[cell];
  const int end = cell_begin_[cell + 1];
  for (int c = begin; c < end; c += kChunk) {
    const int n = std::min(kChunk, end - c);
    if (slab_batch(n, items_, c, r.o, r.inv, t_min, best.t, mask, cand) == 0) continue;
    for (int k = 0; k < n; ++k) {
      if (!(cand[k] < best.t)) continue;
      const int index = items_.box[c + k];
      // Axis-aligned: the slab result is exact (skip boxes around the origin: one-sided faces).
      // Rotated: the AABB was hit before best.t; test the box itself.
      const float t = c + k < mid ? (cand[k] > t_min ? cand[k] : kInf)
                                  : rotated_entry(boxes_[index], r.o, r.d, r.inv[2], t_min);
      if (t < best.t) {
        best.t = t;
        best.kind = 1;
        best.index = index;
      }
    }
  }
}

void RayCaster::walk_grid(const Ray& r, float t_min, std::uint8_t mask, Best& best) const {
  if (nx_ == 0) return;
  const float glo[3] = {gx0_, gy0_, gz0_};
  const float ghi[3] = {gx0_ + nx_ * cell_, gy0_ + ny_ * cell_, gz1_};
  float ta = t_min;
  float tb = best.t;
  for (int a = 0; a < 3; ++a) {
    const float t0 = (glo[a] - r.o[a]) * r.inv[a];
    const float t1 = (ghi[a] - r.o[a]) * r.inv[a];
    ta = std::max(ta, std::min(t0, t1));
    tb = std::min(tb, std::max(t0, t1));
  }
  if (ta > tb) return;
  if (nx_ == 1 && ny_ == 1) {
    test_items(0, r, t_min, mask, best);
    return;
  }
  const float px = r.o[0] + ta * r.d[0];
  const float py = r.o[1] + ta * r.d[1];
  int ix = std::clamp(static_cast<int>(std::floor((px - gx0_) * inv_cell_)), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(std::floor((py - gy0_) * inv_cell_)), 0, ny_ - 1);
  const int sx = r.inv[0] >= 0.0f ? 1 : -1;
  const int sy = r.inv[1] >= 0.0f ? 1 : -1;
  const int ox = sx > 0 ? 1 : 0;
  const int oy = sy > 0 ? 1 : 0;
  while (true) {
    const float tnx = (gx0_ + static_cast<float>(ix + ox) * cell_ - r.o[0]) * r.inv[0];
    const float tny = (gy0_ + static_cast<float>(iy + oy) * cell_ - r.o[1]) * r.inv[1];
    const int cell = iy * nx_ + ix;
    test_items(cell, r, t_min, mask, best);
    const float t_exit = std::min(tnx, tny);
    if (best.t <= t_exit || t_exit >= tb) break;
    if (tnx < tny) {
      ix += sx;
      if (ix < 0 || ix >= nx_) break;
    } else {
      iy += sy;
      if (iy < 0 || iy >= ny_) break;
    }
  }
}

Hit RayCaster::make_hit(const Ray& r, const Best& best) const {
  Hit hit;
  hit.distance = best.t;
  float p[3];
  if (best.kind == 1) {
    const CasterBox& b = boxes_[best.index];
    float lo[3];
    float ld[3];
    to_box_frame(b, r.o, r.d, lo, ld);
    for (int a = 0; a < 3; ++a) p[a] = lo[a] + best.t * ld[a];
    const int slot = entry_slot(b, lo, ld, r.inv[2]);
    uv_from_local(slot, p, b.h, hit.u, hit.v);
    hit.face = b.first_face + slot;
  } else if (best.kind == 2) {
    float h[3];
    for (int a = 0; a < 3; ++a) {
      h[a] = 0.5f * (room_hi_[a] - room_lo_[a]);
      p[a] = r.o[a] + best.t * r.d[a] - (room_lo_[a] + h[a]);
    }
    // Room face 2a (lo side, normal +a) is parametrised like box face 2a + 1, and vice versa.
    uv_from_local(best.slot ^ 1, p, h, hit.u, hit.v);
    hit.face = room_face_ + best.slot;
  } else {
    hit.u = std::clamp(r.o[0] + best.t * r.d[0] - ground_[0], 0.0f, ground_[2] - ground_[0]);
    hit.v = std::clamp(r.o[1] + best.t * r.d[1] - ground_[1], 0.0f, ground_[3] - ground_[1]);
    hit.face = ground_face_;
  }
  return hit;
}

std::optional<Hit> RayCaster::intersect(const Vec3f& origin, const Vec3f& direction, float t_min, float t_max,
                                        std::uint8_t mask) const {
  if (!(t_max > t_min)) return std::nullopt;
  Ray r;
  for (int a = 0; a < 3; ++a) {
    r.o[a] = origin[a];
    r.d[a] = direction[a];
    r.inv[a] = safe_inv(direction[a]);
  }
  Best best;
  best.t = next_up(t_max);  // hits at exactly t_max count
  if (has_room_) test_room(r, t_min, best);
  if (has_ground_) test_ground(r, t_min, best);
  walk_grid(r, t_min, mask, best);
  if (best.kind == 0) return std::nullopt;
  return make_hit(r, best);
}

}  // namespace mrvs::sim::detail
