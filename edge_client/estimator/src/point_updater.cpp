#include "mrvs/edge/point_updater.h"

#include "mrvs/edge/feature_measurement.h"

namespace mrvs::edge {
namespace {

/// The observations of `track` at `t_ns` only (cam0 only unless `stereo`).
FeatureTrack at_time(const FeatureTrack& track, TimestampNs t_ns, bool stereo) {
  FeatureTrack out;
  out.id = track.id;
  for (const CameraObservation& o : track.obs) {
    if (o.t_ns == t_ns && (stereo || o.cam == 0)) out.obs.push_back(o);
  }
  return out;
}

}  // namespace

PointUpdater::PointUpdater(const PointOptions& options, const TriangulationOptions& triangulation)
    : options_(options), triangulation_(triangulation), chi2_(200) {}

std::optional<Measurement> PointUpdater::point_measurement(const State& state, const FeatureTrack& track,
                                                           FeatureId id, TimestampNs t_ns) const {
  const PointState& p = state.points.at(id);
  const FeatureTrack now = at_time(track, t_ns, options_.stereo_updates);
  if (now.obs.empty()) return std::nullopt;
  const Vec3d lin = state.options().use_fej ? p.fej : p.p_w;
  StatusOr<FeatureRows> rows = feature_rows(state, now, p.p_w, lin, options_.sigma_px);
  if (!rows.ok()) return std::nullopt;
  Measurement m = rows->m;
  m.vars.push_back(p.slot);
  m.H.conservativeResize(Eigen::NoChange, m.H.cols() + 3);
  m.H.rightCols<3>() = rows->H_f;
  return m;
}

PointStats PointUpdater::update(State& state, const FeatureDatabase& db, TimestampNs t_ns,
                                const std::optional<std::vector<FeatureId>>& only) const {
  PointStats stats;
  std::vector<FeatureId> ids;
  if (only) {
    for (FeatureId id : *only) {
      if (state.points.count(id) != 0) ids.push_back(id);
    }
  } else {
    for (const auto& [id, p] : state.points) ids.push_back(id);
  }
  // Batches of at most max_in_update points, each linearised at the state the previous
  // batch left.
  const auto batch = static_cast<std::size_t>(options_.max_in_update);
  for (std::size_t begin = 0; begin < ids.size(); begin += batch) {
    std::vector<Measurement> parts;
    for (std::size_t i = begin; i < std::min(ids.size(), begin + batch); ++i) {
      const FeatureTrack* track = db.find(ids[i]);
      std::optional<Measurement> m = track ? point_measurement(state, *track, ids[i], t_ns) : std::nullopt;
      if (!m) continue;
      if (mahalanobis(state, *m) > options_.chi2_multiplier * chi2_.q95(m->rows())) {
        ++state.points.at(ids[i]).update_failures;
        ++stats.gated;
        continue;
      }
      parts.push_back(std::move(*m));
    }
    if (parts.empty()) continue;
    // Not compressed: each point's rows only see its own columns and the clone's, which the
    // update exploits; a QR would fill them in.
    const Status s = ekf_update(state, stack(parts));
    if (!s.ok()) stats.status = s;
    if (s.ok()) stats.updated += static_cast<int>(parts.size());
  }
  return stats;
}

PointStats PointUpdater::initialize(State& state, const FeatureDatabase& db,
                                    const std::vector<FeatureId>& ids, TimestampNs t_ns) const {
  PointStats stats;
  for (FeatureId id : ids) {
    if (static_cast<int>(state.points.size()) >= state.options().max_slam) break;
    const FeatureTrack* track = db.find(id);
    if (track == nullptr || state.points.count(id) != 0) continue;
    const std::vector<BearingObservation> bearings = clone_bearings(state, *track);
    StatusOr<Vec3d> p_w = static_cast<int>(bearings.size()) >= options_.min_observations
                              ? triangulate(bearings, triangulation_)
                              : StatusOr<Vec3d>(absl::FailedPreconditionError("too few observations"));
    StatusOr<FeatureRows> rows = p_w.ok() ? feature_rows(state, *track, *p_w, *p_w, options_.sigma_px)
                                          : StatusOr<FeatureRows>(p_w.status());
    StatusOr<SplitMeasurement> split =
        rows.ok() && rows->m.rows() > 3
            ? split_by_new_variable(rows->m, rows->H_f)
            : StatusOr<SplitMeasurement>(absl::FailedPreconditionError("no rows"));
    if (!split.ok() ||
        mahalanobis(state, split->rest) > options_.chi2_multiplier * chi2_.q95(split->rest.rows())) {
      ++stats.init_failed;
      continue;
    }
    const auto [slot, df] = add_variable(state, split->first, split->R_f);
    PointState point;
    point.p_w = *p_w + df;
    // First estimate: the position the rows above (which set the point's cross covariance)
    // were linearised at, not the corrected one. With p_w + df, every later update's Jacobian
    // disagreed with the initialisation's about the unobservable global yaw, and the updates
    // turned the yaw steadily (degrees a minute on EuRoC-like runs).
    point.fej = *p_w;
    point.slot = slot;
    point.added_ns = t_ns;
    state.points.emplace(id, point);
    const Status s = ekf_update(state, split->rest);
    if (!s.ok()) stats.status = s;
    ++stats.initialized;
  }
  return stats;
}

std::vector<FeatureId> PointUpdater::remove_stale(State& state, const FeatureDatabase& db,
                                                  TimestampNs t_ns) const {
  std::vector<FeatureId> stale;
  for (const auto& [id, p] : state.points) {
    const FeatureTrack* track = db.find(id);
    if (track == nullptr || !track->seen_at(t_ns) || p.update_failures > options_.max_failures)
      stale.push_back(id);
  }
  for (FeatureId id : stale) marginalize_point(state, id);
  return stale;
}

}  // namespace mrvs::edge
