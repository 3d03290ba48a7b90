#include "query_test_maps.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include <gtest/gtest.h>

namespace mrvs::map::test {

ReferenceLevel::ReferenceLevel(const MapLevel& level) : resolution_(level.resolution) {
  for (std::size_t i = 0; i < level.points.size(); ++i) {
    const std::optional<voxel::VoxelIndex> v = voxel_of(level.points[i].position, level.resolution);
    if (v) voxels_.emplace(voxel::pack(*v), static_cast<std::int64_t>(i));
  }
}

std::int64_t ReferenceLevel::find(const voxel::VoxelIndex& v) const {
  if (!voxel::packable(v)) return -1;
  const auto it = voxels_.find(voxel::pack(v));
  return it == voxels_.end() ? -1 : it->second;
}

Segment make_segment(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, float t_start,
                     float t_end) {
  Segment s;
  s.origin = origin.cast<double>();
  s.direction = direction.cast<double>();
  s.direction /= s.direction.norm();
  s.t_start = t_start;
  s.t_end = t_end;
  return s;
}

voxel::VoxelIndex voxel_at(const Segment& s, double t, double r) {
  voxel::VoxelIndex v;
  for (int a = 0; a < 3; ++a)
    v[a] = static_cast<std::int32_t>(std::floor((s.origin[a] + t * s.direction[a]) / r));
  return v;
}

double chord(const Segment& s, const voxel::VoxelIndex& v, double r, double* entry) {
  double t0 = -std::numeric_limits<double>::infinity();
  double t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double lo = v[a] * r;
    const double hi = (v[a] + 1) * r;
    if (s.direction[a] == 0.0) {
      if (s.origin[a] < lo || s.origin[a] >= hi) return -std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (lo - s.origin[a]) / s.direction[a];
    double tb = (hi - s.origin[a]) / s.direction[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (entry != nullptr) *entry = t0;
  return std::min(t1, s.t_end) - std::max(t0, s.t_start);
}

std::optional<SampledHit> sample_first_hit(const ReferenceLevel& level, const Segment& s, double step) {
  const double r = level.resolution();
  voxel::VoxelIndex previous(std::numeric_limits<std::int32_t>::min(), 0, 0);
  const auto n = static_cast<std::int64_t>(std::ceil((s.t_end - s.t_start) / step));
  for (std::int64_t i = 0; i <= n; ++i) {
    const double t = std::min(s.t_start + static_cast<double>(i) * step, s.t_end);
    const voxel::VoxelIndex v = voxel_at(s, t, r);
    if (v == previous) continue;
    previous = v;
    const std::int64_t point = level.find(v);
    if (point >= 0) return SampledHit{v, point, t};
  }
  return std::nullopt;
}

Eigen::Vector3f point_in_voxel(const voxel::VoxelIndex& v, double r, const Eigen::Vector3d& fraction) {
  return ((v.cast<double>() + fraction) * r).cast<float>();
}

namespace {

void add_voxel(MapLevel& level, std::set<std::uint64_t>& used, const voxel::VoxelIndex& v,
               std::mt19937_64& rng) {
  if (!voxel::packable(v) || !used.insert(voxel::pack(v)).second) return;
  std::uniform_real_distribution<double> inside(0.02, 0.98);
  const Eigen::Vector3f p =
      point_in_voxel(v, level.resolution, Eigen::Vector3d(inside(rng), inside(rng), inside(rng)));
  const std::optional<voxel::VoxelIndex> back = voxel_of(p, level.resolution);
  if (!back || *back != v) return;  // float rounding moved it: skip
  MapPoint point;
  point.position = p;
  level.points.push_back(point);
}

}  // namespace

VoxelMap random_map(const std::vector<double>& resolutions, double box_m, int clusters, int scatter,
                    std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  VoxelMap map;
  for (const double r : resolutions) {
    MapLevel level;
    level.resolution = r;
    std::set<std::uint64_t> used;
    std::uniform_real_distribution<double> where(-box_m, box_m);
    std::uniform_int_distribution<int> radius(1, 6);
    std::bernoulli_distribution keep(0.35);
    for (int c = 0; c < clusters; ++c) {
      const voxel::VoxelIndex centre(static_cast<std::int32_t>(std::floor(where(rng) / r)),
                                     static_cast<std::int32_t>(std::floor(where(rng) / r)),
                                     static_cast<std::int32_t>(std::floor(where(rng) / r)));
      const int rad = radius(rng);
      for (int z = -rad; z <= rad; ++z)
        for (int y = -rad; y <= rad; ++y)
          for (int x = -rad; x <= rad; ++x)
            if (keep(rng)) add_voxel(level, used, centre + voxel::VoxelIndex(x, y, z), rng);
    }
    for (int s = 0; s < scatter; ++s) {
      add_voxel(level, used,
                voxel::VoxelIndex(static_cast<std::int32_t>(std::floor(where(rng) / r)),
                                  static_cast<std::int32_t>(std::floor(where(rng) / r)),
                                  static_cast<std::int32_t>(std::floor(where(rng) / r))),
                rng);
    }
    std::shuffle(level.points.begin(), level.points.end(), rng);
    map.levels.push_back(std::move(level));
  }
  return map;
}

std::shared_ptr<VoxelMap> single_level_map(double resolution, const std::vector<Eigen::Vector3f>& points) {
  auto map = std::make_shared<VoxelMap>();
  MapLevel level;
  level.resolution = resolution;
  for (const Eigen::Vector3f& p : points) {
    MapPoint point;
    point.position = p;
    level.points.push_back(point);
  }
  map->levels.push_back(std::move(level));
  return map;
}

QueryEngine make_engine(std::shared_ptr<const VoxelMap> map, const QueryOptions& options) {
  StatusOr<QueryEngine> engine = QueryEngine::create(std::move(map), options);
  EXPECT_TRUE(engine.ok()) << engine.status();
  return engine.ok() ? *std::move(engine) : QueryEngine();
}

}  // namespace mrvs::map::test
