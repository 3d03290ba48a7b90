#pragma once
// The cloud's localisation service on the link (design/localisation.md): takes
// LocalisationRequest samples from any number of edge clients, answers each with the
// Localiser on its own thread (a registration takes up to about half a second; ray queries are
// answered meanwhile by the RayServer's thread), one reply per request. Malformed requests are
// answered "bad request" with the reason; when more than max_queued requests wait, the newest
// are answered "busy"; a client's older request still waiting is superseded by its newer one
// (answered "busy"). The server keeps serving whatever it receives.
#include <atomic>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <thread>

#include "mrvs/core/status.h"
#include "mrvs/link/participant.h"
#include "mrvs/localise/localiser.h"

namespace mrvs::wire {
class LocalisationReply;
}

namespace mrvs::cloud {

struct LocalisationServerOptions {
  std::size_t max_queued = 16;  ///< waiting requests; more are answered "busy"
};

struct LocalisationCounters {
  std::uint64_t requests = 0;
  std::uint64_t answered_ok = 0;
  std::uint64_t refused = 0;   ///< any other status
  std::uint64_t bytes_in = 0;  ///< CDR payload of the requests
  std::uint64_t bytes_out = 0;
  double last_time_ms = 0.0;
};

class LocalisationServer {
 public:
  /// Creates the reader and writer on `participant` (which must outlive the server).
  static StatusOr<std::unique_ptr<LocalisationServer>> create(
      link::Participant& participant, std::shared_ptr<const localise::Localiser> localiser,
      const link::LinkTopics& topics, const LocalisationServerOptions& options = {});
  ~LocalisationServer();

  /// Starts the serving thread (once).
  void start();
  /// Stops it and waits for the request being answered; thread-safe, idempotent.
  void stop();

  std::map<std::uint32_t, LocalisationCounters> counters() const;
  std::uint64_t answered() const { return answered_.load(); }

 private:
  struct Dds;
  LocalisationServer(std::shared_ptr<const localise::Localiser> localiser,
                     const LocalisationServerOptions& options);
  void serve();
  /// Takes what arrived into the queue (answering the malformed and the excess at once).
  void take_arrivals();
  void answer_next();
  void reply(const wire::LocalisationReply& reply, std::uint32_t client, std::size_t bytes_in);

  std::shared_ptr<const localise::Localiser> localiser_;
  LocalisationServerOptions options_;
  std::unique_ptr<Dds> dds_;
  std::thread thread_;
  mutable std::mutex counters_mutex_;
  std::map<std::uint32_t, LocalisationCounters> counters_;
  std::atomic<std::uint64_t> answered_{0};
};

}  // namespace mrvs::cloud
