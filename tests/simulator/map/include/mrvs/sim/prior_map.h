#pragma once
// The synthetic "survey LiDAR" prior map (simulator.md section 5): every in-map face of the
// scene is covered by a stratified jittered grid (one uniform sample per cell); a sample is
// kept only if a survey station sees it (the nearest that does); then intensity, position
// noise, holes and a global misalignment are applied. Deterministic by seed and independent
// of the thread count. Two models (map.model):
// - surface: the spacing grows with the tile's distance to the trajectory (spacing_*), the
//   position noise is along the face normal and axes;
// - scanner: a terrestrial laser scanner at each station, its scans merged as a registered
//   survey is: a tile gets the spacing the densest station's angular lattice gives there,
//   r * scan_step / sqrt(cos(incidence)) (the same area per return), clamped to
//   [scan_min_spacing_m, spacing_far_m]; a station returns from a sample only above
//   scan_min_elevation_deg and, beyond dropout_start_deg of incidence, with a probability
//   falling linearly to 0 at dropout_full_deg (then the next nearest station that sees it
//   may); the range noise, sigma = range_noise_m + range_noise_per_m * r, is along that
//   station's ray; occlusion shadows are the stations' visibility.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/geometry/types.h"
#include "mrvs/sim/map_options.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim {

/// One map point. The PLY file holds x, y, z and intensity; `face` is for tests and tools.
struct MapPoint {
  Eigen::Vector3f position = Eigen::Vector3f::Zero();  ///< metres (frame: see PriorMap)
  float intensity = 0.0f;                              ///< in [0, 1]
  std::int32_t face = -1;                              ///< Face::id it was sampled on (-1: unknown)
};

/// A virtual terrestrial scanner position.
struct SurveyStation {
  Vec3d position_w = Vec3d::Zero();  ///< metres, world
  bool used = true;                  ///< false: inside a box or outside the room, sees nothing
};

/// Bookkeeping of one sample_prior_map run.
struct MapCounts {
  std::int64_t tiles = 0;         ///< sampling tiles on in-map faces
  std::int64_t samples = 0;       ///< jittered-grid samples drawn (one per cell)
  std::int64_t visible = 0;       ///< samples seen by at least one station
  std::int64_t hole_removed = 0;  ///< visible samples removed by holes
  std::int64_t points = 0;        ///< points in the map (visible - hole_removed)
  double in_map_area_m2 = 0.0;    ///< total area of the in-map faces, m^2
  double visible_area_m2 = 0.0;   ///< visible samples x their cell areas (before holes), m^2
  double hole_area_m2 = 0.0;      ///< part of visible_area_m2 removed by holes, m^2
  int stations_used = 0;          ///< stations that can see anything
};

/// The prior map and its ground truth.
struct PriorMap {
  /// What goes into pointcloud0/data.ply: noisy, misaligned, map frame (p_map = T_map_world p_w).
  std::vector<MapPoint> points;
  /// Same points in the same order without position noise, misalignment or intensity
  /// noise (intensity = the model applied to the albedo, clipped): world frame.
  std::vector<MapPoint> clean_points;
  /// The misalignment: rotation exp(misalignment_deg x random axis), translation
  /// misalignment_m x random direction (identity by default); p_map = T_map_world * p_world.
  SE3d T_map_world;
  std::vector<SurveyStation> stations;  ///< survey stations, world
  MapCounts counts;
};

/// Survey stations for `trajectory_w` (positions, world, metres): options.num_stations (or
/// one per station_spacing_m of path length) at equal path-length intervals, centred (station
/// k at (k + 0.5) / N of the path), at (x, y) of the trajectory and z = station_height_m.
/// A station inside a closed object (box) or outside an indoor room is marked unused.
StatusOr<std::vector<SurveyStation>> survey_stations(const Scene& scene,
                                                     const std::vector<Vec3d>& trajectory_w,
                                                     const MapOptions& options);

/// The first and last positions of `path` and every one at least `step` from the last kept.
std::vector<Vec3d> thin_path(const std::vector<Vec3d>& path, double step);
/// Distance from p to the nearest position of `path` (infinity for an empty path).
double distance_to_path(const std::vector<Vec3d>& path, const Vec3d& p);

/// Sample spacing (metres) of a tile whose centre is `distance_m` from the nearest trajectory
/// sample and at height `height_m`: clamp(s_near * d / d_near, s_near, s_far), or s_far above
/// far_above_z_m when that is > 0.
double tile_spacing(const MapOptions& options, double distance_m, double height_m);

/// Map intensity before noise and clipping for albedo `albedo` seen at `cos_incidence`
/// (cosine between the face normal and the direction to the scanning station).
double model_intensity(const MapOptions& options, double albedo, double cos_incidence);

/// Samples the prior map of `scene` seen along `trajectory_w` (positions, world, metres;
/// e.g. the ground-truth body positions). Errors: empty trajectory, invalid options, or a
/// map that would exceed 200 M samples. Randomness: Stream::kMapSampling (jitter, keyed by
/// face, tile, cell), kMapNoise (position and intensity noise, same keys), kMapHoles,
/// kMisalignment. OpenMP-parallel, identical output for any thread count.
StatusOr<PriorMap> sample_prior_map(const Scene& scene, const std::vector<Vec3d>& trajectory_w,
                                    const MapOptions& options, std::uint64_t seed);

/// T_map_world: rotation misalignment_deg about a random axis, translation misalignment_m
/// along a random direction (Stream::kMisalignment); identity when both are 0.
SE3d map_misalignment(const MapOptions& options, std::uint64_t seed);

}  // namespace mrvs::sim
