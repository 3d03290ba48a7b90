#include "mrvs/edge/dds_map_service.h"

#include <spdlog/spdlog.h>

namespace mrvs::edge {

StatusOr<std::unique_ptr<DdsMapService>> DdsMapService::create(const MapClientOptions& options) {
  MRVS_ASSIGN_OR_RETURN(std::unique_ptr<MapClient> client, MapClient::create(options));
  return std::unique_ptr<DdsMapService>(new DdsMapService(std::move(client)));
}

std::optional<MapDescription> DdsMapService::description() {
  const auto info = client_->map_info();
  if (!info) return std::nullopt;
  return MapDescription{info->origin, info->resolutions, info->checksum, offers_localisation()};
}

bool DdsMapService::offers_localisation() {
  const auto info = client_->map_info();
  if (!info) return false;
  const std::uint32_t v = info->localisation_protocol_version;
  if (v != 0 && v != wire::LOCALISATION_PROTOCOL_VERSION && !warned_protocol_) {
    spdlog::warn(
        "the cloud speaks localisation protocol {}, this edge {}: no localisation (use matching builds)", v,
        wire::LOCALISATION_PROTOCOL_VERSION);
    warned_protocol_ = true;
  }
  return v == wire::LOCALISATION_PROTOCOL_VERSION;
}

StatusOr<std::size_t> DdsMapService::send_localisation(const localisation::Request& request,
                                                       float quantum_m) {
  return client_->send_localisation(request, quantum_m);
}

std::vector<LocalisationReply> DdsMapService::poll_localisation() {
  std::vector<LocalisationReply> out;
  for (LocalisationAnswer& a : client_->take_localisation_replies()) {
    out.push_back({a.seq, std::move(a.result), a.bytes, a.rtt_ns});
  }
  return out;
}

MapReply DdsMapService::query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns,
                              DurationNs timeout, bool want_normals) {
  MapReply out;
  const QueryReply reply = client_->query(rays, stamp_ns, timeout, want_normals);
  out.rtt_ns = reply.rtt_ns;
  out.answered = reply.outcome == QueryOutcome::kAnswered;
  if (out.answered) {
    out.hits.reserve(reply.answers.size());
    for (const link::RayAnswer& a : reply.answers) out.hits.push_back({a.hit, a.point, a.normal});
    if (outage_) {
      spdlog::warn(
          "the cloud answers again ({} requests without an answer since {} ns); the map is used again",
          outage_requests_, outage_since_ns_);
      outage_ = false;
    }
    return out;
  }
  switch (reply.outcome) {
    case QueryOutcome::kTimeout:
      out.failure = "no reply before the deadline";
      break;
    case QueryOutcome::kRefused:
      out.failure = "refused by the cloud";
      break;
    case QueryOutcome::kSendFailed:
      out.failure = "request not sent";
      break;
    case QueryOutcome::kTooManyRays:
      out.failure = "too many rays for one batch";
      break;
    case QueryOutcome::kAnswered:
      break;
  }
  if (!outage_) {
    spdlog::warn("no answer from the cloud at frame {} ns ({}); going on without map points", stamp_ns,
                 out.failure);
    outage_ = true;
    outage_since_ns_ = stamp_ns;
    outage_requests_ = 0;
  }
  ++outage_requests_;
  return out;
}

}  // namespace mrvs::edge
