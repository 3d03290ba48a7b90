#pragma once
// The estimator's MapService over Fast DDS (the thin adapter between the IDL world of
// MapClient and the estimator's types). Logs the cloud's outages and returns once, not per
// frame: "no answer from the cloud since ..." and "the cloud answers again after ...".
#include <memory>

#include "mrvs/edge/map_client.h"
#include "mrvs/edge/map_service.h"

namespace mrvs::edge {

class DdsMapService : public MapService {
 public:
  static StatusOr<std::unique_ptr<DdsMapService>> create(const MapClientOptions& options);

  std::optional<MapDescription> description() override;
  MapReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns, DurationNs timeout,
                 bool want_normals) override;
  bool offers_localisation() override;
  StatusOr<std::size_t> send_localisation(const localisation::Request& request, float quantum_m) override;
  std::vector<LocalisationReply> poll_localisation() override;

  const MapClientStats& stats() const { return client_->stats(); }
  MapClient& client() { return *client_; }

 private:
  explicit DdsMapService(std::unique_ptr<MapClient> client) : client_(std::move(client)) {}
  std::unique_ptr<MapClient> client_;
  bool outage_ = false;
  TimestampNs outage_since_ns_ = 0;
  std::uint64_t outage_requests_ = 0;
  bool warned_protocol_ = false;
};

}  // namespace mrvs::edge
