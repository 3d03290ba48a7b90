#pragma once
// What the front-end hands the estimator for one stereo frame (no image types here).
#include <cstdint>
#include <vector>

#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"

namespace mrvs::edge {

using FeatureId = std::uint64_t;

/// One feature in one stereo frame.
struct FeatureObservation {
  FeatureId id = 0;               ///< stable over the feature's track, unique for the tracker's life
  Vec2d uv_left = Vec2d::Zero();  ///< raw (distorted) pixel in cam0
  Vec2d xn_left = Vec2d::Zero();  ///< undistorted normalised coordinates in cam0
  bool stereo = false;            ///< uv_right / xn_right valid
  Vec2d uv_right = Vec2d::Zero();
  Vec2d xn_right = Vec2d::Zero();
  int track_length = 1;  ///< frames observed so far, this one included
  /// Mean cam0 brightness (0-255) of the pixels around uv_left; 0: not measured (the
  /// localisation submap's appearance, mrvs::edge::patch_brightness).
  float brightness = 0.0f;
};

/// The features of one stereo frame.
struct FeatureFrame {
  TimestampNs t_ns = 0;  ///< camera time of the image pair
  std::vector<FeatureObservation> features;
};

}  // namespace mrvs::edge
