#include "mrvs/edge/msckf_updater.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "mrvs/edge/feature_measurement.h"

namespace mrvs::edge {

MsckfUpdater::MsckfUpdater(const MsckfOptions& options, const TriangulationOptions& triangulation)
    : options_(options), triangulation_(triangulation), chi2_(500) {}

std::optional<Measurement> MsckfUpdater::feature_measurement(const State& state, const FeatureTrack& track,
                                                             MsckfStats* stats, const MapPoint* on_plane,
                                                             Vec3d* position) const {
  const std::vector<BearingObservation> bearings = clone_bearings(state, track);
  if (static_cast<int>(bearings.size()) < options_.min_observations) {
    ++stats->too_few_observations;
    return std::nullopt;
  }
  const StatusOr<Vec3d> p_w = triangulate(bearings, triangulation_);
  if (!p_w.ok()) {
    ++stats->triangulation_failed;
    return std::nullopt;
  }
  StatusOr<FeatureRows> rows = feature_rows(state, track, *p_w, *p_w, options_.sigma_px);
  if (!rows.ok() || rows->m.rows() <= 3) {
    ++stats->triangulation_failed;
    return std::nullopt;
  }
  if (on_plane != nullptr && on_plane->plane) append_plane_row(*on_plane, *p_w, &*rows);
  StatusOr<SplitMeasurement> split = split_by_new_variable(rows->m, rows->H_f);
  if (!split.ok()) {
    ++stats->triangulation_failed;
    return std::nullopt;
  }
  Measurement& m = split->rest;
  if (mahalanobis(state, m) > options_.chi2_multiplier * chi2_.q95(m.rows())) {
    ++stats->gated;
    return std::nullopt;
  }
  if (position) *position = *p_w;
  return std::move(m);
}

StatusOr<Stage1Mode> parse_stage1_mode(const std::string& name) {
  if (name == "known_landmark") return Stage1Mode::kKnownLandmark;
  if (name == "msckf_nullspace") return Stage1Mode::kMsckfNullspace;
  if (name == "ray_depth") return Stage1Mode::kRayDepth;
  if (name == "plane") return Stage1Mode::kPlane;
  return absl::InvalidArgumentError("stage1_mode '" + name +
                                    "' is not one of known_landmark, msckf_nullspace, ray_depth, plane");
}

void append_plane_row(const MapPoint& point, const Vec3d& p_w, FeatureRows* rows) {
  // 0 = n . (p - X) + noise of the map point (variance) and of the surface (rms), scaled to
  // the rows' sigma; the feature's error enters through H_f, the state's not at all.
  const Vec3d& n = point.plane->normal;
  const double sigma_m = std::sqrt(point.variance + point.plane->rms_m * point.plane->rms_m);
  const double scale = rows->m.sigma / std::max(sigma_m, 1e-6);
  const Eigen::Index k = rows->m.rows();
  rows->m.H.conservativeResize(k + 1, Eigen::NoChange);
  rows->m.H.row(k).setZero();
  rows->m.r.conservativeResize(k + 1);
  rows->m.r(k) = -scale * n.dot(p_w - point.p_w);
  rows->H_f.conservativeResize(k + 1, Eigen::NoChange);
  rows->H_f.row(k) = scale * n.transpose();
}

namespace {

/// m whitened to unit-sigma rows scaled by sigma_px, for rows of noise sigma^2 I + H_f C H_f^T.
void whiten(Measurement* m, const Eigen::MatrixXd& H_f, const Mat3d& C, double sigma_px) {
  Eigen::MatrixXd S = H_f * C * H_f.transpose();
  S.diagonal().array() += sigma_px * sigma_px;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  m->H = sigma_px * llt.matrixL().solve(m->H);
  m->r = sigma_px * llt.matrixL().solve(m->r);
}

}  // namespace

std::optional<Measurement> MsckfUpdater::map_measurement(const State& state, const FeatureTrack& track,
                                                         const MapPoint& point, Stage1Mode mode,
                                                         MsckfStats* stats) const {
  if (mode == Stage1Mode::kPlane) return feature_measurement(state, track, stats, &point);
  const bool anchored = mode == Stage1Mode::kRayDepth && point.anchor;
  StatusOr<FeatureRows> rows = anchored
                                   ? anchored_feature_rows(state, track, *point.anchor, options_.sigma_px)
                                   : feature_rows(state, track, point.p_w, point.p_w, options_.sigma_px);
  const int needed = 2 * options_.min_observations - (mode == Stage1Mode::kMsckfNullspace ? 0 : 2);
  if (!rows.ok() || rows->m.rows() < needed - (anchored ? 2 : 0)) {
    ++stats->too_few_observations;
    return std::nullopt;
  }
  Measurement m;
  if (anchored) {
    m = rows->m;
    whiten(&m, rows->H_f, anchored_covariance(state, *point.anchor, point.variance, options_.sigma_px),
           options_.sigma_px);
  } else if (mode == Stage1Mode::kMsckfNullspace) {
    StatusOr<SplitMeasurement> split = split_by_new_variable(rows->m, rows->H_f);
    if (!split.ok()) {
      ++stats->triangulation_failed;
      return std::nullopt;
    }
    m = std::move(split->rest);
  } else {
    // Noise of the rows: pixel noise plus the map point's, correlated across the views.
    m = rows->m;
    whiten(&m, rows->H_f, point.variance * Mat3d::Identity() + point.association, options_.sigma_px);
  }
  if (mahalanobis(state, m) > options_.chi2_multiplier * chi2_.q95(m.rows())) {
    ++stats->gated;
    return std::nullopt;
  }
  return m;
}

MsckfStats MsckfUpdater::update(State& state, const FeatureDatabase& db, const std::vector<FeatureId>& ids,
                                const std::map<FeatureId, MapPoint>& map_points, Stage1Mode mode,
                                std::vector<std::pair<FeatureId, Vec3d>>* triangulated) const {
  MsckfStats stats;
  // The most observed features first, at most max_features.
  std::vector<const FeatureTrack*> tracks;
  for (FeatureId id : ids) {
    if (const FeatureTrack* t = db.find(id)) tracks.push_back(t);
  }
  std::stable_sort(tracks.begin(), tracks.end(), [](const FeatureTrack* a, const FeatureTrack* b) {
    return a->obs.size() > b->obs.size();
  });
  if (static_cast<int>(tracks.size()) > options_.max_features)
    tracks.resize(static_cast<std::size_t>(options_.max_features));
  stats.candidates = static_cast<int>(tracks.size());
  std::vector<Measurement> parts;
  for (const FeatureTrack* t : tracks) {
    const auto mp = map_points.find(t->id);
    Vec3d p_w = Vec3d::Zero();
    std::optional<Measurement> m = mp == map_points.end()
                                       ? feature_measurement(state, *t, &stats, nullptr, &p_w)
                                       : map_measurement(state, *t, mp->second, mode, &stats);
    if (m && triangulated && mp == map_points.end()) triangulated->emplace_back(t->id, p_w);
    if (!m) continue;
    if (mp != map_points.end()) ++stats.with_map;
    stats.rows += m->rows();
    parts.push_back(std::move(*m));
  }
  stats.used = static_cast<int>(parts.size());
  if (parts.empty()) return stats;
  Measurement all = stack(parts);
  compress(&all);
  stats.status = ekf_update(state, all);
  return stats;
}

}  // namespace mrvs::edge
