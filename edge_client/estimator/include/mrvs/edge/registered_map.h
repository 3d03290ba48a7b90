#pragma once
// The registered-point voxel grid (algorithm.md 4.1-4.3, Voxel-SVIO's voxel map): map points
// registered into the state live in voxels of `voxel_m` holding at most `per_voxel` each;
// the neighbourhood of a voxel decides which points are suitable for an update. Floor keys
// (mrvs/voxel/voxel_key.h), not the reference code's int16 truncation. Positions are world
// (map frame) and should be relative to the map origin for UTM-sized coordinates.
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "mrvs/edge/feature_observation.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::edge {

class RegisteredMap {
 public:
  RegisteredMap(double voxel_m, int per_voxel) : voxel_m_(voxel_m), per_voxel_(per_voxel) {}

  /// True when `p`'s voxel can take one more point.
  bool has_room(const Vec3d& p) const;
  /// Adds point `id` at p; false (and nothing added) when its voxel is full or p is invalid.
  bool add(FeatureId id, const Vec3d& p);
  /// Moves `id` to the voxel of p when it changed and that voxel has room.
  void move(FeatureId id, const Vec3d& p);
  void remove(FeatureId id);
  /// Points in the (2 radius + 1)^3 voxels around p.
  std::vector<FeatureId> neighbourhood(const Vec3d& p, int radius) const;
  std::size_t size() const { return host_.size(); }
  bool contains(FeatureId id) const { return host_.count(id) != 0; }

 private:
  std::optional<std::uint64_t> key_of(const Vec3d& p) const;
  double voxel_m_;
  int per_voxel_;
  std::unordered_map<std::uint64_t, std::vector<FeatureId>> cells_;
  std::unordered_map<FeatureId, std::uint64_t> host_;
};

}  // namespace mrvs::edge
