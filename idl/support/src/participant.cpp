#include "mrvs/link/participant.h"

#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <fmt/format.h>

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include "mrvs_linkPubSubTypes.h"

namespace mrvs::link {
namespace {

using eprosima::fastdds::dds::DomainParticipantFactory;
using eprosima::fastdds::dds::DomainParticipantQos;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;
using eprosima::fastrtps::types::ReturnCode_t;

StatusOr<Locator_t> udp_locator(const std::string& address) {
  Locator_t locator;
  locator.kind = LOCATOR_KIND_UDPv4;
  if (!IPLocator::isIPv4(address) || !IPLocator::setIPv4(locator, address)) {
    return absl::InvalidArgumentError(
        fmt::format("'{}' is not an IPv4 address (--dds-interface / --dds-peer)", address));
  }
  return locator;
}

Status load_profiles(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) {
    return absl::NotFoundError(
        fmt::format("DDS profile {} does not exist; use one of config/dds/*.xml", file.string()));
  }
  DomainParticipantFactory* factory = DomainParticipantFactory::get_instance();
  DomainParticipantQos probe;
  // The factory keeps profiles for the whole process: load a file only once.
  if (factory->get_participant_qos_from_profile(kParticipantProfile, probe) == ReturnCode_t::RETCODE_OK) {
    return absl::OkStatus();
  }
  if (factory->load_XML_profiles_file(file.string()) != ReturnCode_t::RETCODE_OK) {
    return absl::InvalidArgumentError(
        fmt::format("cannot load DDS profile {}: not a valid Fast DDS XML profile file", file.string()));
  }
  return absl::OkStatus();
}

Status apply_overrides(const ParticipantOptions& options, DomainParticipantQos& qos) {
  if (!options.interface_address.empty()) {
    MRVS_ASSIGN_OR_RETURN(const Locator_t local, udp_locator(options.interface_address));
    auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
    udp->interfaceWhiteList = {options.interface_address};
    qos.transport().user_transports = {udp};
    qos.wire_protocol().builtin.metatrafficUnicastLocatorList.clear();
    qos.wire_protocol().builtin.metatrafficUnicastLocatorList.push_back(local);
    qos.wire_protocol().default_unicast_locator_list.clear();
    qos.wire_protocol().default_unicast_locator_list.push_back(local);
  }
  if (!options.peers.empty()) {
    qos.wire_protocol().builtin.initialPeersList.clear();
    for (const std::string& peer : options.peers) {
      MRVS_ASSIGN_OR_RETURN(const Locator_t locator, udp_locator(peer));
      qos.wire_protocol().builtin.initialPeersList.push_back(locator);
    }
  }
  qos.name(options.name);
  return absl::OkStatus();
}

/// The project's network safety rules (README, transport.md rule 1).
Status check_safe(const DomainParticipantQos& qos, const std::filesystem::path& file) {
  const std::string where = fmt::format("DDS profile {}", file.string());
  if (qos.transport().use_builtin_transports) {
    return absl::FailedPreconditionError(fmt::format(
        "{}: useBuiltinTransports must be false (the builtin transports add shared memory and UDP on every "
        "interface)",
        where));
  }
  if (qos.transport().user_transports.empty()) {
    return absl::FailedPreconditionError(fmt::format("{}: no user transport is configured", where));
  }
  for (const auto& transport : qos.transport().user_transports) {
    const auto* udp = dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor*>(transport.get());
    if (udp == nullptr) {
      return absl::FailedPreconditionError(fmt::format("{}: only UDPv4 transports are allowed", where));
    }
    if (udp->interfaceWhiteList.empty()) {
      return absl::FailedPreconditionError(fmt::format(
          "{}: the UDPv4 transport needs an interfaceWhiteList (or pass --dds-interface)", where));
    }
  }
  const auto& builtin = qos.wire_protocol().builtin;
  if (builtin.metatrafficUnicastLocatorList.empty()) {
    return absl::FailedPreconditionError(fmt::format(
        "{}: set builtin.metatrafficUnicastLocatorList, otherwise Fast DDS discovers over multicast", where));
  }
  if (!builtin.metatrafficMulticastLocatorList.empty()) {
    return absl::FailedPreconditionError(
        fmt::format("{}: multicast metatraffic locators are not allowed", where));
  }
  if (builtin.initialPeersList.empty()) {
    return absl::FailedPreconditionError(fmt::format(
        "{}: builtin.initialPeersList is empty, so no peer can be discovered (or pass --dds-peer)", where));
  }
  return absl::OkStatus();
}

}  // namespace

StatusOr<DomainParticipantQos> resolve_participant_qos(const ParticipantOptions& options) {
  MRVS_RETURN_IF_ERROR(load_profiles(options.profile_file));
  DomainParticipantQos qos;
  if (DomainParticipantFactory::get_instance()->get_participant_qos_from_profile(kParticipantProfile, qos) !=
      ReturnCode_t::RETCODE_OK) {
    return absl::InvalidArgumentError(fmt::format("DDS profile {} has no participant profile named '{}'",
                                                  options.profile_file.string(), kParticipantProfile));
  }
  MRVS_RETURN_IF_ERROR(apply_overrides(options, qos));
  MRVS_RETURN_IF_ERROR(check_safe(qos, options.profile_file));
  return qos;
}

StatusOr<std::unique_ptr<Participant>> Participant::create(const ParticipantOptions& options) {
  if (options.domain_id < 0 || options.domain_id > 232) {
    return absl::InvalidArgumentError(fmt::format("DDS domain {} is outside [0, 232]", options.domain_id));
  }
  MRVS_ASSIGN_OR_RETURN(const DomainParticipantQos qos, resolve_participant_qos(options));
  std::unique_ptr<Participant> p(new Participant());
  p->participant_ = DomainParticipantFactory::get_instance()->create_participant(options.domain_id, qos);
  if (p->participant_ == nullptr) {
    return absl::UnavailableError(fmt::format(
        "cannot create the DDS participant (profile {}): is the interface address up on this host?",
        options.profile_file.string()));
  }
  p->publisher_ = p->participant_->create_publisher(eprosima::fastdds::dds::PUBLISHER_QOS_DEFAULT);
  p->subscriber_ = p->participant_->create_subscriber(eprosima::fastdds::dds::SUBSCRIBER_QOS_DEFAULT);
  if (p->publisher_ == nullptr || p->subscriber_ == nullptr) {
    return absl::InternalError("cannot create the DDS publisher or subscriber");
  }
  return p;
}

Participant::~Participant() {
  if (participant_ == nullptr) return;
  participant_->delete_contained_entities();
  DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

StatusOr<eprosima::fastdds::dds::Topic*> Participant::topic(const std::string& name,
                                                            eprosima::fastdds::dds::TypeSupport type) {
  if (participant_->find_type(type.get_type_name()) == nullptr &&
      type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
    return absl::InternalError(fmt::format("cannot register DDS type {}", type.get_type_name()));
  }
  auto* topic =
      participant_->create_topic(name, type.get_type_name(), eprosima::fastdds::dds::TOPIC_QOS_DEFAULT);
  if (topic == nullptr) return absl::InternalError(fmt::format("cannot create DDS topic {}", name));
  return topic;
}

StatusOr<eprosima::fastdds::dds::DataWriter*> Participant::writer(eprosima::fastdds::dds::Topic* topic,
                                                                  const std::string& profile) {
  auto* w = publisher_->create_datawriter_with_profile(topic, profile);
  if (w == nullptr) {
    return absl::InternalError(
        fmt::format("cannot create the DDS writer of {} (profile '{}')", topic->get_name(), profile));
  }
  return w;
}

StatusOr<eprosima::fastdds::dds::DataReader*> Participant::reader(
    eprosima::fastdds::dds::TopicDescription* topic, const std::string& profile) {
  auto* r = subscriber_->create_datareader_with_profile(topic, profile);
  if (r == nullptr) {
    return absl::InternalError(
        fmt::format("cannot create the DDS reader of {} (profile '{}')", topic->get_name(), profile));
  }
  return r;
}

StatusOr<LinkTopics> create_link_topics(Participant& participant,
                                        eprosima::fastdds::dds::TypeSupport request_type) {
  namespace dds = eprosima::fastdds::dds;
  if (request_type.empty()) request_type = dds::TypeSupport(new wire::RayQueryBatchPubSubType());
  LinkTopics topics;
  MRVS_ASSIGN_OR_RETURN(topics.requests, participant.topic(kRequestTopic, request_type));
  MRVS_ASSIGN_OR_RETURN(
      topics.replies, participant.topic(kReplyTopic, dds::TypeSupport(new wire::RayReplyBatchPubSubType())));
  MRVS_ASSIGN_OR_RETURN(topics.map_info,
                        participant.topic(kMapInfoTopic, dds::TypeSupport(new wire::MapInfoPubSubType())));
  MRVS_ASSIGN_OR_RETURN(topics.localisation_requests,
                        participant.topic(kLocalisationRequestTopic,
                                          dds::TypeSupport(new wire::LocalisationRequestPubSubType())));
  MRVS_ASSIGN_OR_RETURN(
      topics.localisation_replies,
      participant.topic(kLocalisationReplyTopic, dds::TypeSupport(new wire::LocalisationReplyPubSubType())));
  return topics;
}

}  // namespace mrvs::link
