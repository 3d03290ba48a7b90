#include "mrvs/edge/map_stage.h"

#include <algorithm>
#include <set>

#include "mrvs/core/time.h"
#include "mrvs/edge/feature_measurement.h"
#include "mrvs/edge/state_helper.h"

namespace mrvs::edge {
namespace {

SurfaceFitOptions fit_options(const MapOptions& o) {
  SurfaceFitOptions out;
  out.radius_m = o.plane_radius_m;
  out.min_points = o.plane_min_points;
  out.max_rms_m = o.plane_max_rms_m;
  return out;
}

/// The map O with O A O^T the covariance of where a ray of direction v (world) meets the
/// plane when A is that of the ray's point across the ray: the oblique projection along v
/// onto the plane, I - v n^T / (n.v), |n.v| held at 0.2 or more (grazing rays).
Mat3d on_surface(const SurfacePlane& plane, const Vec3d& v_w) {
  const Vec3d v = v_w.normalized();
  const double c = plane.normal.dot(v);
  const double held = std::abs(c) < 0.2 ? std::copysign(0.2, c == 0.0 ? 1.0 : c) : c;
  return Mat3d::Identity() - v * plane.normal.transpose() / held;
}

/// The surface plane at hit X (plane mode): through X with the normal the cloud sent
/// (cloud_normals; its roughness bound plane_max_rms_m), else the plane the SurfaceMap fits
/// to the answered points around X; nullopt without either.
std::optional<SurfacePlane> plane_of(const voxel::RayHit& hit, const Vec3d& X, const SurfaceMap& surfaces,
                                     const MapOptions& o) {
  if (hit.normal.squaredNorm() > 0.5f) {
    SurfacePlane plane;
    plane.normal = hit.normal.cast<double>().normalized();
    plane.centroid = X;
    plane.rms_m = o.plane_max_rms_m;
    return plane;
  }
  return surfaces.plane_at(X, fit_options(o));
}

/// Every hit is a point of the prior map (whether or not its feature is accepted).
void remember_surfaces(const std::vector<voxel::RayHit>& hits, const Vec3d& origin, SurfaceMap* surfaces) {
  if (surfaces == nullptr) return;
  for (const voxel::RayHit& h : hits) {
    if (h.hit) surfaces->add(origin + h.point.cast<double>());
  }
}

}  // namespace

MapStage::MapStage(const MapOptions& options, const TriangulationOptions& triangulation)
    : options_(options), triangulation_(triangulation) {}

bool MapStage::wants_normals() const { return options_.cloud_normals && options_.stage1_mode == "plane"; }

int MapStage::max_rays() const {
  // The paper's budget, 200 x 44 B per frame, holds with the normals' 6 B per hit too.
  constexpr int kWithNormals = 200 * (kRayBytes + kHitBytes) / (kRayBytes + kHitBytes + kNormalBytes);
  return wants_normals() ? std::min(options_.max_rays_per_frame, kWithNormals) : options_.max_rays_per_frame;
}

void MapStage::add_registered_point(State& state, const FeatureTrack& track, const FeatureRay& ray,
                                    const Vec3d& X, TimestampNs t_ns, const SurfacePlane* plane) const {
  // A landmark known from the map: its variance (plus the association's), independent of the
  // state. (Anchoring it on its ray like ray_depth's stage-1 points, correlated with the query
  // clone, was measured worse: the registered points then no longer hold the pose where it
  // was; see edge_client/README.md.)
  Mat3d covariance = Mat3d::Identity() * map_point_variance(options_, ray.ray.resolution);
  const std::optional<RayAnchor> anchor =
      options_.association_noise || plane != nullptr ? ray_anchor(state, track, ray, X) : std::nullopt;
  if (anchor && plane != nullptr) {
    // Where the ray met the surface slides along it with the query pose's error.
    const Mat3d O =
        on_surface(*plane, state.T_w_c(anchor->t_ns, anchor->cam).rotation_matrix() * anchor->p_c);
    covariance += O * hit_covariance_across(state, *anchor) * O.transpose();
  } else if (anchor) {
    covariance += hit_covariance_across(state, *anchor);
  }
  PointState point;
  point.p_w = point.fej = X;
  point.slot = state.append(3);
  state.P.block<3, 3>(point.slot.offset, point.slot.offset) = covariance;
  point.added_ns = t_ns;
  point.from_map = true;
  state.points.emplace(track.id, point);
}

std::vector<voxel::RayHit> MapStage::query(MapService& service, const std::vector<FeatureRay>& rays,
                                           TimestampNs stamp_ns, Clock::time_point deadline,
                                           MapFrameStats* stats) const {
  if (rays.empty()) return {};
  const auto left = std::chrono::duration_cast<std::chrono::nanoseconds>(deadline - Clock::now()).count();
  const DurationNs timeout = std::min<DurationNs>(from_seconds(options_.query_timeout_ms * 1e-3), left);
  ++stats->requests;
  if (timeout <= 0) {
    ++stats->timeouts;
    return {};
  }
  std::vector<voxel::RayQuery> batch;
  batch.reserve(rays.size());
  for (const FeatureRay& r : rays) batch.push_back(r.ray);
  const MapReply reply = service.query(batch, stamp_ns, timeout, wants_normals());
  stats->rtt_ms += 1e-6 * static_cast<double>(reply.rtt_ns);
  stats->bytes_up += kRayBytes * batch.size();
  if (!reply.answered || reply.hits.size() != batch.size()) {
    ++stats->timeouts;
    return {};
  }
  ++stats->answered;
  stats->bytes_down += (batch.size() + 7) / 8;
  const int per_hit = wants_normals() ? kHitBytes + kNormalBytes : kHitBytes;
  for (const voxel::RayHit& h : reply.hits) stats->bytes_down += h.hit ? per_hit : 0;
  return reply.hits;
}

std::map<FeatureId, MapPoint> MapStage::associate(const State& state, const FeatureDatabase& db,
                                                  const io::Trajectory& groundtruth,
                                                  std::vector<FeatureId>* ids, MapService& service,
                                                  Clock::time_point deadline, MapFrameStats* stats,
                                                  SurfaceMap* surfaces) const {
  std::map<FeatureId, MapPoint> out;
  const auto t0 = Clock::now();
  const auto map = service.description();
  stats->available = map.has_value();
  if (!map) return out;
  // The most observed candidates, one ray each.
  std::vector<const FeatureTrack*> tracks;
  for (FeatureId id : *ids) {
    if (const FeatureTrack* t = db.find(id)) tracks.push_back(t);
  }
  std::stable_sort(tracks.begin(), tracks.end(), [](const FeatureTrack* a, const FeatureTrack* b) {
    return a->obs.size() > b->obs.size();
  });
  const int cap = std::min(options_.max_stage1_features, max_rays());
  std::vector<FeatureRay> rays;
  for (const FeatureTrack* t : tracks) {
    if (static_cast<int>(rays.size()) >= cap) break;
    const auto p = triangulate(clone_bearings(state, *t), triangulation_);
    if (!p.ok()) continue;
    if (auto ray = make_feature_ray(state, groundtruth, *t, *p, *map, options_)) rays.push_back(*ray);
  }
  stats->stage1_rays = static_cast<int>(rays.size());
  const std::vector<voxel::RayHit> hits = query(service, rays, state.newest_clone_ns(), deadline, stats);
  remember_surfaces(hits, map->origin, surfaces);
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].hit) continue;
    ++stats->stage1_hits;
    const Vec3d X = map->origin + hits[i].point.cast<double>();
    const FeatureTrack& track = *db.find(rays[i].id);
    if (!accept_hit(state, groundtruth, track, rays[i], X, options_)) continue;
    MapPoint& point = out[rays[i].id];
    point = MapPoint{X, map_point_variance(options_, rays[i].ray.resolution),
                     ray_anchor(state, track, rays[i], X), Mat3d::Zero(), std::nullopt};
    if (options_.association_noise && point.anchor)
      point.association = hit_covariance_across(state, *point.anchor);
    if (surfaces != nullptr) {
      point.plane = plane_of(hits[i], X, *surfaces, options_);
      stats->stage1_planes += point.plane.has_value();
    }
  }
  stats->stage1_accepted = static_cast<int>(out.size());
  // The reference code's rule: with most features on the map, the others are suspect.
  if (!rays.empty() && static_cast<double>(out.size()) / rays.size() >= options_.drop_unmatched_hit_rate) {
    std::set<FeatureId> queried;
    for (const FeatureRay& r : rays) queried.insert(r.id);
    const auto before = ids->size();
    ids->erase(std::remove_if(ids->begin(), ids->end(),
                              [&](FeatureId id) { return queried.count(id) != 0 && out.count(id) == 0; }),
               ids->end());
    stats->stage1_dropped = static_cast<int>(before - ids->size());
  }
  stats->ray_ms += ms_since(t0);
  return out;
}

std::vector<FeatureId> MapStage::register_new(State& state, const FeatureDatabase& db,
                                              const io::Trajectory& groundtruth, TimestampNs t_ns,
                                              RegisteredMap* grid, MapService& service,
                                              Clock::time_point deadline, MapFrameStats* stats,
                                              SurfaceMap* surfaces) const {
  std::vector<FeatureId> added;
  const auto t0 = Clock::now();
  const auto map = service.description();
  if (!map) return added;
  // Rays only for the room the state has left: a hit beyond it could not be registered.
  // Twice the room, as about half the new features' rays give an accepted hit with room in
  // the grid.
  const int room = state.options().max_slam - static_cast<int>(state.points.size());
  const int budget = std::min(max_rays() - stats->stage1_rays, 2 * room);
  std::vector<FeatureRay> rays;
  for (const auto& [id, track] : db.tracks()) {
    if (static_cast<int>(rays.size()) >= budget) break;
    if (track.first_ns() != t_ns || track.obs.size() < 2 || state.points.count(id) != 0)
      continue;  // new stereo pairs
    const auto p = triangulate(clone_bearings(state, track), triangulation_);
    if (!p.ok() || !grid->has_room(*p)) continue;
    if (auto ray = make_feature_ray(state, groundtruth, track, *p, *map, options_)) rays.push_back(*ray);
  }
  stats->registration_rays = static_cast<int>(rays.size());
  const std::vector<voxel::RayHit> hits = query(service, rays, t_ns, deadline, stats);
  remember_surfaces(hits, map->origin, surfaces);
  for (std::size_t i = 0; i < hits.size(); ++i) {
    if (!hits[i].hit) continue;
    ++stats->registration_hits;
    if (static_cast<int>(state.points.size()) >= state.options().max_slam) continue;
    const Vec3d X = map->origin + hits[i].point.cast<double>();
    const FeatureTrack& track = *db.find(rays[i].id);
    if (!accept_hit(state, groundtruth, track, rays[i], X, options_)) continue;
    // With surfaces (stage1_mode plane): only hits on a surface, which slide along it with the pose.
    std::optional<SurfacePlane> plane;
    if (surfaces != nullptr && !(plane = plane_of(hits[i], X, *surfaces, options_))) continue;
    if (!grid->add(rays[i].id, X)) continue;
    add_registered_point(state, track, rays[i], X, t_ns, plane ? &*plane : nullptr);
    added.push_back(rays[i].id);
  }
  stats->registered = static_cast<int>(added.size());
  stats->ray_ms += ms_since(t0);
  return added;
}

std::vector<FeatureId> MapStage::suitable(const State& state, const FeatureDatabase& db,
                                          const RegisteredMap& grid, TimestampNs t_ns) const {
  std::set<FeatureId> seen;
  for (const auto& [id, p] : state.points) {
    const FeatureTrack* t = db.find(id);
    if (p.from_map && t != nullptr && t->seen_at(t_ns)) seen.insert(id);
  }
  std::set<FeatureId> out;
  for (FeatureId id : seen) {
    for (FeatureId n : grid.neighbourhood(state.points.at(id).p_w, options_.registered_neighbourhood)) {
      if (seen.count(n) != 0) out.insert(n);
    }
  }
  return {out.begin(), out.end()};
}

}  // namespace mrvs::edge
