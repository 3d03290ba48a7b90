#include "mrvs/cloud/ray_server.h"

#include <chrono>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "mrvs/link/types.h"
#include "mrvs_linkPubSubTypes.h"

namespace mrvs::cloud {
namespace {

using eprosima::fastrtps::types::ReturnCode_t;
namespace dds = eprosima::fastdds::dds;

TimestampNs steady_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

struct RayServer::Dds {
  std::unique_ptr<link::Participant> participant;
  dds::DataReader* requests = nullptr;
  dds::DataWriter* replies = nullptr;
  dds::DataWriter* map_info = nullptr;
  dds::GuardCondition stop_condition;
};

RayServer::RayServer(map::QueryEngine engine, const RayServerOptions& options)
    : engine_(std::move(engine)), options_(options), dds_(std::make_unique<Dds>()) {}

RayServer::~RayServer() = default;

StatusOr<std::unique_ptr<RayServer>> RayServer::create(map::QueryEngine engine,
                                                       const RayServerOptions& options) {
  std::unique_ptr<RayServer> server(new RayServer(std::move(engine), options));
  server->resolutions_ = server->engine_.map().resolutions();
  Dds& d = *server->dds_;
  MRVS_ASSIGN_OR_RETURN(d.participant, link::Participant::create(options.dds));
  // Requests are read with room beyond the IDL bound: an oversized batch gets an error reply
  // instead of being dropped by the middleware (link/types.h).
  MRVS_ASSIGN_OR_RETURN(const link::LinkTopics topics,
                        link::create_link_topics(*d.participant, link::request_type(link::kMaxRaysReceived)));
  MRVS_ASSIGN_OR_RETURN(d.requests, d.participant->reader(topics.requests, link::kReaderProfile));
  MRVS_ASSIGN_OR_RETURN(d.replies, d.participant->writer(topics.replies, link::kWriterProfile));
  MRVS_ASSIGN_OR_RETURN(d.map_info, d.participant->writer(topics.map_info, link::kMapInfoWriterProfile));
  if (options.localiser) {
    MRVS_ASSIGN_OR_RETURN(server->localisation_, LocalisationServer::create(*d.participant, options.localiser,
                                                                            topics, options.localisation));
  }
  MRVS_RETURN_IF_ERROR(server->publish_map_info());
  return server;
}

Status RayServer::publish_map_info() {
  link::MapInfo info;
  info.map_id = options_.map_id;
  info.origin = engine_.map().origin;
  info.checksum = options_.map_checksum;
  info.resolutions = resolutions_;
  info.max_rays_per_batch = static_cast<std::uint32_t>(engine_.options().max_rays_per_batch);
  info.localisation_protocol_version = localisation_ ? wire::LOCALISATION_PROTOCOL_VERSION : 0;
  wire::MapInfo sample = link::encode_map_info(info);
  if (dds_->map_info->write(&sample) != true) return absl::InternalError("cannot publish the map info");
  return absl::OkStatus();
}

void RayServer::handle(const wire::RayQueryBatch& request) {
  const link::RequestCheck check = link::check_request(
      request, static_cast<std::size_t>(engine_.options().max_rays_per_batch), resolutions_);
  std::uint64_t hits = 0;
  hits_.assign(check.status == wire::STATUS_OK ? request.rays().size() : 0, std::nullopt);
  normals_.assign(request.want_normals() ? hits_.size() : 0, Eigen::Vector3f::Zero());
  for (std::size_t i = 0; i < hits_.size(); ++i) {
    const map::QueryResult result = engine_.query(link::decode_ray(request.rays()[i]));
    if (result.status != map::QueryStatus::kHit) continue;
    hits_[i] = result.point;
    ++hits;
    if (normals_.empty()) continue;
    if (const auto n = engine_.surface_normal(result.level, result.point)) normals_[i] = *n;
  }
  if (check.status != wire::STATUS_OK) {
    spdlog::warn("client {} frame {}: {} ({})", request.client_id(), request.frame_seq(),
                 link::status_name(check.status), check.detail);
  }
  wire::RayReplyBatch reply = link::encode_reply(request, check, hits_, normals_);
  if (dds_->replies->write(&reply) != true) {
    spdlog::warn("client {} frame {}: the reply could not be written", request.client_id(),
                 request.frame_seq());
  }
  std::lock_guard<std::mutex> lock(counters_mutex_);
  ClientCounters& c = counters_[request.client_id()];
  ++c.requests;
  c.rays += request.rays().size();
  c.hits += hits;
  c.rejected_requests += check.status != wire::STATUS_OK;
  c.last_frame_seq = request.frame_seq();
  c.last_request_ns = steady_now_ns();
}

Status RayServer::run() {
  if (localisation_) localisation_->start();
  dds::WaitSet waitset;
  dds_->requests->get_statuscondition().set_enabled_statuses(dds::StatusMask::data_available());
  waitset.attach_condition(dds_->requests->get_statuscondition());
  waitset.attach_condition(dds_->stop_condition);
  const eprosima::fastrtps::Duration_t poll(0, 200'000'000);
  TimestampNs last_stats = steady_now_ns();
  wire::RayQueryBatch request;
  dds::SampleInfo info;
  while (!dds_->stop_condition.get_trigger_value()) {
    dds::ConditionSeq active;
    waitset.wait(active, poll);  // timeout is fine: it only paces the stats log
    while (dds_->requests->take_next_sample(&request, &info) == ReturnCode_t::RETCODE_OK) {
      if (!info.valid_data) continue;  // a writer went away
      handle(request);
      const std::uint64_t n = ++answered_;
      if (options_.max_requests > 0 && n >= options_.max_requests) stop();
    }
    if (options_.stats_period_ns > 0 && steady_now_ns() - last_stats >= options_.stats_period_ns) {
      log_counters();
      last_stats = steady_now_ns();
    }
  }
  if (localisation_) localisation_->stop();
  log_counters();
  return absl::OkStatus();
}

void RayServer::stop() { dds_->stop_condition.set_trigger_value(true); }

std::map<std::uint32_t, ClientCounters> RayServer::counters() const {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  return counters_;
}

void RayServer::log_counters() const {
  for (const auto& [id, c] : counters()) {
    spdlog::info("client {}: {} requests ({} refused), {} rays, {} hits ({:.1f} %), last frame {}", id,
                 c.requests, c.rejected_requests, c.rays, c.hits, c.rays > 0 ? 100.0 * c.hits / c.rays : 0.0,
                 c.last_frame_seq);
  }
  if (!localisation_) return;
  for (const auto& [id, c] : localisation_->counters()) {
    spdlog::info("client {}: {} localisation requests ({} answered ok), {} B in, {} B out, last {:.0f} ms",
                 id, c.requests, c.answered_ok, c.bytes_in, c.bytes_out, c.last_time_ms);
  }
}

}  // namespace mrvs::cloud
