#pragma once
// The cloud in process (no middleware): ray queries answered by a QueryEngine, localisation
// requests by a Localiser, behind the estimator's MapService. A localisation request is
// answered at once, as the wire would carry it (points quantised); its reply is held back
// until `latency` of the sensor clock has passed after the request's stamp (set it to the
// cloud's registration time to play a run in real time), or returned at the next poll.
#include <deque>
#include <memory>
#include <optional>

#include "mrvs/edge/map_service.h"
#include "mrvs/localise/localiser.h"
#include "mrvs/map/query_engine.h"

namespace mrvs::test {

class InProcessCloud : public edge::MapService {
 public:
  /// `localiser` may be null (no localisation service).
  InProcessCloud(std::shared_ptr<const map::QueryEngine> engine,
                 std::shared_ptr<const localise::Localiser> localiser);

  std::optional<edge::MapDescription> description() override;
  edge::MapReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns, DurationNs timeout,
                       bool want_normals) override;
  bool offers_localisation() override { return localiser_ != nullptr && answer; }
  StatusOr<std::size_t> send_localisation(const localisation::Request& request, float quantum_m) override;
  std::vector<edge::LocalisationReply> poll_localisation() override;

  /// The sensor time now (the replies due by then are returned by poll_localisation).
  void set_now(TimestampNs t_ns) { now_ns_ = t_ns; }
  /// Hold each reply for the registration time it took (sensor clock), as a real-time run would.
  bool real_time_replies = true;
  /// false: an outage (no answers, no localisation).
  bool answer = true;

  /// Every request and its result, in order (for probes and tests).
  struct Exchange {
    localisation::Request request;
    localisation::Result result;
  };
  const std::vector<Exchange>& exchanges() const { return exchanges_; }

 private:
  std::shared_ptr<const map::QueryEngine> engine_;
  std::shared_ptr<const localise::Localiser> localiser_;
  std::deque<std::pair<TimestampNs, edge::LocalisationReply>> due_;  ///< (due time, reply)
  std::vector<Exchange> exchanges_;
  TimestampNs now_ns_ = 0;
};

}  // namespace mrvs::test
