#pragma once
// The observations of every tracked feature inside the sliding window (OpenVINS'
// FeatureDatabase): per feature, its pixels and undistorted normalised coordinates in
// each camera at each image time.
#include <array>
#include <map>
#include <vector>

#include "mrvs/core/time.h"
#include "mrvs/edge/feature_observation.h"

namespace mrvs::edge {

/// One observation of a feature in one camera.
struct CameraObservation {
  TimestampNs t_ns = 0;  ///< camera time of the image
  int cam = 0;
  Vec2d uv = Vec2d::Zero();  ///< raw pixel
  Vec2d xn = Vec2d::Zero();  ///< undistorted normalised coordinates
};

struct FeatureTrack {
  FeatureId id = 0;
  std::vector<CameraObservation> obs;  ///< time-ordered; at a time, cam0 before cam1
  TimestampNs first_ns() const { return obs.empty() ? 0 : obs.front().t_ns; }
  TimestampNs last_ns() const { return obs.empty() ? 0 : obs.back().t_ns; }
  bool seen_at(TimestampNs t_ns) const;
  /// Number of image times it was seen at (1 per stereo pair).
  int frames() const;
};

class FeatureDatabase {
 public:
  /// Adds the observations of one frame (left, and right when stereo).
  void add(const FeatureFrame& frame);

  const std::map<FeatureId, FeatureTrack>& tracks() const { return tracks_; }
  const FeatureTrack* find(FeatureId id) const;
  std::size_t size() const { return tracks_.size(); }

  /// Ids of the features last seen before `t_ns` (their track ended).
  std::vector<FeatureId> lost_before(TimestampNs t_ns) const;
  /// Ids of the features seen at `t_ns`.
  std::vector<FeatureId> seen_at(TimestampNs t_ns) const;

  /// Removes a feature.
  void erase(FeatureId id);
  /// Removes the observations at `t_ns` (a marginalised non-keyframe), and empty tracks.
  void erase_at(TimestampNs t_ns);
  /// Removes the observations before `t_ns` (older than the window), and empty tracks.
  void erase_before(TimestampNs t_ns);
  /// Keeps only the observations at or after `t_ns` of one feature (it was used).
  void keep_from(FeatureId id, TimestampNs t_ns);

 private:
  std::map<FeatureId, FeatureTrack> tracks_;
};

}  // namespace mrvs::edge
