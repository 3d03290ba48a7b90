#pragma once
// The paper's use of the cloud map in one frame (section IV-E; algorithm.md decisions 3-5):
//   stage 1  the co-visible features about to update the filter are triangulated, one ray
//            each goes to the cloud, the hits are checked on the edge; accepted ones update
//            the filter as map points (MsckfUpdater::map_measurement);
//   stage 2  after the update the frame's new features are queried the same way and the
//            accepted hits registered into the state (and the registered-point grid), where
//            their 2-D tracks update them like any point.
// Every request waits at most until the frame's deadline; a frame without answers goes on
// as plain VIO.
#include <chrono>
#include <map>
#include <vector>

#include "mrvs/edge/map_association.h"
#include "mrvs/edge/msckf_updater.h"
#include "mrvs/edge/registered_map.h"
#include "mrvs/edge/surface_map.h"

namespace mrvs::edge {

/// Application payload on the wire: a ray, a hit's point, a hit's surface normal (bytes).
inline constexpr int kRayBytes = 32;
inline constexpr int kHitBytes = 12;
inline constexpr int kNormalBytes = 6;

/// What the map did in one frame.
struct MapFrameStats {
  bool available = false;  ///< the cloud's map description is known
  int requests = 0;
  int answered = 0;
  int timeouts = 0;  ///< requests without an answer in time
  int stage1_rays = 0;
  int stage1_hits = 0;
  int stage1_accepted = 0;
  int stage1_dropped = 0;  ///< unmatched features left out (hit-rate rule)
  int stage1_planes = 0;   ///< accepted points with a surface plane (stage1_mode plane)
  int registration_rays = 0;
  int registration_hits = 0;
  int registered = 0;
  double rtt_ms = 0.0;         ///< summed over the frame's requests
  std::size_t bytes_up = 0;    ///< application payload: 32 B per ray
  std::size_t bytes_down = 0;  ///< 12 B per hit (+ the hit bit)
  double selection_ms = 0.0;   ///< (d) registered map-point selection
  double ray_ms = 0.0;         ///< (e) ray forming, round trips and checks
};

class MapStage {
 public:
  using Clock = std::chrono::steady_clock;

  MapStage(const MapOptions& options, const TriangulationOptions& triangulation);

  /// Stage 1 on the MSCKF candidates `ids` (at most max_stage1_features, the most observed):
  /// the accepted map points; the unmatched ids are removed from `ids` when the frame's hit
  /// rate reaches drop_unmatched_hit_rate.
  /// `groundtruth` is only read for query_pose_source gt (here and in register_new).
  std::map<FeatureId, MapPoint> associate(const State& state, const FeatureDatabase& db,
                                          const io::Trajectory& groundtruth, std::vector<FeatureId>* ids,
                                          MapService& service, Clock::time_point deadline,
                                          MapFrameStats* stats, SurfaceMap* surfaces = nullptr) const;

  /// Stage 2 registration of the features first seen at clone t_ns (stereo pairs): accepted
  /// hits enter the state as points with the map's variance, while there is room in the
  /// state and in `grid`; returns their ids. `surfaces` is given in stage1_mode plane only:
  /// every hit (of either call) goes into it, associate() gives stage 1's points their
  /// surface plane from it, and register_new() registers only hits with a plane.
  std::vector<FeatureId> register_new(State& state, const FeatureDatabase& db,
                                      const io::Trajectory& groundtruth, TimestampNs t_ns,
                                      RegisteredMap* grid, MapService& service, Clock::time_point deadline,
                                      MapFrameStats* stats, SurfaceMap* surfaces = nullptr) const;

  /// The registered points suitable for stage 2: those observed at t_ns and within
  /// registered_neighbourhood voxels of another observed registered point's voxel.
  std::vector<FeatureId> suitable(const State& state, const FeatureDatabase& db, const RegisteredMap& grid,
                                  TimestampNs t_ns) const;

  const MapOptions& options() const { return options_; }

  /// Plane mode with cloud_normals: the requests ask for surface normals.
  bool wants_normals() const;
  /// Rays per frame: max_rays_per_frame, fewer with normals (the 200 x 44 B budget).
  int max_rays() const;

 private:
  /// Adds the accepted hit X of `ray` as a registered point of `track` (independent of the
  /// state, with the map's variance).
  /// With `plane` (stage1_mode plane) the query pose's uncertainty moves the point along the
  /// surface (a covariance across the normal).
  void add_registered_point(State& state, const FeatureTrack& track, const FeatureRay& ray, const Vec3d& X,
                            TimestampNs t_ns, const SurfacePlane* plane = nullptr) const;
  /// Sends `rays` within the deadline; the hits (empty vector when not answered).
  std::vector<voxel::RayHit> query(MapService& service, const std::vector<FeatureRay>& rays,
                                   TimestampNs stamp_ns, Clock::time_point deadline,
                                   MapFrameStats* stats) const;

  MapOptions options_;
  TriangulationOptions triangulation_;
};

}  // namespace mrvs::edge
