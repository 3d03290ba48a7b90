// The participant QoS the project's profiles produce obey the network safety rules.
// (QoS only: no participant is created, nothing is sent.)
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/link/participant.h"

namespace mrvs::link {
namespace {

using eprosima::fastrtps::rtps::IPLocator;
using ::testing::HasSubstr;

const std::filesystem::path kLoopback = std::filesystem::path(MRVS_SOURCE_DIR) / "config/dds/loopback.xml";

ParticipantOptions with_profile(const std::filesystem::path& file) {
  ParticipantOptions options;
  options.profile_file = file;
  return options;
}

const eprosima::fastdds::rtps::UDPv4TransportDescriptor& only_udp(
    const eprosima::fastdds::dds::DomainParticipantQos& qos) {
  EXPECT_EQ(qos.transport().user_transports.size(), 1u);
  return dynamic_cast<const eprosima::fastdds::rtps::UDPv4TransportDescriptor&>(
      *qos.transport().user_transports[0]);
}

TEST(ParticipantQos, LoopbackProfileStaysOnLoopbackWithoutMulticast) {
  auto qos = resolve_participant_qos(with_profile(kLoopback));
  ASSERT_TRUE(qos.ok()) << qos.status();
  EXPECT_FALSE(qos->transport().use_builtin_transports);
  EXPECT_THAT(only_udp(*qos).interfaceWhiteList, ::testing::ElementsAre("127.0.0.1"));
  const auto& builtin = qos->wire_protocol().builtin;
  EXPECT_TRUE(builtin.metatrafficMulticastLocatorList.empty());
  ASSERT_FALSE(builtin.metatrafficUnicastLocatorList.empty());
  for (const auto& locator : builtin.metatrafficUnicastLocatorList)
    EXPECT_EQ(IPLocator::ip_to_string(locator), "127.0.0.1");
  for (const auto& locator : builtin.initialPeersList)
    EXPECT_EQ(IPLocator::ip_to_string(locator), "127.0.0.1");
  for (const auto& locator : qos->wire_protocol().default_unicast_locator_list) {
    EXPECT_EQ(IPLocator::ip_to_string(locator), "127.0.0.1");
  }
  EXPECT_TRUE(qos->wire_protocol().default_multicast_locator_list.empty());
}

TEST(ParticipantQos, AddressOverridesReplaceInterfaceAndPeers) {
  ParticipantOptions options = with_profile(kLoopback);
  options.interface_address = "10.77.0.2";
  options.peers = {"10.77.0.1"};
  auto qos = resolve_participant_qos(options);
  ASSERT_TRUE(qos.ok()) << qos.status();
  EXPECT_THAT(only_udp(*qos).interfaceWhiteList, ::testing::ElementsAre("10.77.0.2"));
  const auto& builtin = qos->wire_protocol().builtin;
  ASSERT_EQ(builtin.metatrafficUnicastLocatorList.size(), 1u);
  EXPECT_EQ(IPLocator::ip_to_string(*builtin.metatrafficUnicastLocatorList.begin()), "10.77.0.2");
  ASSERT_EQ(builtin.initialPeersList.size(), 1u);
  EXPECT_EQ(IPLocator::ip_to_string(*builtin.initialPeersList.begin()), "10.77.0.1");
}

TEST(ParticipantQos, BadAddressesAndMissingFilesAreErrors) {
  ParticipantOptions options = with_profile(kLoopback);
  options.peers = {"not-an-ip"};
  EXPECT_THAT(std::string(resolve_participant_qos(options).status().message()), HasSubstr("not-an-ip"));
  const ParticipantOptions missing = with_profile("/nonexistent/profile.xml");
  EXPECT_THAT(std::string(resolve_participant_qos(missing).status().message()),
              HasSubstr("/nonexistent/profile.xml"));
}

}  // namespace
}  // namespace mrvs::link
