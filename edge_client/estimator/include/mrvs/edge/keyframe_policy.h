#pragma once
// Which clone leaves a full window (algorithm.md 3.8): when the second-newest image moved
// the features enough since the one before it (parallax), or too few features reached it,
// it is a keyframe and the oldest clone goes; otherwise the second-newest goes and its
// observations are dropped (VINS-Mono style), keeping the older keyframes.
#include "mrvs/config/options.h"
#include "mrvs/edge/feature_database.h"
#include "mrvs/edge/state.h"

namespace mrvs::edge {

struct KeyframeOptions : config::OptionsEquality<KeyframeOptions> {
  bool use_keyframes = true;  ///< false: always the oldest clone
  double parallax_px = 20.0;  ///< mean feature motion that makes a keyframe, px (at fx)
  int min_tracked = 20;       ///< fewer common features: a keyframe

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("use_keyframes", use_keyframes, any(), "marginalise non-keyframes first (else always the oldest)");
    v("parallax_px", parallax_px, in_range(0.0, 1000.0), "keyframe parallax, px");
    v("min_tracked", min_tracked, in_range(0, 10000), "fewer common features make a keyframe");
  }
};

/// The clone to remove from `state` (which has more than two clones).
TimestampNs clone_to_marginalize(const State& state, const FeatureDatabase& db,
                                 const KeyframeOptions& options);

}  // namespace mrvs::edge
