#pragma once
// Point features kept in the state (algorithm.md 3.6, 3.7): long tracks enter the state by
// delayed initialisation (the feature isolated from the rest of its rows, which then update
// the state), are updated with their newest observations every frame, and leave when their
// track is lost or they keep failing the gate.
#include <optional>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/edge/triangulation.h"

namespace mrvs::edge {

struct PointOptions : config::OptionsEquality<PointOptions> {
  double sigma_px = 1.0;         ///< pixel noise
  double chi2_multiplier = 1.0;  ///< gate multiplier
  int max_in_update = 100;       ///< points per stacked update
  double delay_s = 1.0;          ///< no points during the first seconds after initialisation
  int max_failures = 1;          ///< a point failing the gate more often leaves the state
  int min_observations = 4;      ///< observations at clone times to initialise a point
  bool stereo_updates = true;    ///< update with both cameras' observations (else cam0 only)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("sigma_px", sigma_px, in_range(0.01, 100.0), "pixel noise, px");
    v("chi2_multiplier", chi2_multiplier, in_range(0.01, 1000.0), "chi-square gate multiplier");
    v("max_in_update", max_in_update, in_range(1, 10000), "points per stacked update");
    v("delay_s", delay_s, in_range(0.0, 1000.0), "no points in the state during the first seconds, s");
    v("max_failures", max_failures, in_range(0, 1000), "gate failures before a point leaves the state");
    v("min_observations", min_observations, in_range(2, 1000), "observations needed to initialise");
    v("stereo_updates", stereo_updates, any(), "update points with both cameras (else the left only)");
  }
};

struct PointStats {
  int updated = 0;
  int gated = 0;
  int initialized = 0;
  int init_failed = 0;
  int removed = 0;
  Status status;
};

class PointUpdater {
 public:
  PointUpdater(const PointOptions& options, const TriangulationOptions& triangulation);

  /// Updates the points of the state (all, or only `ids`) with their observations at clone
  /// `t_ns`.
  PointStats update(State& state, const FeatureDatabase& db, TimestampNs t_ns,
                    const std::optional<std::vector<FeatureId>>& ids = std::nullopt) const;
  /// Adds the features `ids` to the state (delayed initialisation), while there is room.
  PointStats initialize(State& state, const FeatureDatabase& db, const std::vector<FeatureId>& ids,
                        TimestampNs t_ns) const;
  /// Removes the points not seen at `t_ns` or failing too often; returns their ids.
  std::vector<FeatureId> remove_stale(State& state, const FeatureDatabase& db, TimestampNs t_ns) const;

  const PointOptions& options() const { return options_; }

 private:
  std::optional<Measurement> point_measurement(const State& state, const FeatureTrack& track, FeatureId id,
                                               TimestampNs t_ns) const;
  PointOptions options_;
  TriangulationOptions triangulation_;
  Chi2Table chi2_;
};

}  // namespace mrvs::edge
