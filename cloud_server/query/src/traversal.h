#pragma once
// 3D-DDA (Amanatides-Woo) over one level's brick index (internal to mrvs::map_query).
//
// The ray is origin + t * direction (direction unit, map-local metres). The segment is first
// clipped to the level's traversal box (everything outside it is empty). Empty bricks are
// crossed in one step: the traversal jumps to the brick's exit and re-derives the voxel there;
// inside occupied bricks it steps voxel by voxel and tests the occupancy bits. The boundary
// crossing times are always computed from the voxel index, t = (idx + up) * r / v + (-o / v),
// never accumulated, so there is no drift over long rays.
//
// Tie rule between axes (as the reference code): x when t_x < t_y and t_x < t_z, else y when
// t_y < t_z, else z. Voxels the ray only touches at an edge or a corner (zero chord) may or
// may not be reported; every voxel with a chord of positive length is visited in order.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Core>

#include "level_index.h"

namespace mrvs::map::detail {

/// Work done by traversals (benchmarks, diagnostics).
struct TraversalCounters {
  std::uint64_t bricks = 0;           ///< brick visits (occupied or empty)
  std::uint64_t occupied_bricks = 0;  ///< visits of bricks holding points
  std::uint64_t voxels = 0;           ///< voxel tests inside occupied bricks
};

/// The first occupied voxel of a segment.
struct RawHit {
  std::uint32_t sorted = 0;  ///< into LevelIndex's sorted points
  double t_entry = 0.0;      ///< where the segment enters the voxel, m
  Eigen::Vector3i voxel = Eigen::Vector3i::Zero();
};

/// Clips [t0, t1] to the part of the line inside `box`; false when nothing is left.
inline bool clip_to_box(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& o, const Eigen::Vector3d& v,
                        double& t0, double& t1) {
  if (box.isEmpty()) return false;
  for (int a = 0; a < 3; ++a) {
    if (v[a] == 0.0) {
      if (o[a] < box.min()[a] || o[a] > box.max()[a]) return false;
      continue;
    }
    const double inv = 1.0 / v[a];
    double ta = (box.min()[a] - o[a]) * inv;
    double tb = (box.max()[a] - o[a]) * inv;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

/// floor(x) as int32 for |x| < 2^31 (std::floor is a library sequence without SSE4.1).
inline std::int32_t floor_to_int(double x) {
  const auto i = static_cast<std::int32_t>(x);
  return i - (x < static_cast<double>(i) ? 1 : 0);
}

/// Axis of the smallest of three crossing times (reference tie rule).
inline int next_axis(const double* t) {
  if (t[0] < t[1] && t[0] < t[2]) return 0;
  return t[1] < t[2] ? 1 : 2;
}

/// First occupied voxel of `index` along o + t v (v unit), t in [t_start, t_end]. A voxel
/// counts when it is entered at t <= t_end; the voxel holding the start point counts with
/// t_entry = t_start. Allocation-free; counts work in `counters` when kCount.
template <bool kCount>
bool first_occupied(const LevelIndex& index, const Eigen::Vector3d& o, const Eigen::Vector3d& v,
                    double t_start, double t_end, RawHit* hit, TraversalCounters* counters) {
  double t = t_start;
  double t1 = t_end;
  if (!clip_to_box(index.box(), o, v, t, t1)) return false;
  const double r = index.resolution();
  const double inv_r = 1.0 / r;
  const double inf = std::numeric_limits<double>::infinity();
  // Every position on the segment, in voxels, stays below 2^30 in magnitude (so the int32
  // casts cannot overflow); segments beyond that (10 000 km at 1 cm: a meaningless ray whose
  // float/double positions near the map have no digits left) find nothing.
  if ((o.cwiseAbs().maxCoeff() + std::max(std::abs(t), std::abs(t1))) * inv_r > 1073741824.0) return false;
  std::int32_t idx[3];
  std::int32_t step[3];
  std::int32_t up[3];
  double k[3];
  double c[3];
  for (int a = 0; a < 3; ++a) {
    idx[a] = floor_to_int((o[a] + t * v[a]) * inv_r);
    step[a] = v[a] > 0.0 ? 1 : (v[a] < 0.0 ? -1 : 0);
    up[a] = v[a] > 0.0 ? 1 : 0;
    const double inv = step[a] != 0 ? 1.0 / v[a] : 0.0;
    k[a] = r * inv;
    c[a] = step[a] != 0 ? -o[a] * inv : inf;
  }
  // Safety net against endless loops on pathological input: more than enough for any
  // segment inside the box (each step crosses one voxel face).
  std::int64_t budget = static_cast<std::int64_t>(3.0 * (t1 - t) / r) + 64;
  for (;;) {
    const std::int32_t b[3] = {brick_of(idx[0]), brick_of(idx[1]), brick_of(idx[2])};
    if constexpr (kCount) ++counters->bricks;
    const std::uint32_t brick = index.find_brick(b[0], b[1], b[2]);
    if (brick == kNoBrick) {
      // Jump to the brick's exit: the exit axis enters the next brick, the others stay in it.
      double te[3];
      for (int a = 0; a < 3; ++a) {
        const std::int32_t last = step[a] > 0 ? b[a] * kBrickEdge + (kBrickEdge - 1) : b[a] * kBrickEdge;
        te[a] = step[a] != 0 ? (last + up[a]) * k[a] + c[a] : inf;
      }
      const int e = next_axis(te);
      if (!(te[e] <= t1) || --budget < 0) return false;
      t = std::max(t, te[e]);
      for (int a = 0; a < 3; ++a) {
        if (a == e || step[a] == 0) continue;
        idx[a] =
            std::clamp(floor_to_int((o[a] + t * v[a]) * inv_r), b[a] * kBrickEdge, b[a] * kBrickEdge + 7);
      }
      idx[e] = (step[e] > 0 ? b[e] * kBrickEdge + kBrickEdge : b[e] * kBrickEdge - 1);
      continue;
    }
    if constexpr (kCount) ++counters->occupied_bricks;
    const BrickMask& mask = index.mask(brick);
    double tm[3];
    for (int a = 0; a < 3; ++a) tm[a] = step[a] != 0 ? (idx[a] + up[a]) * k[a] + c[a] : inf;
    for (;;) {
      if constexpr (kCount) ++counters->voxels;
      const int bit = bit_of(idx[0], idx[1], idx[2]);
      if (mask.test(bit)) {
        hit->sorted = index.base(brick) + mask.rank(bit);
        hit->t_entry = t;
        hit->voxel = Eigen::Vector3i(idx[0], idx[1], idx[2]);
        return true;
      }
      const int a = next_axis(tm);
      if (!(tm[a] <= t1) || --budget < 0) return false;
      t = std::max(t, tm[a]);
      idx[a] += step[a];
      if (brick_of(idx[a]) != b[a]) break;
      tm[a] = (idx[a] + up[a]) * k[a] + c[a];
    }
  }
}

}  // namespace mrvs::map::detail
