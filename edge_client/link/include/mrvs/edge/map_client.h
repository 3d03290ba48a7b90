#pragma once
// The edge side of the link: sends a batch of ray queries to the cloud and waits for its
// reply until a deadline, never longer. Replies are correlated by (client id, frame
// sequence); stale and duplicate replies are dropped and counted. When the cloud is absent,
// killed or restarted, queries time out and the caller carries on; when it is back they are
// answered again, without restarting the client.
//
// Not thread-safe: one thread (the estimator's) uses a client.
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/link/codec.h"
#include "mrvs/link/participant.h"
#include "mrvs/localisation/types.h"
#include "mrvs/voxel/ray_query.h"

namespace mrvs::edge {

struct MapClientOptions {
  link::ParticipantOptions dds;
  std::uint32_t client_id = 0;  ///< 0: derived from the process id and the clock
};

enum class QueryOutcome {
  kAnswered,     ///< the reply arrived in time (answers valid)
  kTimeout,      ///< no reply before the deadline
  kRefused,      ///< the cloud answered with an error status (see QueryReply::server_status)
  kSendFailed,   ///< the request could not be written
  kTooManyRays,  ///< more rays than a batch may hold (not sent; split the batch)
};

struct QueryReply {
  QueryOutcome outcome = QueryOutcome::kTimeout;
  std::vector<link::RayAnswer> answers;  ///< one per ray (kAnswered)
  wire::BatchStatus server_status = wire::STATUS_OK;
  std::uint32_t bad_ray_index = 0;
  std::uint64_t frame_seq = 0;
  DurationNs rtt_ns = 0;  ///< write to reply (steady clock); the waited time on timeout
};

struct MapClientStats {
  std::uint64_t sent = 0;
  std::uint64_t answered = 0;
  std::uint64_t refused = 0;
  std::uint64_t timeouts = 0;
  std::uint64_t stale_dropped = 0;    ///< replies to earlier (timed-out) requests
  std::uint64_t foreign_dropped = 0;  ///< replies for other clients (all clients share the reply topic)
  std::uint64_t corrupt_dropped = 0;  ///< replies inconsistent with their request
  std::uint64_t map_changes = 0;      ///< map info updates with a different checksum
  std::uint64_t localisation_sent = 0;
  std::uint64_t localisation_replies = 0;
  std::uint64_t localisation_bytes_up = 0;    ///< CDR payload of the requests
  std::uint64_t localisation_bytes_down = 0;  ///< ... of the replies
};

/// A localisation reply taken by the client.
struct LocalisationAnswer {
  std::uint64_t seq = 0;
  localisation::Result result;
  std::size_t bytes = 0;  ///< CDR payload
  DurationNs rtt_ns = 0;  ///< since the request was written
};

class MapClient {
 public:
  static StatusOr<std::unique_ptr<MapClient>> create(const MapClientOptions& options);
  ~MapClient();

  std::uint32_t client_id() const { return client_id_; }

  /// The latest map info received (nullopt before the first one). Cheap; call every frame.
  std::optional<link::MapInfo> map_info();
  /// Waits up to `timeout` for map info.
  std::optional<link::MapInfo> wait_for_map_info(DurationNs timeout);

  /// Sends `rays` (map-local) as frame `stamp_ns` and waits for the reply at most `timeout`;
  /// `want_normals` asks for the surface normal of each hit (RayAnswer::normal).
  QueryReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns, DurationNs timeout,
                   bool want_normals = false);

  /// Writes a localisation request (points quantised to quantum_m; those out of the int16
  /// range are left out, logged). Returns the payload bytes; error when it cannot be written.
  StatusOr<std::size_t> send_localisation(const localisation::Request& request, float quantum_m);
  /// This client's localisation replies that arrived (decoded; corrupt ones logged, dropped).
  std::vector<LocalisationAnswer> take_localisation_replies();

  const MapClientStats& stats() const { return stats_; }

 private:
  struct Dds;
  MapClient();
  /// Takes replies until the one for `seq` (or none left); returns it when found.
  std::optional<QueryReply> take_reply(std::uint64_t seq, std::size_t num_rays);
  void poll_map_info();

  std::unique_ptr<Dds> dds_;
  std::uint32_t client_id_ = 0;
  std::uint64_t next_seq_ = 1;
  std::optional<link::MapInfo> map_info_;
  std::map<std::uint64_t, std::chrono::steady_clock::time_point> localisation_sent_;  ///< by seq
  MapClientStats stats_;
};

}  // namespace mrvs::edge
