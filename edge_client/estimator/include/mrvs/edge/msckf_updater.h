#pragma once
// The MSCKF update (algorithm.md 3.5): features whose tracks leave the window are
// triangulated from the clones, their rows projected onto the left null space of H_f (the
// feature drops out), gated by chi-square, stacked, compressed by QR and applied in one EKF
// update. The tracks used are removed from the database by the caller.
#include <map>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/state_helper.h"
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
};

class MsckfUpdater {
 public:
  MsckfUpdater(const MsckfOptions& options, const TriangulationOptions& triangulation);

  /// Updates `state` with the features `ids` of `db`: with their map point when `map_points`
  /// has one (known landmark, or the reference code's null-space use with `nullspace_map`),
  /// otherwise triangulated.
  MsckfStats update(State& state, const FeatureDatabase& db, const std::vector<FeatureId>& ids,
                    const std::map<FeatureId, MapPoint>& map_points = {}, bool nullspace_map = false) const;

  /// Stage-1 rows of a feature whose position is the map point: known_landmark keeps every
  /// row, its noise sigma^2 I + H_f (v I) H_f^T whitened to sigma^2 I; nullspace_map
  /// projects H_f out like the MSCKF, linearised at the map point. Gated; nullopt when not
  /// usable (`stats` counts why).
  std::optional<Measurement> map_measurement(const State& state, const FeatureTrack& track,
                                             const MapPoint& point, bool nullspace_map,
                                             MsckfStats* stats) const;

  /// The null-space projected, gated rows of one feature (exposed for tests and issue 8).
  /// nullopt when it is not usable; `stats` counts why.
  std::optional<Measurement> feature_measurement(const State& state, const FeatureTrack& track,
                                                 MsckfStats* stats) const;

  const MsckfOptions& options() const { return options_; }

 private:
  MsckfOptions options_;
  TriangulationOptions triangulation_;
  Chi2Table chi2_;
};

}  // namespace mrvs::edge
