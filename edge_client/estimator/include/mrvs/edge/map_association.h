#pragma once
// Association of features with the cloud's voxel map (algorithm.md sections 2 and 7,
// decisions 3-5): one ray per feature from the camera of its newest observation through that
// pixel, starting near the triangulated distance, at the level whose voxel matches the
// pixel footprint there; the hit is checked on the edge against the feature's other
// observations (multi-view consistency), the in-view test having run on the cloud.
#include <optional>
#include <string>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/feature_measurement.h"
#include "mrvs/edge/map_service.h"
#include "mrvs/edge/state.h"
#include "mrvs/io/types.h"

namespace mrvs::edge {

struct MapOptions : config::OptionsEquality<MapOptions> {
  bool enabled = true;              ///< false: plain VIO (the edge_client --no-map switch)
  double fixed_resolution_m = 0.0;  ///< > 0: every ray asks this level (ablation); 0: multi-resolution
  double footprint_scale = 1.0;     ///< level for scale * depth / f (1: the paper's r* = argmin |r - d/f|)
  /// > 0: multi-resolution never asks a level finer than this many standard deviations of
  /// where the ray meets the map (the query clone's covariance across the ray).
  double uncertainty_scale = 0.0;
  /// Multi-resolution never asks a level finer than this, m (0: any). A level whose voxels
  /// are finer than about twice the survey's point spacing has holes and noisy planes.
  double min_resolution_m = 0.0;
  /// Known landmarks (stage 1 and registered points): add the query pose's uncertainty across
  /// the ray to the map point's covariance (the hit lies where the estimated ray met the map).
  bool association_noise = false;
  std::string stage1_mode =
      "known_landmark";  ///< known_landmark | msckf_nullspace (the reference code) | ray_depth | plane
  /// stage1_mode plane: the surface plane around a hit, fitted to the map points the cloud
  /// has answered (SurfaceMap): within this radius, at least plane_min_points, at most
  /// plane_max_rms_m rough.
  double plane_radius_m = 0.5;
  int plane_min_points = 6;
  double plane_max_rms_m = 0.05;
  /// Plane mode: ask the cloud for the surface normal at each hit (6 more bytes per hit, wire
  /// protocol 2) and use it instead of fitting the answered points.
  bool cloud_normals = false;
  std::string query_pose_source = "estimated";  ///< estimated | gt (the paper's "w/ GT" rows)
  int max_stage1_features = 100;                ///< co-visible features queried per frame
  int max_rays_per_frame = 200;                 ///< stage 1 and registration together
  double threshold_offset_px = 0.5;             ///< multi-view check: r f / z + offset - 0.5 ...
  double threshold_lower_px = 2.0;              ///< ... clamped to [lower, upper] px
  double threshold_upper_px = 3.0;
  double max_hit_distance_m = 0.15;      ///< a hit further from the triangulated point is refused
  double drop_unmatched_hit_rate = 0.7;  ///< at this hit rate unmatched features leave stage 1 (> 1: never)
  double map_sigma_m = 0.005;            ///< map point noise (plus voxel_sigma_factor * r), m
  double voxel_sigma_factor = 0.5;       ///< of the voxel size r
  double query_timeout_ms = 15.0;        ///< per request, within the frame's deadline
  double frame_budget_ms = 45.0;         ///< the frame never blocks on the cloud past this, ms
  bool register_new_features = true;     ///< query the frame's new features after the update (stage 2)
  bool points_from_tracks = false;       ///< with the map: also triangulated points in the state
  double registered_voxel_m = 0.3;       ///< registered-point grid (0.3 indoor, 1.0 outdoor)
  int registered_per_voxel = 5;
  int registered_neighbourhood = 2;  ///< voxels around a tracked point that make points suitable

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("enabled", enabled, any(), "use the cloud map (false: plain VIO)");
    v("fixed_resolution_m", fixed_resolution_m, in_range(0.0, 10.0),
      "ask this level only (0: multi-resolution), m");
    v("footprint_scale", footprint_scale, in_range(0.1, 100.0), "multi-resolution: level for scale * d / f");
    v("uncertainty_scale", uncertainty_scale, in_range(0.0, 100.0),
      "multi-resolution: level at least this many sigma of the hit across the ray (0: off)");
    v("min_resolution_m", min_resolution_m, in_range(0.0, 10.0),
      "multi-resolution: never a level finer than this, m (0: any)");
    v("association_noise", association_noise, any(),
      "known landmarks: add the query pose's uncertainty across the ray to the map noise");
    v("stage1_mode", stage1_mode, one_of({"known_landmark", "msckf_nullspace", "ray_depth", "plane"}),
      "stage-1 use of map points");
    v("plane_radius_m", plane_radius_m, in_range(0.01, 100.0), "plane mode: surface fit radius, m");
    v("plane_min_points", plane_min_points, in_range(3, 10000), "plane mode: map points a plane needs");
    v("plane_max_rms_m", plane_max_rms_m, in_range(0.0, 10.0), "plane mode: roughest surface fitted, m");
    v("cloud_normals", cloud_normals, any(), "plane mode: surface normals from the cloud");
    v("query_pose_source", query_pose_source, one_of({"estimated", "gt"}), "poses the rays are formed from");
    v("max_stage1_features", max_stage1_features, in_range(0, 256), "features queried in stage 1 per frame");
    v("max_rays_per_frame", max_rays_per_frame, in_range(0, 256), "rays per frame");
    v("threshold_offset_px", threshold_offset_px, in_range(0.0, 100.0), "multi-view threshold offset, px");
    v("threshold_lower_px", threshold_lower_px, in_range(0.0, 100.0), "multi-view threshold lower clamp, px");
    v("threshold_upper_px", threshold_upper_px, in_range(0.0, 100.0), "multi-view threshold upper clamp, px");
    v("max_hit_distance_m", max_hit_distance_m, in_range(0.0, 100.0), "hit to triangulated point, m");
    v("drop_unmatched_hit_rate", drop_unmatched_hit_rate, in_range(0.0, 2.0),
      "hit rate dropping the unmatched");
    v("map_sigma_m", map_sigma_m, in_range(0.0, 10.0), "map point noise, m");
    v("voxel_sigma_factor", voxel_sigma_factor, in_range(0.0, 10.0), "noise per voxel size");
    v("query_timeout_ms", query_timeout_ms, in_range(0.1, 10000.0), "wait per request, ms");
    v("frame_budget_ms", frame_budget_ms, in_range(0.1, 10000.0), "cloud wait per frame at most, ms");
    v("register_new_features", register_new_features, any(), "query new features and register the hits");
    v("points_from_tracks", points_from_tracks, any(), "also triangulated points in the state");
    v("registered_voxel_m", registered_voxel_m, in_range(0.01, 100.0), "registered-point voxel size, m");
    v("registered_per_voxel", registered_per_voxel, in_range(1, 1000), "registered points per voxel");
    v("registered_neighbourhood", registered_neighbourhood, in_range(0, 10),
      "neighbourhood of suitable points, voxels");
  }
};

/// One ray with what the edge needs to judge its answer.
struct FeatureRay {
  FeatureId id = 0;
  voxel::RayQuery ray;          ///< map-local
  Vec3d p_tri = Vec3d::Zero();  ///< triangulated position, world (map frame)
  TimestampNs t_ns = 0;         ///< the observation the ray goes through
  int cam = 0;
  double depth_m = 0.0;  ///< of p_tri in that camera
  double focal_px = 0.0;
};

/// The camera pose of observation (t_ns, cam) used to form rays: the state's, or the ground
/// truth's (query_pose_source gt, interpolated). nullopt when unavailable.
std::optional<SE3d> query_camera_pose(const State& state, const io::Trajectory& groundtruth,
                                      const MapOptions& options, TimestampNs t_ns, int cam);

/// The ray of `track` (its newest cam0 observation at a clone) towards `p_tri`; nullopt when
/// the point is behind that camera or the level cannot be chosen.
std::optional<FeatureRay> make_feature_ray(const State& state, const io::Trajectory& groundtruth,
                                           const FeatureTrack& track, const Vec3d& p_tri,
                                           const MapDescription& map, const MapOptions& options);

/// The multi-view check of a hit X (world): mean pixel error over the feature's other
/// observations at clones (all cameras) against r f / z + offset - 0.5 clamped to
/// [lower, upper]. `mean_error_px` (optional) receives the error; no other view: refused.
bool accept_hit(const State& state, const io::Trajectory& groundtruth, const FeatureTrack& track,
                const FeatureRay& ray, const Vec3d& X, const MapOptions& options,
                double* mean_error_px = nullptr);

/// Isotropic variance of a map point of level r (m^2).
/// Covariance (m^2) of where the ray of the anchor's camera through its point meets the map,
/// across the ray, from the covariance of the anchor clone (and extrinsics); zero when the
/// clone is gone. hit_sigma_across: its largest standard deviation.
Mat3d hit_covariance_across(const State& state, const RayAnchor& anchor);
double hit_sigma_across(const State& state, const RayAnchor& anchor);

/// The hit X as a point of the ray's camera: its depth there, the direction of the
/// observation the ray went through (estimated clone pose); nullopt when X is behind it.
std::optional<RayAnchor> ray_anchor(const State& state, const FeatureTrack& track, const FeatureRay& ray,
                                    const Vec3d& X);

inline double map_point_variance(const MapOptions& o, double r) {
  const double s = o.voxel_sigma_factor * r;
  return o.map_sigma_m * o.map_sigma_m + s * s;
}

}  // namespace mrvs::edge
