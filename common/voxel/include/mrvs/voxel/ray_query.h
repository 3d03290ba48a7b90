#pragma once
// One ray query, as the edge forms it and the cloud answers it (the paper's 32-byte uplink
// per feature). Positions are map-local: relative to the map origin the cloud announces.
#include <Eigen/Core>

namespace mrvs::voxel {

struct RayQuery {
  Eigen::Vector3f origin = Eigen::Vector3f::Zero();      ///< ray origin (camera centre), m
  float initial_distance = 0.0f;                         ///< d: distance to the triangulated feature, m
  Eigen::Vector3f direction = Eigen::Vector3f::UnitZ();  ///< v: direction (need not be unit)
  float resolution = 0.0f;                               ///< r*: voxel size of the level to traverse, m
};

/// The cloud's answer to one ray (the paper's 12-byte downlink when it hit).
struct RayHit {
  bool hit = false;
  Eigen::Vector3f point = Eigen::Vector3f::Zero();  ///< map-local, m (valid when hit)
  /// Unit normal of the map's surface around the hit when asked for and planar; else zero.
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();
};

}  // namespace mrvs::voxel
