#include "mrvs/edge/feature_database.h"

#include <algorithm>

namespace mrvs::edge {

bool FeatureTrack::seen_at(TimestampNs t_ns) const {
  return std::any_of(obs.rbegin(), obs.rend(), [t_ns](const CameraObservation& o) { return o.t_ns == t_ns; });
}

int FeatureTrack::frames() const {
  int n = 0;
  TimestampNs last = -1;
  for (const CameraObservation& o : obs) {
    if (o.t_ns != last) ++n, last = o.t_ns;
  }
  return n;
}

void FeatureDatabase::add(const FeatureFrame& frame) {
  for (const FeatureObservation& f : frame.features) {
    FeatureTrack& t = tracks_[f.id];
    t.id = f.id;
    if (!t.obs.empty() && t.obs.back().t_ns >= frame.t_ns) continue;  // a frame is added once
    t.obs.push_back({frame.t_ns, 0, f.uv_left, f.xn_left});
    if (f.stereo) t.obs.push_back({frame.t_ns, 1, f.uv_right, f.xn_right});
  }
}

const FeatureTrack* FeatureDatabase::find(FeatureId id) const {
  const auto it = tracks_.find(id);
  return it == tracks_.end() ? nullptr : &it->second;
}

std::vector<FeatureId> FeatureDatabase::lost_before(TimestampNs t_ns) const {
  std::vector<FeatureId> out;
  for (const auto& [id, t] : tracks_) {
    if (t.last_ns() < t_ns) out.push_back(id);
  }
  return out;
}

std::vector<FeatureId> FeatureDatabase::seen_at(TimestampNs t_ns) const {
  std::vector<FeatureId> out;
  for (const auto& [id, t] : tracks_) {
    if (t.seen_at(t_ns)) out.push_back(id);
  }
  return out;
}

void FeatureDatabase::erase(FeatureId id) { tracks_.erase(id); }

void FeatureDatabase::erase_at(TimestampNs t_ns) {
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    auto& obs = it->second.obs;
    obs.erase(
        std::remove_if(obs.begin(), obs.end(), [t_ns](const CameraObservation& o) { return o.t_ns == t_ns; }),
        obs.end());
    it = obs.empty() ? tracks_.erase(it) : std::next(it);
  }
}

void FeatureDatabase::erase_before(TimestampNs t_ns) {
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    auto& obs = it->second.obs;
    obs.erase(
        std::remove_if(obs.begin(), obs.end(), [t_ns](const CameraObservation& o) { return o.t_ns < t_ns; }),
        obs.end());
    it = obs.empty() ? tracks_.erase(it) : std::next(it);
  }
}

void FeatureDatabase::keep_from(FeatureId id, TimestampNs t_ns) {
  const auto it = tracks_.find(id);
  if (it == tracks_.end()) return;
  auto& obs = it->second.obs;
  obs.erase(
      std::remove_if(obs.begin(), obs.end(), [t_ns](const CameraObservation& o) { return o.t_ns < t_ns; }),
      obs.end());
  if (obs.empty()) tracks_.erase(it);
}

}  // namespace mrvs::edge
