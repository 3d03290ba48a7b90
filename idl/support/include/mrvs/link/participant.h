#pragma once
// A Fast DDS DomainParticipant for the edge-cloud link, made from one of the project's XML
// profiles (config/dds/*.xml) with optional address overrides, and checked against the
// network safety rules before it is created: no builtin transports (they add shared memory
// and UDP on every interface), only UDPv4 transports restricted to listed interfaces, unicast
// metatraffic (no multicast discovery). A profile that breaks a rule is refused with a
// message naming the rule; nothing is started.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>

#include "mrvs/core/status.h"

namespace mrvs::link {

inline constexpr const char* kParticipantProfile = "mrvs_participant";
inline constexpr const char* kWriterProfile = "mrvs_writer";
inline constexpr const char* kReaderProfile = "mrvs_reader";
inline constexpr const char* kMapInfoWriterProfile = "mrvs_map_info_writer";
inline constexpr const char* kMapInfoReaderProfile = "mrvs_map_info_reader";

inline constexpr const char* kRequestTopic = "mrvs/ray_requests";
inline constexpr const char* kReplyTopic = "mrvs/ray_replies";
inline constexpr const char* kMapInfoTopic = "mrvs/map_info";
inline constexpr const char* kLocalisationRequestTopic = "mrvs/localisation_requests";
inline constexpr const char* kLocalisationReplyTopic = "mrvs/localisation_replies";

struct ParticipantOptions {
  std::filesystem::path profile_file;  ///< config/dds/<profile>.xml
  int domain_id = 42;                  ///< DDS domain
  std::string interface_address;       ///< non-empty: the only interface (whitelist, locators)
  std::vector<std::string> peers;      ///< non-empty: replaces the profile's initial peers
  std::string name = "mrvs";           ///< participant name seen in discovery
};

/// Owns a participant with one publisher and one subscriber; deleting it deletes every
/// entity it created (RAII).
class Participant {
 public:
  static StatusOr<std::unique_ptr<Participant>> create(const ParticipantOptions& options);
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  eprosima::fastdds::dds::DomainParticipant* get() const { return participant_; }
  eprosima::fastdds::dds::Publisher* publisher() const { return publisher_; }
  eprosima::fastdds::dds::Subscriber* subscriber() const { return subscriber_; }

  /// Registers `type` (once) and creates the topic `name`.
  StatusOr<eprosima::fastdds::dds::Topic*> topic(const std::string& name,
                                                 eprosima::fastdds::dds::TypeSupport type);
  /// A writer / reader with QoS from the XML profile `profile` of this participant's file.
  StatusOr<eprosima::fastdds::dds::DataWriter*> writer(eprosima::fastdds::dds::Topic* topic,
                                                       const std::string& profile);
  StatusOr<eprosima::fastdds::dds::DataReader*> reader(eprosima::fastdds::dds::TopicDescription* topic,
                                                       const std::string& profile);

 private:
  Participant() = default;
  eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
  eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
  eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

/// The topics of the link in one participant: ray queries, map info, localisation.
struct LinkTopics {
  eprosima::fastdds::dds::Topic* requests = nullptr;
  eprosima::fastdds::dds::Topic* replies = nullptr;
  eprosima::fastdds::dds::Topic* map_info = nullptr;
  eprosima::fastdds::dds::Topic* localisation_requests = nullptr;
  eprosima::fastdds::dds::Topic* localisation_replies = nullptr;
};
/// Creates them; `request_type` is the requests' type support (the server reads with room
/// beyond the IDL bound, link/types.h). Empty = the generated one.
StatusOr<LinkTopics> create_link_topics(Participant& participant,
                                        eprosima::fastdds::dds::TypeSupport request_type = {});

/// The participant QoS the options would produce (profile + overrides), after the safety
/// checks; for tests and diagnostics. Loads the XML file into the factory.
StatusOr<eprosima::fastdds::dds::DomainParticipantQos> resolve_participant_qos(
    const ParticipantOptions& options);

}  // namespace mrvs::link
