#include "mrvs/edge/keyframe_policy.h"

#include <iterator>

namespace mrvs::edge {

TimestampNs clone_to_marginalize(const State& state, const FeatureDatabase& db, const KeyframeOptions& o) {
  const TimestampNs oldest = state.clones.begin()->first;
  if (!o.use_keyframes || state.clones.size() < 3) return oldest;
  auto it = state.clones.rbegin();
  const TimestampNs second = std::next(it)->first;
  const TimestampNs third = std::next(it, 2)->first;
  if (third == oldest) return oldest;  // never drop the only older image
  // Mean normalised motion of cam0 features between the third- and second-newest images.
  double sum = 0.0;
  int n = 0;
  for (const auto& [id, track] : db.tracks()) {
    const CameraObservation *a = nullptr, *b = nullptr;
    for (const CameraObservation& obs : track.obs) {
      if (obs.cam != 0) continue;
      if (obs.t_ns == third) a = &obs;
      if (obs.t_ns == second) b = &obs;
    }
    if (a != nullptr && b != nullptr) sum += (b->xn - a->xn).norm(), ++n;
  }
  if (n < o.min_tracked) return oldest;
  const double fx = state.cams[0].model->fx();
  return sum / n * fx >= o.parallax_px ? oldest : second;
}

}  // namespace mrvs::edge
