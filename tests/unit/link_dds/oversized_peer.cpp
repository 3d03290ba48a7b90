// A misbehaving edge for test_link_dds: sends RayQueryBatch samples with more rays than the
// IDL bound (client id 4242), every 100 ms for up to --seconds, on the loopback profile.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>

#include <fastdds/dds/publisher/DataWriter.hpp>

#include "mrvs/link/codec.h"
#include "mrvs/link/participant.h"
#include "mrvs/link/types.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: oversized_peer PROFILE.xml DOMAIN SECONDS\n");
    return 2;
  }
  mrvs::link::ParticipantOptions options;
  options.profile_file = argv[1];
  options.domain_id = std::atoi(argv[2]);
  options.name = "oversized_peer";
  auto peer = mrvs::link::Participant::create(options);
  if (!peer.ok()) return 1;
  auto topic = (*peer)->topic(mrvs::link::kRequestTopic, mrvs::link::request_type(300));
  auto writer = topic.ok() ? (*peer)->writer(*topic, mrvs::link::kWriterProfile) : topic.status();
  if (!writer.ok()) return 1;
  std::vector<mrvs::voxel::RayQuery> rays(300);
  for (auto& r : rays) {
    r.initial_distance = 1.0f;
    r.resolution = 0.02f;
  }
  mrvs::wire::RayQueryBatch big = mrvs::link::encode_request(4242, 1, 0, rays);
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(std::atoi(argv[3]));
  while (std::chrono::steady_clock::now() < end) {
    if (!(*writer)->write(&big)) std::fprintf(stderr, "oversized_peer: write failed\n");
    big.frame_seq(big.frame_seq() + 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return 0;
}
