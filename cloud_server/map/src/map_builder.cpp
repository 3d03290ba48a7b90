#include "mrvs/map/map_builder.h"

#include <sys/resource.h>

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "mrvs/map/map_file.h"
#include "mrvs/map/saliency.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// Key value that pack() never produces (its top bit is always 0): "not packable".
constexpr std::uint64_t kBadKey = std::numeric_limits<std::uint64_t>::max();

/// A point competing for its voxel.
struct Candidate {
  std::uint64_t key = 0;     ///< packed voxel index at the level being built
  float saliency = 0.0f;     ///< S of the point
  std::uint64_t raw = 0;     ///< raw index (tie-break: lowest wins)
  std::uint64_t source = 0;  ///< index into the candidate list's point array
};

Status extent_error(const std::vector<Eigen::Vector3f>& positions, std::size_t i, double r,
                    const Vec3d& origin) {
  const Eigen::Vector3f& p = positions[i];
  const double limit_m = r * static_cast<double>(voxel::kMaxIndex);
  return absl::InvalidArgumentError(fmt::format(
      "the map extent is too large for resolution {} m: point ({:.3f}, {:.3f}, {:.3f}) is ({:.3f}, {:.3f}, "
      "{:.3f}) m from the map origin ({:.3f}, {:.3f}, {:.3f}), but voxel indices must stay within +-{} "
      "voxels "
      "(+-{:.1f} m at this resolution); use a coarser finest level or split the cloud into tiles",
      r, static_cast<double>(p.x()) + origin.x(), static_cast<double>(p.y()) + origin.y(),
      static_cast<double>(p.z()) + origin.z(), p.x(), p.y(), p.z(), origin.x(), origin.y(), origin.z(),
      voxel::kMaxIndex, limit_m));
}

/// Winner per voxel: highest saliency, then lowest raw index. Sorted by key; compacted in place.
void select_per_voxel(std::vector<Candidate>& candidates) {
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    if (a.key != b.key) return a.key < b.key;
    if (a.saliency != b.saliency) return a.saliency > b.saliency;
    return a.raw < b.raw;
  });
  std::size_t kept = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (i == 0 || candidates[i].key != candidates[i - 1].key) candidates[kept++] = candidates[i];
  }
  candidates.resize(kept);
}

/// One built level plus the raw index of each of its points.
struct BuiltLevel {
  MapLevel level;
  std::vector<std::uint64_t> raw_index;
};

StatusOr<BuiltLevel> build_level(const std::vector<Eigen::Vector3f>& positions,
                                 const std::vector<float>& intensities, const std::vector<float>& saliency,
                                 const std::vector<std::uint64_t>& raw_index, double r, const Vec3d& origin,
                                 int threads) {
  std::vector<Candidate> candidates(positions.size());
  const auto n = static_cast<std::int64_t>(positions.size());
#pragma omp parallel for num_threads(threads) schedule(static)
  for (std::int64_t i = 0; i < n; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const auto index = voxel_of(positions[u], r);
    candidates[u] = Candidate{index ? voxel::pack(*index) : kBadKey, saliency[u], raw_index[u], u};
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (candidates[i].key == kBadKey) return extent_error(positions, i, r, origin);
  }
  select_per_voxel(candidates);
  BuiltLevel out;
  out.level.resolution = r;
  out.level.points.reserve(candidates.size());
  out.raw_index.reserve(candidates.size());
  for (const Candidate& c : candidates) {
    const auto s = static_cast<std::size_t>(c.source);
    out.level.points.push_back(MapPoint{positions[s], intensities[s], saliency[s]});
    out.raw_index.push_back(c.raw);
  }
  return out;
}

/// Map-local float positions of the raw cloud.
StatusOr<std::vector<Eigen::Vector3f>> local_positions(const RawCloud& cloud, const Vec3d& origin) {
  std::vector<Eigen::Vector3f> local(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    local[i] = (cloud.positions[i] - origin).cast<float>();
    if (!local[i].allFinite()) {
      return absl::InvalidArgumentError(
          fmt::format("map builder: raw point {} is not finite relative to the origin", i));
    }
  }
  return local;
}

Status check_cloud(const RawCloud& cloud) {
  const std::string name = cloud.source.empty() ? "<in-memory cloud>" : cloud.source;
  if (cloud.positions.empty())
    return absl::InvalidArgumentError(fmt::format("map builder: {} has no point", name));
  if (cloud.positions.size() != cloud.intensities.size()) {
    return absl::InvalidArgumentError(fmt::format("map builder: {} has {} positions but {} intensities", name,
                                                  cloud.positions.size(), cloud.intensities.size()));
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.positions[i].allFinite() || !std::isfinite(cloud.intensities[i])) {
      return absl::InvalidArgumentError(fmt::format("map builder: point {} of {} is not finite", i, name));
    }
  }
  return absl::OkStatus();
}

std::string describe(const RawCloud& cloud, const MapBuilderOptions& options,
                     const std::vector<double>& levels) {
  return fmt::format(
      "mrvs map_builder; source: {}; intensity: {}; raw points: {}; levels: [{}] m; knn: {}; alpha: {}; "
      "min_neighbour_distance_m: {}; origin: bounding-box minimum floored to {} m",
      cloud.source.empty() ? "<in-memory cloud>" : cloud.source,
      cloud.intensity_field.empty() ? "intensity" : cloud.intensity_field, cloud.size(),
      fmt::join(levels, ", "), options.knn, options.alpha, options.min_neighbour_distance_m,
      options.origin_rounding_m);
}

void fill_report(const VoxelMap& map, const std::vector<float>& saliency, BuildReport& report) {
  report.raw_points = map.raw_point_count;
  report.origin = map.origin;
  report.levels.clear();
  for (const MapLevel& level : map.levels) report.levels.push_back({level.resolution, level.points.size()});
  report.map_points = map.point_count();
  report.map_bytes = map_file_size(map);
  report.raw_bytes = map.raw_point_count * (3 * sizeof(double) + sizeof(float));
  double sum = 0.0;
  report.saliency_min = std::numeric_limits<double>::infinity();
  report.saliency_max = 0.0;
  for (const float s : saliency) {
    sum += s;
    report.saliency_min = std::min(report.saliency_min, static_cast<double>(s));
    report.saliency_max = std::max(report.saliency_max, static_cast<double>(s));
  }
  report.saliency_mean = saliency.empty() ? 0.0 : sum / static_cast<double>(saliency.size());
  report.peak_memory_bytes = peak_memory_bytes();
}

}  // namespace

StatusOr<std::vector<double>> sorted_levels(const std::vector<double>& levels) {
  if (levels.empty()) return absl::InvalidArgumentError("builder.levels: no resolution given");
  std::vector<double> sorted = levels;
  for (const double r : sorted) {
    if (!std::isfinite(r) || !(r > 0.0)) {
      return absl::InvalidArgumentError(
          fmt::format("builder.levels: resolution {} is not a positive number", r));
    }
  }
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 1; i < sorted.size(); ++i) {
    if (sorted[i] - sorted[i - 1] <= 1e-9 * sorted[i]) {
      return absl::InvalidArgumentError(
          fmt::format("builder.levels: resolution {} is given twice; levels must be distinct", sorted[i]));
    }
  }
  return sorted;
}

StatusOr<Vec3d> map_origin(const std::vector<Vec3d>& positions, double rounding_m) {
  if (positions.empty()) return absl::InvalidArgumentError("map origin: no point");
  if (!std::isfinite(rounding_m) || !(rounding_m > 0.0)) {
    return absl::InvalidArgumentError(fmt::format("map origin: rounding {} m must be positive", rounding_m));
  }
  Vec3d lo = positions.front();
  for (const Vec3d& p : positions) lo = lo.cwiseMin(p);
  Vec3d origin;
  for (int k = 0; k < 3; ++k) origin[k] = std::floor(lo[k] / rounding_m) * rounding_m;
  if (!origin.allFinite()) return absl::InvalidArgumentError("map origin: the cloud is not finite");
  return origin;
}

StatusOr<VoxelMap> build_voxel_map(const RawCloud& cloud, const MapBuilderOptions& options,
                                   BuildReport* report) {
  const Clock::time_point t0 = Clock::now();
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "builder"));
  MRVS_RETURN_IF_ERROR(check_cloud(cloud));
  MRVS_ASSIGN_OR_RETURN(const std::vector<double> levels, sorted_levels(options.levels));
  const int threads = options.threads > 0 ? options.threads : omp_get_max_threads();
  VoxelMap map;
  MRVS_ASSIGN_OR_RETURN(map.origin, map_origin(cloud.positions, options.origin_rounding_m));
  MRVS_ASSIGN_OR_RETURN(const std::vector<Eigen::Vector3f> local, local_positions(cloud, map.origin));
  // The extent check of the finest level runs before the (long) saliency computation.
  for (std::size_t i = 0; i < local.size(); ++i) {
    if (!voxel_of(local[i], levels.front())) return extent_error(local, i, levels.front(), map.origin);
  }
  spdlog::debug("map builder: origin and local positions ready; peak memory {} MiB",
                peak_memory_bytes() >> 20);
  const Clock::time_point t_saliency = Clock::now();
  SaliencyOptions saliency_options{options.knn, options.alpha, options.min_neighbour_distance_m, threads};
  MRVS_ASSIGN_OR_RETURN(const std::vector<float> saliency,
                        compute_saliency(local, cloud.intensities, saliency_options));
  const double seconds_saliency = seconds_since(t_saliency);
  spdlog::debug("map builder: saliency done in {:.2f} s; peak memory {} MiB", seconds_saliency,
                peak_memory_bytes() >> 20);

  const Clock::time_point t_levels = Clock::now();
  std::vector<std::uint64_t> raw_index(local.size());
  for (std::size_t i = 0; i < raw_index.size(); ++i) raw_index[i] = i;
  MRVS_ASSIGN_OR_RETURN(BuiltLevel finest, build_level(local, cloud.intensities, saliency, raw_index,
                                                       levels.front(), map.origin, threads));
  // Coarser levels choose among the finest representatives only.
  std::vector<Eigen::Vector3f> fine_positions;
  std::vector<float> fine_intensities;
  std::vector<float> fine_saliency;
  for (const MapPoint& p : finest.level.points) {
    fine_positions.push_back(p.position);
    fine_intensities.push_back(p.intensity);
    fine_saliency.push_back(p.saliency);
  }
  map.levels.push_back(std::move(finest.level));
  for (std::size_t l = 1; l < levels.size(); ++l) {
    MRVS_ASSIGN_OR_RETURN(BuiltLevel coarse, build_level(fine_positions, fine_intensities, fine_saliency,
                                                         finest.raw_index, levels[l], map.origin, threads));
    map.levels.push_back(std::move(coarse.level));
  }
  map.raw_point_count = cloud.size();
  map.description = describe(cloud, options, levels);
  if (report != nullptr) {
    report->seconds_saliency = seconds_saliency;
    report->seconds_levels = seconds_since(t_levels);
    fill_report(map, saliency, *report);
    report->seconds_total = seconds_since(t0);
  }
  return map;
}

std::uint64_t peak_memory_bytes() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0;
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024;  // Linux: kilobytes
}

std::string BuildReport::summary() const {
  std::string out = fmt::format("raw points: {}; origin: ({:.3f}, {:.3f}, {:.3f}) m\n", raw_points,
                                origin.x(), origin.y(), origin.z());
  for (std::size_t l = 0; l < levels.size(); ++l) {
    out += fmt::format("level {}: resolution {} m: {} points ({:.2f} % of the raw cloud)\n", l,
                       levels[l].resolution, levels[l].points,
                       raw_points > 0
                           ? 100.0 * static_cast<double>(levels[l].points) / static_cast<double>(raw_points)
                           : 0.0);
  }
  out += fmt::format("saliency: min {:.4g}, mean {:.4g}, max {:.4g}\n", saliency_min, saliency_mean,
                     saliency_max);
  out += fmt::format("time: saliency {:.2f} s, levels {:.2f} s, total {:.2f} s; peak memory {:.1f} MiB\n",
                     seconds_saliency, seconds_levels, seconds_total,
                     static_cast<double>(peak_memory_bytes) / (1024.0 * 1024.0));
  out += fmt::format(
      "compression: {} map points / {} raw points; {} map bytes / {} raw bytes ({:.2f} %)", map_points,
      raw_points, map_bytes, raw_bytes,
      raw_bytes > 0 ? 100.0 * static_cast<double>(map_bytes) / static_cast<double>(raw_bytes) : 0.0);
  return out;
}

}  // namespace mrvs::map
