#include "mrvs/cloud/localisation_server.h"

#include <algorithm>
#include <deque>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <fastdds/dds/core/condition/GuardCondition.hpp>
#include <fastdds/dds/core/condition/WaitSet.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "mrvs/link/localisation_codec.h"
#include "mrvs_linkPubSubTypes.h"

namespace mrvs::cloud {
namespace {

using eprosima::fastrtps::types::ReturnCode_t;
namespace dds = eprosima::fastdds::dds;
using LStatus = localisation::Status;

}  // namespace

struct LocalisationServer::Dds {
  /// A request waiting for the localiser: its ids (for the reply) and its decoded content.
  struct Queued {
    wire::LocalisationRequest header;  ///< without its points
    localisation::Request request;
    std::size_t bytes_in = 0;
  };
  dds::DataReader* requests = nullptr;
  dds::DataWriter* replies = nullptr;
  dds::GuardCondition stop_condition;
  std::deque<Queued> queue;  ///< serving thread only
};

LocalisationServer::LocalisationServer(std::shared_ptr<const localise::Localiser> localiser,
                                       const LocalisationServerOptions& options)
    : localiser_(std::move(localiser)), options_(options), dds_(std::make_unique<Dds>()) {}

LocalisationServer::~LocalisationServer() { stop(); }

StatusOr<std::unique_ptr<LocalisationServer>> LocalisationServer::create(
    link::Participant& participant, std::shared_ptr<const localise::Localiser> localiser,
    const link::LinkTopics& topics, const LocalisationServerOptions& options) {
  if (!localiser) return absl::InvalidArgumentError("localisation server: no localiser");
  std::unique_ptr<LocalisationServer> s(new LocalisationServer(std::move(localiser), options));
  MRVS_ASSIGN_OR_RETURN(s->dds_->requests,
                        participant.reader(topics.localisation_requests, link::kReaderProfile));
  MRVS_ASSIGN_OR_RETURN(s->dds_->replies,
                        participant.writer(topics.localisation_replies, link::kWriterProfile));
  return s;
}

void LocalisationServer::start() {
  if (!thread_.joinable()) thread_ = std::thread([this] { serve(); });
}

void LocalisationServer::stop() {
  dds_->stop_condition.set_trigger_value(true);
  if (thread_.joinable()) thread_.join();
}

void LocalisationServer::serve() {
  dds::WaitSet waitset;
  dds_->requests->get_statuscondition().set_enabled_statuses(dds::StatusMask::data_available());
  waitset.attach_condition(dds_->requests->get_statuscondition());
  waitset.attach_condition(dds_->stop_condition);
  const eprosima::fastrtps::Duration_t poll(0, 200'000'000);
  while (!dds_->stop_condition.get_trigger_value()) {
    take_arrivals();
    if (!dds_->queue.empty()) {
      answer_next();
      continue;
    }
    dds::ConditionSeq active;
    waitset.wait(active, poll);
  }
}

void LocalisationServer::take_arrivals() {
  wire::LocalisationRequest request;
  dds::SampleInfo info;
  while (dds_->requests->take_next_sample(&request, &info) == ReturnCode_t::RETCODE_OK) {
    if (!info.valid_data) continue;
    const std::size_t bytes_in = link::payload_bytes(request);
    auto decoded = link::decode_localisation_request(request);
    if (!decoded.ok()) {  // answered at once: no registration needed
      const std::string why(decoded.status().message());
      spdlog::warn("localisation: client {} request {}: bad request ({})", request.client_id(),
                   request.request_seq(), why);
      reply(link::refuse_localisation(request, LStatus::kBadRequest, why), request.client_id(), bytes_in);
      continue;
    }
    auto& queue = dds_->queue;
    const auto older = std::find_if(queue.begin(), queue.end(), [&](const Dds::Queued& q) {
      return q.header.client_id() == request.client_id();
    });
    if (older != queue.end()) {
      reply(link::refuse_localisation(older->header, LStatus::kBusy,
                                      "superseded by the client's newer request"),
            older->header.client_id(), older->bytes_in);
      queue.erase(older);
    }
    if (queue.size() >= options_.max_queued) {
      reply(link::refuse_localisation(request, LStatus::kBusy,
                                      fmt::format("{} requests are waiting; ask again later", queue.size())),
            request.client_id(), bytes_in);
      continue;
    }
    Dds::Queued q;
    q.header = request;
    q.header.points().clear();  // the reply needs the ids only
    q.request = std::move(*decoded);
    q.bytes_in = bytes_in;
    queue.push_back(std::move(q));
  }
}

void LocalisationServer::answer_next() {
  const Dds::Queued q = std::move(dds_->queue.front());
  dds_->queue.pop_front();
  const localisation::Result result = localiser_->localise(q.request);
  spdlog::info("localisation: client {} request {} ({} points{}): {} in {:.0f} ms; {}", q.header.client_id(),
               q.header.request_seq(), q.request.points.size(), q.request.prior ? ", prior region" : "",
               localisation::status_name(result.status), result.time_ms, result.detail);
  reply(link::encode_localisation_reply(q.header, result), q.header.client_id(), q.bytes_in);
  std::lock_guard<std::mutex> lock(counters_mutex_);
  counters_[q.header.client_id()].last_time_ms = result.time_ms;
}

void LocalisationServer::reply(const wire::LocalisationReply& reply, std::uint32_t client,
                               std::size_t bytes_in) {
  wire::LocalisationReply sample = reply;
  if (dds_->replies->write(&sample) != true) {
    spdlog::warn("localisation: client {} request {}: the reply could not be written", client,
                 reply.request_seq());
  }
  ++answered_;
  std::lock_guard<std::mutex> lock(counters_mutex_);
  LocalisationCounters& c = counters_[client];
  ++c.requests;
  ++(reply.status() == wire::LOCALISATION_OK ? c.answered_ok : c.refused);
  c.bytes_in += bytes_in;
  c.bytes_out += link::payload_bytes(reply);
}

std::map<std::uint32_t, LocalisationCounters> LocalisationServer::counters() const {
  std::lock_guard<std::mutex> lock(counters_mutex_);
  return counters_;
}

}  // namespace mrvs::cloud
