#pragma once
// What the estimator needs from the cloud's map (no middleware here): its description,
// batches of ray queries answered by a deadline, and the localisation service (asynchronous:
// a request is sent, its reply picked up at a later frame). edge_client/link implements it
// over Fast DDS (DdsMapService); tests implement it in process on a QueryEngine / Localiser.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/localisation/types.h"
#include "mrvs/voxel/ray_query.h"

namespace mrvs::edge {

struct MapDescription {
  Vec3d origin = Vec3d::Zero();     ///< map frame, m: rays and hits are relative to it
  std::vector<double> resolutions;  ///< voxel sizes of the levels, m
  std::uint64_t checksum = 0;
  bool localisation = false;  ///< the cloud serves localisation requests (our protocol)
};

struct MapReply {
  bool answered = false;            ///< false: timed out, refused or not sent (see failure)
  std::vector<voxel::RayHit> hits;  ///< one per ray when answered
  DurationNs rtt_ns = 0;            ///< request to reply (or the time waited)
  std::string failure;              ///< why not answered
};

/// A localisation reply as the estimator sees it.
struct LocalisationReply {
  std::uint64_t seq = 0;  ///< the request's
  localisation::Result result;
  std::size_t bytes_down = 0;  ///< payload of the reply on the wire
  DurationNs rtt_ns = 0;       ///< request sent to reply taken (steady clock)
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

  /// Whether the cloud serves localisation (known from its map description).
  virtual bool offers_localisation() { return false; }
  /// Sends `request` (points quantised to `quantum_m`) without waiting; the payload bytes
  /// sent, or why it could not be sent.
  virtual StatusOr<std::size_t> send_localisation(const localisation::Request& /*request*/,
                                                  float /*quantum_m*/) {
    return absl::UnimplementedError("this map service has no localisation");
  }
  /// The replies that arrived since the last call (each once).
  virtual std::vector<LocalisationReply> poll_localisation() { return {}; }
};

}  // namespace mrvs::edge
