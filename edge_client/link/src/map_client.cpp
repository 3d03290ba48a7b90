#include "mrvs/edge/map_client.h"

#include <unistd.h>

#include <chrono>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "mrvs/core/hash.h"
#include "mrvs/link/localisation_codec.h"
#include "mrvs_linkPubSubTypes.h"

namespace mrvs::edge {
namespace {

using eprosima::fastrtps::types::ReturnCode_t;
namespace dds = eprosima::fastdds::dds;
using Clock = std::chrono::steady_clock;

DurationNs since(Clock::time_point t0) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
}

eprosima::fastrtps::Duration_t to_dds(DurationNs ns) {
  ns = std::max<DurationNs>(ns, 0);
  return eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(ns / 1'000'000'000),
                                        static_cast<std::uint32_t>(ns % 1'000'000'000));
}

std::uint32_t make_client_id() {
  const auto t = static_cast<std::uint64_t>(Clock::now().time_since_epoch().count());
  const std::uint32_t id =
      static_cast<std::uint32_t>(mix64(t ^ (static_cast<std::uint64_t>(::getpid()) << 32)));
  return id == 0 ? 1 : id;
}

}  // namespace

struct MapClient::Dds {
  std::unique_ptr<link::Participant> participant;
  dds::DataWriter* requests = nullptr;
  dds::DataReader* replies = nullptr;
  dds::DataReader* map_info = nullptr;
  dds::DataWriter* localisation_requests = nullptr;
  dds::DataReader* localisation_replies = nullptr;
};

MapClient::MapClient() : dds_(std::make_unique<Dds>()) {}
MapClient::~MapClient() = default;

StatusOr<std::unique_ptr<MapClient>> MapClient::create(const MapClientOptions& options) {
  std::unique_ptr<MapClient> c(new MapClient());
  c->client_id_ = options.client_id != 0 ? options.client_id : make_client_id();
  Dds& d = *c->dds_;
  MRVS_ASSIGN_OR_RETURN(d.participant, link::Participant::create(options.dds));
  MRVS_ASSIGN_OR_RETURN(const link::LinkTopics topics, link::create_link_topics(*d.participant));
  // Every client reads the one reply topic and keeps its own replies (client id, frame
  // sequence). A content-filtered topic would need type objects (fastddsgen -typeobject),
  // which Fast DDS 2.9 encodes ~100x slower; per-client topics would lose the first replies
  // to discovery. Cost: each client also receives the other clients' replies.
  MRVS_ASSIGN_OR_RETURN(d.requests, d.participant->writer(topics.requests, link::kWriterProfile));
  MRVS_ASSIGN_OR_RETURN(d.replies, d.participant->reader(topics.replies, link::kReaderProfile));
  MRVS_ASSIGN_OR_RETURN(d.map_info, d.participant->reader(topics.map_info, link::kMapInfoReaderProfile));
  MRVS_ASSIGN_OR_RETURN(d.localisation_requests,
                        d.participant->writer(topics.localisation_requests, link::kWriterProfile));
  MRVS_ASSIGN_OR_RETURN(d.localisation_replies,
                        d.participant->reader(topics.localisation_replies, link::kReaderProfile));
  return c;
}

void MapClient::poll_map_info() {
  wire::MapInfo sample;
  dds::SampleInfo info;
  while (dds_->map_info->take_next_sample(&sample, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    auto decoded = link::decode_map_info(sample);
    if (!decoded.ok()) {
      spdlog::error("map info ignored: {}", std::string(decoded.status().message()));
      continue;
    }
    if (map_info_ && map_info_->checksum != decoded->checksum) {
      ++stats_.map_changes;
      spdlog::warn("the cloud's map changed: {} (checksum {:016x})", decoded->map_id, decoded->checksum);
    }
    map_info_ = *decoded;
  }
}

std::optional<link::MapInfo> MapClient::map_info() {
  poll_map_info();
  return map_info_;
}

std::optional<link::MapInfo> MapClient::wait_for_map_info(DurationNs timeout) {
  const Clock::time_point start = Clock::now();
  dds::WaitSet waitset;
  dds_->map_info->get_statuscondition().set_enabled_statuses(dds::StatusMask::data_available());
  waitset.attach_condition(dds_->map_info->get_statuscondition());
  while (!map_info() && since(start) < timeout) {
    dds::ConditionSeq active;
    waitset.wait(active, to_dds(timeout - since(start)));
  }
  return map_info_;
}

std::optional<QueryReply> MapClient::take_reply(std::uint64_t seq, std::size_t num_rays) {
  wire::RayReplyBatch reply;
  dds::SampleInfo info;
  while (dds_->replies->take_next_sample(&reply, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    if (reply.client_id() != client_id_) {
      ++stats_.foreign_dropped;
      continue;
    }
    if (reply.frame_seq() != seq) {
      ++stats_.stale_dropped;  // an earlier request's late reply, or a duplicate
      continue;
    }
    QueryReply out;
    out.frame_seq = seq;
    out.server_status = reply.status();
    out.bad_ray_index = reply.bad_ray_index();
    if (reply.status() != wire::STATUS_OK) {
      out.outcome = QueryOutcome::kRefused;
      return out;
    }
    auto answers = link::decode_reply(reply, num_rays);
    if (!answers.ok()) {
      ++stats_.corrupt_dropped;
      spdlog::warn("{}", std::string(answers.status().message()));
      continue;
    }
    out.outcome = QueryOutcome::kAnswered;
    out.answers = std::move(*answers);
    return out;
  }
  return std::nullopt;
}

QueryReply MapClient::query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns,
                            DurationNs timeout, bool want_normals) {
  const std::uint64_t seq = next_seq_++;
  const std::size_t limit =
      map_info_ ? std::min<std::size_t>(map_info_->max_rays_per_batch, wire::MAX_RAYS_PER_BATCH)
                : wire::MAX_RAYS_PER_BATCH;
  if (rays.size() > limit) {
    QueryReply refused;
    refused.outcome = QueryOutcome::kTooManyRays;
    refused.frame_seq = seq;
    refused.server_status = wire::STATUS_TOO_MANY_RAYS;
    refused.bad_ray_index = static_cast<std::uint32_t>(limit);
    return refused;
  }
  wire::RayQueryBatch request = link::encode_request(client_id_, seq, stamp_ns, rays, want_normals);
  dds::WaitSet waitset;
  dds_->replies->get_statuscondition().set_enabled_statuses(dds::StatusMask::data_available());
  waitset.attach_condition(dds_->replies->get_statuscondition());
  const Clock::time_point start = Clock::now();
  ++stats_.sent;
  if (!dds_->requests->write(&request)) {
    QueryReply failed;
    failed.outcome = QueryOutcome::kSendFailed;
    failed.frame_seq = seq;
    return failed;
  }
  for (;;) {
    if (std::optional<QueryReply> reply = take_reply(seq, rays.size())) {
      reply->rtt_ns = since(start);
      ++(reply->outcome == QueryOutcome::kAnswered ? stats_.answered : stats_.refused);
      return *reply;
    }
    const DurationNs left = timeout - since(start);
    if (left <= 0) break;
    dds::ConditionSeq active;
    waitset.wait(active, to_dds(left));
  }
  ++stats_.timeouts;
  QueryReply timed_out;
  timed_out.frame_seq = seq;
  timed_out.rtt_ns = since(start);
  return timed_out;
}

StatusOr<std::size_t> MapClient::send_localisation(const localisation::Request& request, float quantum_m) {
  std::size_t dropped = 0;
  wire::LocalisationRequest w = link::encode_localisation_request(client_id_, request, quantum_m, &dropped);
  if (dropped > 0) {
    spdlog::warn(
        "localisation request {}: {} of {} points left out (beyond {} m of the anchor or the {}-point bound)",
        request.seq, dropped, request.points.size(), 32767.0 * quantum_m, wire::MAX_SUBMAP_POINTS);
  }
  const std::size_t bytes = link::payload_bytes(w);
  if (!dds_->localisation_requests->write(&w)) {
    return absl::UnavailableError(fmt::format("localisation request {} could not be written", request.seq));
  }
  ++stats_.localisation_sent;
  stats_.localisation_bytes_up += bytes;
  localisation_sent_[request.seq] = Clock::now();
  while (localisation_sent_.size() > 64) localisation_sent_.erase(localisation_sent_.begin());
  return bytes;
}

std::vector<LocalisationAnswer> MapClient::take_localisation_replies() {
  std::vector<LocalisationAnswer> out;
  wire::LocalisationReply reply;
  dds::SampleInfo info;
  while (dds_->localisation_replies->take_next_sample(&reply, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data || reply.client_id() != client_id_) continue;
    const auto sent = localisation_sent_.find(reply.request_seq());
    if (sent == localisation_sent_.end()) continue;  // a duplicate, or not ours
    auto decoded = link::decode_localisation_reply(reply);
    if (!decoded.ok()) {
      ++stats_.corrupt_dropped;
      spdlog::warn("localisation reply dropped: {}", std::string(decoded.status().message()));
      continue;
    }
    LocalisationAnswer a;
    a.seq = reply.request_seq();
    a.result = std::move(*decoded);
    a.bytes = link::payload_bytes(reply);
    a.rtt_ns = since(sent->second);
    localisation_sent_.erase(sent);
    ++stats_.localisation_replies;
    stats_.localisation_bytes_down += a.bytes;
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace mrvs::edge
