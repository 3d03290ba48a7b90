// Every profile shipped in config/dds/ parses with Fast DDS 2.9, passes the safety checks
// (with the address parameters for the two-host ones) and has the documented QoS.
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/attributes/PublisherAttributes.h>
#include <fastrtps/attributes/SubscriberAttributes.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <gtest/gtest.h>

#include "mrvs/link/participant.h"

namespace mrvs::link {
namespace {

using eprosima::fastrtps::xmlparser::XMLP_ret;
using eprosima::fastrtps::xmlparser::XMLProfileManager;

struct ProfileCase {
  const char* file;
  bool needs_addresses;
  bool fast_heartbeats;
};

class ShippedProfiles : public ::testing::TestWithParam<ProfileCase> {
 protected:
  // Profiles live in one process-wide registry: start every case from an empty one.
  void SetUp() override { XMLProfileManager::DeleteInstance(); }
  void TearDown() override { XMLProfileManager::DeleteInstance(); }
  std::filesystem::path path() const {
    return std::filesystem::path(MRVS_SOURCE_DIR) / "config/dds" / GetParam().file;
  }
};

TEST_P(ShippedProfiles, ParseAndPassTheSafetyChecks) {
  ParticipantOptions options;
  options.profile_file = path();
  if (GetParam().needs_addresses) {
    options.interface_address = "10.77.0.2";
    options.peers = {"10.77.0.1"};
  }
  auto qos = resolve_participant_qos(options);
  ASSERT_TRUE(qos.ok()) << qos.status();
  EXPECT_FALSE(qos->transport().use_builtin_transports);
  EXPECT_TRUE(qos->wire_protocol().builtin.metatrafficMulticastLocatorList.empty());
}

TEST_P(ShippedProfiles, WritersAndReadersHaveTheLinkQos) {
  ASSERT_EQ(XMLProfileManager::loadXMLFile(path().string()), XMLP_ret::XML_OK);
  eprosima::fastrtps::PublisherAttributes writer;
  ASSERT_EQ(XMLProfileManager::fillPublisherAttributes(kWriterProfile, writer, false), XMLP_ret::XML_OK);
  EXPECT_EQ(writer.qos.m_reliability.kind, eprosima::fastrtps::RELIABLE_RELIABILITY_QOS);
  EXPECT_EQ(writer.qos.m_reliability.max_blocking_time.to_ns(), 100'000'000);
  EXPECT_EQ(writer.qos.m_durability.kind, eprosima::fastrtps::VOLATILE_DURABILITY_QOS);
  EXPECT_EQ(writer.qos.m_publishMode.kind, eprosima::fastrtps::SYNCHRONOUS_PUBLISH_MODE);
  EXPECT_EQ(writer.qos.data_sharing.kind(), eprosima::fastdds::dds::OFF);
  EXPECT_EQ(writer.topic.historyQos.kind, eprosima::fastrtps::KEEP_LAST_HISTORY_QOS);
  EXPECT_EQ(writer.topic.historyQos.depth, 16);
  eprosima::fastrtps::SubscriberAttributes reader;
  ASSERT_EQ(XMLProfileManager::fillSubscriberAttributes(kReaderProfile, reader, false), XMLP_ret::XML_OK);
  // The reply topic is shared: a reader keeps its own reply while other clients' arrive.
  EXPECT_EQ(reader.topic.historyQos.kind, eprosima::fastrtps::KEEP_LAST_HISTORY_QOS);
  EXPECT_EQ(reader.topic.historyQos.depth, 16);
  EXPECT_EQ(reader.qos.data_sharing.kind(), eprosima::fastdds::dds::OFF);
  if (GetParam().fast_heartbeats) {
    EXPECT_EQ(writer.times.heartbeatPeriod.to_ns(), 10'000'000);
    EXPECT_EQ(writer.times.nackResponseDelay.to_ns(), 0);
    EXPECT_EQ(reader.times.heartbeatResponseDelay.to_ns(), 0);
  } else {
    EXPECT_GE(writer.times.heartbeatPeriod.to_ns(), 1'000'000'000);  // Fast DDS default (3 s)
  }
  eprosima::fastrtps::PublisherAttributes info;
  ASSERT_EQ(XMLProfileManager::fillPublisherAttributes(kMapInfoWriterProfile, info, false), XMLP_ret::XML_OK);
  EXPECT_EQ(info.qos.m_durability.kind, eprosima::fastrtps::TRANSIENT_LOCAL_DURABILITY_QOS);
}

INSTANTIATE_TEST_SUITE_P(Link, ShippedProfiles,
                         ::testing::Values(ProfileCase{"loopback.xml", false, false},
                                           ProfileCase{"two_hosts.xml", true, false},
                                           ProfileCase{"lossy_link.xml", true, true}));

TEST(ShippedProfilesSafety, TwoHostProfileWithoutAddressesBindsOnlyToTheNamespaceAddress) {
  XMLProfileManager::DeleteInstance();
  ParticipantOptions options;
  options.profile_file = std::filesystem::path(MRVS_SOURCE_DIR) / "config/dds/two_hosts.xml";
  auto qos = resolve_participant_qos(options);
  ASSERT_TRUE(qos.ok()) << qos.status();
  const auto& udp = dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor&>(
      *qos->transport().user_transports[0]);
  EXPECT_EQ(udp.interfaceWhiteList, std::vector<std::string>{"10.77.0.1"});
  XMLProfileManager::DeleteInstance();
}

}  // namespace
}  // namespace mrvs::link
