#pragma once
// What the estimator needs from the cloud's map (no middleware here): its description and
// batches of ray queries answered by a deadline. edge_client/link implements it over Fast
// DDS (DdsMapService); tests implement it in process on a QueryEngine.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/voxel/ray_query.h"

namespace mrvs::edge {

struct MapDescription {
  Vec3d origin = Vec3d::Zero();     ///< map frame, m: rays and hits are relative to it
  std::vector<double> resolutions;  ///< voxel sizes of the levels, m
  std::uint64_t checksum = 0;
};

struct MapReply {
  bool answered = false;            ///< false: timed out, refused or not sent (see failure)
  std::vector<voxel::RayHit> hits;  ///< one per ray when answered
  DurationNs rtt_ns = 0;            ///< request to reply (or the time waited)
  std::string failure;              ///< why not answered
};

class MapService {
 public:
  virtual ~MapService() = default;
  /// The map's description once known (nullopt while the cloud is not heard from).
  virtual std::optional<MapDescription> description() = 0;
  /// Answers `rays` (map-local) by `timeout` at the latest; with `want_normals`, each hit
  /// also carries the surface normal there (RayHit::normal).
  virtual MapReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns, DurationNs timeout,
                         bool want_normals) = 0;
};

}  // namespace mrvs::edge
