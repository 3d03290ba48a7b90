#pragma once
// The offline multi-resolution voxel map builder (paper section III-A; algorithm.md 1.3):
//
// 1. origin: the bounding-box minimum of the raw cloud floored to a multiple of
//    origin_rounding_m (default whole metres) per axis, so map-local coordinates are small,
//    non-negative and the origin is a round number (UTM clouds keep sub-mm precision in the
//    float32 local positions);
// 2. saliency of every raw point (saliency.h) on the map-local positions;
// 3. finest level: per voxel the raw point of maximum saliency (ties: lowest raw index);
// 4. every coarser level: per coarse voxel the maximum-saliency point among the FINEST-level
//    representatives inside it (ties: lowest raw index), copied bit for bit, so every coarse
//    point is a fine point, also for non-nested grids (0.02 / 0.03).
// Voxels are assigned from the stored float32 local positions (voxel_of in voxel_map.h).
// Points of each level are sorted by their packed voxel key. Deterministic for any thread count.
#include <cstdint>
#include <string>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/map/point_cloud_io.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::map {

/// Section `builder` of config/map_indoor.yaml / map_outdoor.yaml.
struct MapBuilderOptions : config::OptionsEquality<MapBuilderOptions> {
  std::vector<double> levels = {0.01, 0.02, 0.03};  ///< voxel sizes, metres (any order, distinct)
  int knn = 16;                                     ///< K nearest neighbours of the saliency
  double alpha = 1.0;                               ///< normal (depth-edge) weight of the saliency
  double min_neighbour_distance_m = 1e-6;           ///< closer neighbours are skipped, metres
  double origin_rounding_m = 1.0;                   ///< origin = floor(bbox min / this) * this, metres
  int threads = 0;                                  ///< OpenMP threads, 0 = all (output independent of it)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("levels", levels, each_in_range(0.001, 100.0).size(1, 16),
      "voxel sizes, m (distinct; sorted finest first)");
    v("knn", knn, in_range(1, 256), "K nearest neighbours per point for normal and saliency");
    v("alpha", alpha, in_range(0.0, 1000.0), "weight of the normal (depth-edge) term of the saliency");
    v("min_neighbour_distance_m", min_neighbour_distance_m, in_range(0.0, 1.0),
      "neighbours closer than this are skipped, m");
    v("origin_rounding_m", origin_rounding_m, in_range(0.001, 100000.0),
      "map origin = bounding-box minimum floored to a multiple of this, m");
    v("threads", threads, in_range(0, 1024), "OpenMP threads, 0 = all cores");
  }
};

/// One level of a BuildReport.
struct LevelReport {
  double resolution = 0.0;  ///< metres
  std::uint64_t points = 0;
};

/// What a build did and cost.
struct BuildReport {
  std::uint64_t raw_points = 0;
  std::vector<LevelReport> levels;      ///< finest first
  Vec3d origin = Vec3d::Zero();         ///< metres
  double seconds_saliency = 0.0;        ///< kd-tree, normals and saliency
  double seconds_levels = 0.0;          ///< voxel selection of all levels
  double seconds_total = 0.0;           ///< whole build_voxel_map call
  std::uint64_t peak_memory_bytes = 0;  ///< process peak resident set (getrusage ru_maxrss) after the build
  std::uint64_t map_points = 0;         ///< over all levels
  std::uint64_t map_bytes = 0;          ///< size of the .mrvm file of the map
  std::uint64_t raw_bytes = 0;          ///< raw cloud as x, y, z double + float intensity (28 B per point)
  double saliency_min = 0.0;            ///< over the raw points
  double saliency_max = 0.0;
  double saliency_mean = 0.0;

  /// Multi-line human-readable summary (one line per level).
  std::string summary() const;
};

/// Sorted (finest first) copy of `levels`; error when one is not finite and positive or two are
/// equal (within a relative 1e-9).
StatusOr<std::vector<double>> sorted_levels(const std::vector<double>& levels);

/// The map origin of a cloud: bounding-box minimum floored to a multiple of `rounding_m`.
StatusOr<Vec3d> map_origin(const std::vector<Vec3d>& positions, double rounding_m);

/// Builds the map (see the file comment). `report` (optional) receives counts, timings, peak
/// memory and compression. Errors: empty cloud, size mismatch, invalid options (validated like
/// the config file), a cloud too large for the finest resolution (voxel indices must fit in 21
/// bits per axis, mrvs::voxel::kMaxIndex), a cloud beyond float32 range from the origin.
StatusOr<VoxelMap> build_voxel_map(const RawCloud& cloud, const MapBuilderOptions& options,
                                   BuildReport* report = nullptr);

/// Peak resident set size of this process so far, bytes (getrusage ru_maxrss).
std::uint64_t peak_memory_bytes();

}  // namespace mrvs::map
