#include "mrvs/map/query_engine.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "level_index.h"
#include "mrvs/geometry/plane_fit.h"
#include "plane_fit.h"
#include "traversal.h"

namespace mrvs::map {

struct QueryEngine::Impl {
  std::shared_ptr<const VoxelMap> map;
  QueryOptions options;
  std::vector<detail::LevelIndex> levels;
};

QueryCounters& QueryCounters::operator+=(const QueryCounters& o) {
  rays += o.rays;
  passes += o.passes;
  bricks += o.bricks;
  occupied_bricks += o.occupied_bricks;
  voxels += o.voxels;
  refined += o.refined;
  return *this;
}

namespace {

/// Largest level count: QueryResult::level is an int8.
constexpr std::size_t kMaxLevels = 127;

Status check_levels(const VoxelMap& map) {
  if (map.levels.size() > kMaxLevels) {
    return absl::InvalidArgumentError(fmt::format(
        "voxel map: {} levels, the query engine supports at most {}", map.levels.size(), kMaxLevels));
  }
  for (std::size_t i = 1; i < map.levels.size(); ++i) {
    if (!(map.levels[i].resolution > map.levels[i - 1].resolution)) {
      return absl::InvalidArgumentError(
          fmt::format("voxel map: level {} has resolution {} m after {} m; levels must be sorted finest "
                      "first with strictly "
                      "increasing resolutions",
                      i, map.levels[i].resolution, map.levels[i - 1].resolution));
    }
  }
  return absl::OkStatus();
}

/// A validated query ray in double precision.
struct PreparedRay {
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;  ///< unit
};

/// Normalises the direction; false for non-finite values or a zero direction.
bool prepare_ray(const Eigen::Vector3f& origin, const Eigen::Vector3f& direction, PreparedRay* out) {
  if (!origin.allFinite() || !direction.allFinite()) return false;
  out->origin = origin.cast<double>();
  out->direction = direction.cast<double>();
  const double norm = out->direction.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return false;
  out->direction /= norm;
  return true;
}

/// Outcome of one DDA pass with its in-view test.
struct PassOutcome {
  bool found = false;     ///< an occupied voxel in range
  bool accepted = false;  ///< its point passed the in-view test
  bool refined = false;   ///< the point is a ray-plane intersection
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

/// A search range: t in [t_start, t_end], optionally with a middle part [skip_start,
/// skip_end] known to be empty (searched by an earlier pass) that is not traversed again.
struct SearchRange {
  double t_start = 0.0;
  double t_end = 0.0;
  double skip_start = 0.0;
  double skip_end = -1.0;  ///< < skip_start: nothing skipped
};

SearchRange range_around(double distance, double range) {
  return SearchRange{std::max(0.0, distance - range), distance + range};
}

template <bool kCount>
bool first_in_range(const detail::LevelIndex& index, const PreparedRay& ray, const SearchRange& range,
                    detail::RawHit* hit, QueryCounters* counters) {
  detail::TraversalCounters work;
  bool found = false;
  if (range.skip_end < range.skip_start) {
    found = detail::first_occupied<kCount>(index, ray.origin, ray.direction, range.t_start, range.t_end, hit,
                                           &work);
  } else {
    // Before the skipped part (if any of it is left), then after it. Every voxel the
    // earlier pass entered in [skip_start, skip_end] was empty, so the first occupied voxel
    // of the whole range is the first of these two.
    if (range.t_start < range.skip_start) {
      found = detail::first_occupied<kCount>(index, ray.origin, ray.direction, range.t_start,
                                             range.skip_start, hit, &work);
    }
    if (!found) {
      found = detail::first_occupied<kCount>(index, ray.origin, ray.direction, range.skip_end, range.t_end,
                                             hit, &work);
    }
  }
  if constexpr (kCount) {
    ++counters->passes;
    counters->bricks += work.bricks;
    counters->occupied_bricks += work.occupied_bricks;
    counters->voxels += work.voxels;
  }
  return found;
}

template <bool kCount>
PassOutcome run_pass(const detail::LevelIndex& index, const QueryOptions& options, const PreparedRay& ray,
                     const SearchRange& range, double threshold, QueryCounters* counters) {
  PassOutcome out;
  detail::RawHit hit;
  if (!first_in_range<kCount>(index, ray, range, &hit, counters)) return out;
  out.found = true;
  out.point = index.position(hit.sorted).cast<double>();
  if (options.refine_plane_intersection) {
    detail::Neighbourhood neighbours;
    detail::gather_neighbourhood(index, hit.voxel, &neighbours);
    const std::optional<Eigen::Vector3d> x =
        detail::plane_circle_intersection(neighbours, ray.origin, ray.direction, options.min_planarity);
    if (x) {
      out.point = *x;
      out.refined = true;
    }
  }
  // In-view test (decision 3): perpendicular distance of the point to the ray line.
  const Eigen::Vector3d w = out.point - ray.origin;
  const double perpendicular = (w - w.dot(ray.direction) * ray.direction).norm();
  out.accepted = perpendicular <= threshold;
  return out;
}

template <bool kCount>
QueryResult run_query(const std::vector<detail::LevelIndex>& levels, const VoxelMap& map,
                      const QueryOptions& options, const RayQuery& ray, QueryCounters* counters) {
  QueryResult result;
  if constexpr (kCount) ++counters->rays;
  PreparedRay prepared;
  if (!prepare_ray(ray.origin, ray.direction, &prepared) || !std::isfinite(ray.initial_distance) ||
      !(ray.initial_distance >= 0.0f) || !std::isfinite(ray.resolution)) {
    result.status = QueryStatus::kInvalidRay;
    return result;
  }
  const int level = map.level_of(static_cast<double>(ray.resolution));
  if (level < 0 || static_cast<std::size_t>(level) >= levels.size()) {
    result.status = QueryStatus::kUnknownResolution;
    return result;
  }
  result.level = static_cast<std::int8_t>(level);
  const detail::LevelIndex& index = levels[static_cast<std::size_t>(level)];
  const double d = ray.initial_distance;
  const double r0 = options.search_range_m;
  const double threshold = index.resolution() + options.threshold_offset_px * d / options.focal_length_px;

  // Pass 1 with R0; pass 2 with 2/3 R0 after a rejected hit, 1.5 R0 after a miss (2.4). After
  // a miss, pass 2 does not traverse pass 1's (empty) range again.
  const SearchRange first_range = range_around(d, r0);
  PassOutcome pass = run_pass<kCount>(index, options, prepared, first_range, threshold, counters);
  result.passes = 1;
  if (!pass.accepted) {
    const bool first_found = pass.found;
    const PassOutcome first = pass;
    SearchRange second = range_around(d, first_found ? r0 * (2.0 / 3.0) : r0 * 1.5);
    if (!first_found) {
      second.skip_start = first_range.t_start;
      second.skip_end = first_range.t_end;
    }
    pass = run_pass<kCount>(index, options, prepared, second, threshold, counters);
    result.passes = 2;
    if (!pass.found && first_found) pass = first;  // report the rejected point of pass 1
  }
  if (pass.accepted) {
    result.status = QueryStatus::kHit;
  } else {
    result.status = pass.found ? QueryStatus::kRejected : QueryStatus::kMiss;
  }
  if (pass.found) {
    result.point = pass.point.cast<float>();
    result.refined = pass.refined;
    if constexpr (kCount) counters->refined += pass.refined ? 1 : 0;
  }
  return result;
}

}  // namespace

StatusOr<QueryEngine> QueryEngine::create(std::shared_ptr<const VoxelMap> map, const QueryOptions& options) {
  if (map == nullptr) return absl::InvalidArgumentError("QueryEngine::create: the voxel map is null");
  const Status valid = config::validate_options(options);
  if (!valid.ok()) {
    return absl::InvalidArgumentError(fmt::format("query options: {}", std::string(valid.message())));
  }
  MRVS_RETURN_IF_ERROR(check_levels(*map));
  auto impl = std::make_shared<Impl>();
  impl->options = options;
  impl->levels.reserve(map->levels.size());
  for (std::size_t i = 0; i < map->levels.size(); ++i) {
    MRVS_ASSIGN_OR_RETURN(detail::LevelIndex index,
                          detail::LevelIndex::build(map->levels[i], static_cast<int>(i)));
    impl->levels.push_back(std::move(index));
  }
  impl->map = std::move(map);
  QueryEngine engine;
  engine.impl_ = std::move(impl);
  return engine;
}

QueryResult QueryEngine::query(const RayQuery& ray) const {
  if (impl_ == nullptr) return QueryResult{QueryStatus::kUnknownResolution};
  return run_query<false>(impl_->levels, *impl_->map, impl_->options, ray, nullptr);
}

QueryResult QueryEngine::query(const RayQuery& ray, QueryCounters* counters) const {
  if (impl_ == nullptr) return QueryResult{QueryStatus::kUnknownResolution};
  if (counters == nullptr) return query(ray);
  return run_query<true>(impl_->levels, *impl_->map, impl_->options, ray, counters);
}

std::optional<VoxelHit> QueryEngine::first_hit(int level, const Eigen::Vector3f& origin,
                                               const Eigen::Vector3f& direction, float t_start,
                                               float t_end) const {
  if (impl_ == nullptr || level < 0 || static_cast<std::size_t>(level) >= impl_->levels.size())
    return std::nullopt;
  PreparedRay ray;
  if (!prepare_ray(origin, direction, &ray) || !std::isfinite(t_start) || !std::isfinite(t_end) ||
      !(t_start <= t_end)) {
    return std::nullopt;
  }
  const detail::LevelIndex& index = impl_->levels[static_cast<std::size_t>(level)];
  detail::RawHit hit;
  if (!detail::first_occupied<false>(index, ray.origin, ray.direction, t_start, t_end, &hit, nullptr)) {
    return std::nullopt;
  }
  return VoxelHit{index.original_index(hit.sorted), static_cast<float>(hit.t_entry)};
}

std::optional<Eigen::Vector3f> QueryEngine::surface_normal(int level, const Eigen::Vector3f& point) const {
  if (impl_ == nullptr || level < 0 || static_cast<std::size_t>(level) >= impl_->levels.size() ||
      !point.allFinite())
    return std::nullopt;
  const QueryOptions& o = impl_->options;
  const detail::LevelIndex& index = impl_->levels[static_cast<std::size_t>(level)];
  // At most kNormalHalfWidthVoxels voxels around the hit: (2 k + 1)^3 lookups per hit.
  const double radius = std::min(o.normal_radius_m, kNormalHalfWidthVoxels * index.resolution());
  std::vector<Eigen::Vector3d> near;
  detail::gather_ball(index, point.cast<double>(), radius, &near);
  if (static_cast<int>(near.size()) < o.normal_min_points) return std::nullopt;
  const std::optional<PlaneFit> fit = fit_plane(near);
  if (!fit || fit->rms_m > o.normal_max_rms_m || fit->extent_m < o.normal_min_extent * radius)
    return std::nullopt;
  return fit->normal.cast<float>();
}

const VoxelMap& QueryEngine::map() const {
  static const VoxelMap kEmpty;
  return impl_ != nullptr ? *impl_->map : kEmpty;
}

const QueryOptions& QueryEngine::options() const {
  static const QueryOptions kDefaults;
  return impl_ != nullptr ? impl_->options : kDefaults;
}

std::size_t QueryEngine::index_memory_bytes() const {
  if (impl_ == nullptr) return 0;
  std::size_t bytes = 0;
  for (const detail::LevelIndex& level : impl_->levels) bytes += level.memory_bytes();
  return bytes;
}

}  // namespace mrvs::map
