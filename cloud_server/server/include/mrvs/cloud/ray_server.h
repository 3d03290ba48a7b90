#pragma once
// The cloud side of the link: answers RayQueryBatch requests from any number of edge
// clients with the query engine, one reply per request, and publishes the map info
// (transient local). Every request is checked first (too many rays, non-finite values, zero
// direction, negative distance, unknown resolution) and answered with an error status
// instead of points when it fails; the server keeps serving. With a Localiser it also serves
// localisation requests (LocalisationServer) on the same participant.
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "mrvs/cloud/localisation_server.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/link/codec.h"
#include "mrvs/link/participant.h"
#include "mrvs/map/query_engine.h"

namespace mrvs::cloud {

struct RayServerOptions {
  link::ParticipantOptions dds;
  std::string map_id;                           ///< shown to clients (e.g. the map file name)
  std::uint64_t map_checksum = 0;               ///< identifies the map content
  DurationNs stats_period_ns = 10'000'000'000;  ///< log the per-client counters this often (0 = never)
  std::uint64_t max_requests = 0;               ///< stop after answering this many (0 = serve until stop())
  /// The localisation service (design/localisation.md) on the same participant, on its own
  /// thread; nullptr: none (the map info says so).
  std::shared_ptr<const localise::Localiser> localiser;
  LocalisationServerOptions localisation;
};

/// Per-client counters.
struct ClientCounters {
  std::uint64_t requests = 0;
  std::uint64_t rays = 0;
  std::uint64_t hits = 0;
  std::uint64_t rejected_requests = 0;  ///< answered with an error status
  std::uint64_t last_frame_seq = 0;
  TimestampNs last_request_ns = 0;  ///< steady clock
};

class RayServer {
 public:
  static StatusOr<std::unique_ptr<RayServer>> create(map::QueryEngine engine,
                                                     const RayServerOptions& options);
  ~RayServer();

  /// Serves until stop() is called or max_requests are answered. Call from one thread.
  Status run();
  /// Makes run() return soon; thread-safe.
  void stop();

  /// Snapshot of the counters, keyed by client id.
  std::map<std::uint32_t, ClientCounters> counters() const;
  std::uint64_t requests_answered() const { return answered_.load(); }
  /// nullptr without a localiser.
  const LocalisationServer* localisation() const { return localisation_.get(); }

 private:
  struct Dds;
  RayServer(map::QueryEngine engine, const RayServerOptions& options);
  Status publish_map_info();
  /// Checks, answers and counts one request.
  void handle(const wire::RayQueryBatch& request);
  void log_counters() const;

  map::QueryEngine engine_;
  RayServerOptions options_;
  std::unique_ptr<Dds> dds_;
  std::unique_ptr<LocalisationServer> localisation_;  ///< after dds_: stopped before the participant goes
  std::vector<double> resolutions_;
  std::vector<std::optional<Eigen::Vector3f>> hits_;  ///< reused per request
  std::vector<Eigen::Vector3f> normals_;              ///< reused per request (when asked)
  mutable std::mutex counters_mutex_;
  std::map<std::uint32_t, ClientCounters> counters_;
  std::atomic<std::uint64_t> answered_{0};
};

}  // namespace mrvs::cloud
