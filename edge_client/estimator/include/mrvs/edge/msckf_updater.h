#pragma once
// The MSCKF update (algorithm.md 3.5): features whose tracks leave the window are
// triangulated from the clones, their rows projected onto the left null space of H_f (the
// feature drops out), gated by chi-square, stacked, compressed by QR and applied in one EKF
// update. The tracks used are removed from the database by the caller.
#include <map>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/feature_measurement.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/edge/surface_map.h"
#include "mrvs/edge/triangulation.h"

namespace mrvs::edge {

struct MsckfOptions : config::OptionsEquality<MsckfOptions> {
  double sigma_px = 1.0;         ///< pixel noise (EuRoC 1.0, KAIST 1.5)
  double chi2_multiplier = 1.0;  ///< gate: Mahalanobis <= this * chi2_95(rows)
  int max_features = 100;        ///< per update, the most observed ones
  int min_observations = 3;      ///< camera observations at clone times needed

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("sigma_px", sigma_px, in_range(0.01, 100.0), "pixel noise, px");
    v("chi2_multiplier", chi2_multiplier, in_range(0.01, 1000.0), "chi-square gate multiplier");
    v("max_features", max_features, in_range(1, 10000), "features per update");
    v("min_observations", min_observations, in_range(2, 1000), "observations at clone times needed");
  }
};

/// What one update did.
struct MsckfStats {
  int candidates = 0;
  int too_few_observations = 0;
  int triangulation_failed = 0;
  int gated = 0;  ///< rejected by chi-square
  int used = 0;
  int rows = 0;      ///< after null-space projection, before compression
  int with_map = 0;  ///< of `used`, features updated with their map point
  Status status;     ///< of the EKF update
};

/// A map point associated with a feature for stage 1 (paper section IV-E.2).
struct MapPoint {
  Vec3d p_w = Vec3d::Zero();  ///< world (map frame)
  double variance = 0.0;      ///< isotropic, m^2
  /// The ray it was found along, with the hit's depth (for Stage1Mode::kRayDepth).
  std::optional<RayAnchor> anchor;
  /// Added to the known landmark's covariance: where the ray of the estimated pose met the
  /// map is uncertain across the ray by the query pose's uncertainty (MapOptions::
  /// association_noise); zero otherwise.
  Mat3d association = Mat3d::Zero();
  /// The map's surface around the point (Stage1Mode::kPlane); nullopt when none was fitted.
  std::optional<SurfacePlane> plane;
};

/// How stage 1 uses a map point.
enum class Stage1Mode {
  kKnownLandmark,   ///< the paper: a landmark of known position, every observation's rows
  kMsckfNullspace,  ///< the reference code: linearised at the map point, H_f projected out
  /// The map's depth along the query ray: the point is fixed in the query camera (its
  /// direction that observation's), so it moves with the estimated pose instead of pinning
  /// the pose to where the estimated ray met the map.
  kRayDepth,
  /// The map's surface plane through the point: the feature, triangulated, must lie on it
  /// (one row of the map point's and the plane's noise along the normal), then H_f is
  /// projected out like the MSCKF. Where a ray from a wrong pose meets a surface moves along
  /// the surface with the pose; only the offset along the normal is information. Without a
  /// plane the feature is used as if it had no map point.
  kPlane,
};
StatusOr<Stage1Mode> parse_stage1_mode(const std::string& name);

/// Stacks the plane row of `point` (which has a plane) under the rows of its feature
/// linearised at p_w: residual -n.(p_w - X), H_f n^T, nothing on the state; noise the map
/// point's variance plus the surface's rms^2, scaled to the rows' sigma.
void append_plane_row(const MapPoint& point, const Vec3d& p_w, FeatureRows* rows);

class MsckfUpdater {
 public:
  MsckfUpdater(const MsckfOptions& options, const TriangulationOptions& triangulation);

  /// Updates `state` with the features `ids` of `db`: with their map point when `map_points`
  /// has one (used as `mode` says), otherwise triangulated.
  /// `triangulated` (optional) receives the position of every feature used without a map
  /// point, as triangulated before the update (the localisation submap's points).
  MsckfStats update(State& state, const FeatureDatabase& db, const std::vector<FeatureId>& ids,
                    const std::map<FeatureId, MapPoint>& map_points = {},
                    Stage1Mode mode = Stage1Mode::kKnownLandmark,
                    std::vector<std::pair<FeatureId, Vec3d>>* triangulated = nullptr) const;

  /// Stage-1 rows of a feature whose position is the map point: kKnownLandmark keeps every
  /// row, its noise sigma^2 I + H_f (v I + association) H_f^T whitened to sigma^2 I; kMsckfNullspace
  /// projects H_f out like the MSCKF, linearised at the map point; kRayDepth uses
  /// anchored_feature_rows with the noise of the map's depth along the ray and of the anchor
  /// pixel across it. Gated; nullopt when not usable (`stats` counts why).
  std::optional<Measurement> map_measurement(const State& state, const FeatureTrack& track,
                                             const MapPoint& point, Stage1Mode mode, MsckfStats* stats) const;

  /// The null-space projected, gated rows of one feature (exposed for tests and issue 8);
  /// with `on_plane` (a map point with a plane) the plane row is stacked before the
  /// projection (Stage1Mode::kPlane). nullopt when it is not usable; `stats` counts why.
  /// `position` (optional) receives the triangulated point of a usable feature.
  std::optional<Measurement> feature_measurement(const State& state, const FeatureTrack& track,
                                                 MsckfStats* stats, const MapPoint* on_plane = nullptr,
                                                 Vec3d* position = nullptr) const;

  const MsckfOptions& options() const { return options_; }

 private:
  MsckfOptions options_;
  TriangulationOptions triangulation_;
  Chi2Table chi2_;
};

}  // namespace mrvs::edge
