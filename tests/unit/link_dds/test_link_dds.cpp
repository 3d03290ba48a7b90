// The edge-cloud link over real Fast DDS participants on loopback (scripts/test.sh runs CTest
// in a private network namespace when root). Server and clients live in this process.
#include <atomic>
#include <random>
#include <thread>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>

#include "mrvs_linkPubSubTypes.h"

#include "localise_scene.h"
#include "mrvs/cloud/ray_server.h"
#include "mrvs/edge/map_client.h"
#include "mrvs/link/localisation_codec.h"

namespace mrvs {
namespace {

constexpr int kDomain = 91;  // not the demo's (42): a running demo cannot answer these tests
constexpr DurationNs kMs = 1'000'000;

link::ParticipantOptions loopback(const std::string& name) {
  link::ParticipantOptions o;
  o.profile_file = std::filesystem::path(MRVS_SOURCE_DIR) / "config/dds/loopback.xml";
  o.domain_id = kDomain;
  o.name = name;
  return o;
}

/// A map of random surface-like points in a 4 m cube, two levels.
std::shared_ptr<const map::VoxelMap> test_map() {
  auto m = std::make_shared<map::VoxelMap>();
  m->origin = Vec3d(332000.0, 4140000.0, 20.0);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 4.0f);
  for (double r : {0.02, 0.04}) {
    map::MapLevel level;
    level.resolution = r;
    std::set<std::uint64_t> used;
    for (int i = 0; i < 20000; ++i) {
      const Eigen::Vector3f p(u(rng), u(rng), 2.0f);  // a floor-like plane at z = 2
      const auto index = voxel::index_of<double>(p.cast<double>(), r);
      if (index && used.insert(voxel::pack(*index)).second) level.points.push_back({p, 0.5f, 1.0f});
    }
    m->levels.push_back(std::move(level));
  }
  return m;
}

std::vector<voxel::RayQuery> rays_towards_floor(int n, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.5f, 3.5f);
  std::vector<voxel::RayQuery> rays(n);
  for (auto& r : rays) {
    r.origin = Eigen::Vector3f(u(rng), u(rng), 3.5f);
    r.direction = Eigen::Vector3f(0.1f * (u(rng) - 2.0f), 0.1f * (u(rng) - 2.0f), -1.0f);
    r.initial_distance = 1.5f;
    r.resolution = 0.02f;
  }
  return rays;
}

class LinkDds : public ::testing::Test {
 protected:
  void start_server(std::shared_ptr<const localise::Localiser> localiser = nullptr) {
    auto engine = map::QueryEngine::create(map_, map::QueryOptions{});
    ASSERT_TRUE(engine.ok()) << engine.status();
    engine_ = std::make_unique<map::QueryEngine>(*engine);
    cloud::RayServerOptions options;
    options.dds = loopback("test_server");
    options.map_id = "test_map";
    options.map_checksum = 1234;
    options.stats_period_ns = 0;
    options.localiser = std::move(localiser);
    auto server = cloud::RayServer::create(*engine, options);
    ASSERT_TRUE(server.ok()) << server.status();
    server_ = std::move(*server);
    thread_ = std::thread([this] { EXPECT_TRUE(server_->run().ok()); });
  }
  void stop_server() {
    if (!server_) return;
    server_->stop();
    thread_.join();
    server_.reset();
  }
  std::unique_ptr<edge::MapClient> make_client() {
    edge::MapClientOptions options;
    options.dds = loopback("test_client");
    auto client = edge::MapClient::create(options);
    EXPECT_TRUE(client.ok()) << client.status();
    return client.ok() ? std::move(*client) : nullptr;
  }
  /// Queries until answered (discovery takes a moment) or `attempts` run out.
  edge::QueryReply query_until_answered(edge::MapClient& client, const std::vector<voxel::RayQuery>& rays,
                                        int attempts = 50) {
    edge::QueryReply reply;
    for (int i = 0; i < attempts && reply.outcome != edge::QueryOutcome::kAnswered; ++i) {
      reply = client.query(rays, 0, 200 * kMs);
      if (reply.outcome == edge::QueryOutcome::kRefused) break;
    }
    return reply;
  }
  void TearDown() override { stop_server(); }

  std::shared_ptr<const map::VoxelMap> map_ = test_map();
  std::unique_ptr<map::QueryEngine> engine_;
  std::unique_ptr<cloud::RayServer> server_;
  std::thread thread_;
};

TEST_F(LinkDds, RoundTripReturnsExactlyTheInProcessQuery) {
  start_server();
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  const auto info = client->wait_for_map_info(5'000 * kMs);
  ASSERT_TRUE(info.has_value());
  EXPECT_EQ(info->origin, map_->origin);
  EXPECT_EQ(info->checksum, 1234u);
  ASSERT_EQ(info->resolutions.size(), 2u);
  const auto rays = rays_towards_floor(200, 1);
  const edge::QueryReply reply = query_until_answered(*client, rays);
  ASSERT_EQ(reply.outcome, edge::QueryOutcome::kAnswered);
  ASSERT_EQ(reply.answers.size(), rays.size());
  int hits = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const map::QueryResult local = engine_->query(rays[i]);
    ASSERT_EQ(reply.answers[i].hit, local.status == map::QueryStatus::kHit) << i;
    if (reply.answers[i].hit) {
      EXPECT_EQ(reply.answers[i].point, local.point) << i;  // bit-exact floats
      ++hits;
    }
  }
  EXPECT_GT(hits, 50);
}

TEST_F(LinkDds, SurfaceNormalsComeOnlyWhenAskedAndEqualTheInProcessFit) {
  start_server();
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  ASSERT_TRUE(client->wait_for_map_info(5'000 * kMs).has_value());
  const auto rays = rays_towards_floor(100, 3);
  const edge::QueryReply plain = query_until_answered(*client, rays);
  ASSERT_EQ(plain.outcome, edge::QueryOutcome::kAnswered);
  for (const link::RayAnswer& a : plain.answers) EXPECT_TRUE(a.normal.isZero());
  const edge::QueryReply reply = client->query(rays, 0, 1'000 * kMs, true);
  ASSERT_EQ(reply.outcome, edge::QueryOutcome::kAnswered);
  int normals = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const map::QueryResult local = engine_->query(rays[i]);
    if (local.status != map::QueryStatus::kHit) continue;
    const auto n = engine_->surface_normal(local.level, local.point);
    ASSERT_TRUE(n.has_value()) << i << ": the floor is a plane";
    EXPECT_LT((reply.answers[i].normal - *n).norm(), 1e-4f) << i;  // 3 x int16 on the wire
    EXPECT_GT(std::abs(reply.answers[i].normal.z()), 0.999f) << i;
    ++normals;
  }
  EXPECT_GT(normals, 30);
}

TEST_F(LinkDds, MissingServerTimesOutWithinTheDeadline) {
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  for (int i = 0; i < 3; ++i) {
    const edge::QueryReply reply = client->query(rays_towards_floor(50, 2), 0, 100 * kMs);
    EXPECT_EQ(reply.outcome, edge::QueryOutcome::kTimeout);
    EXPECT_GE(reply.rtt_ns, 100 * kMs);
    EXPECT_LT(reply.rtt_ns, 150 * kMs);  // never much past the deadline
  }
  EXPECT_EQ(client->stats().timeouts, 3u);
}

TEST_F(LinkDds, ServerRestartIsSurvivedWithoutRestartingTheClient) {
  start_server();
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  const auto rays = rays_towards_floor(20, 3);
  ASSERT_EQ(query_until_answered(*client, rays).outcome, edge::QueryOutcome::kAnswered);
  stop_server();
  EXPECT_EQ(client->query(rays, 0, 100 * kMs).outcome, edge::QueryOutcome::kTimeout);
  start_server();
  EXPECT_EQ(query_until_answered(*client, rays).outcome, edge::QueryOutcome::kAnswered);
  EXPECT_GE(client->stats().timeouts, 1u);
}

TEST_F(LinkDds, BadBatchesAreRefusedAndTheServerKeepsServing) {
  start_server();
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  const auto good = rays_towards_floor(10, 4);
  ASSERT_EQ(query_until_answered(*client, good).outcome, edge::QueryOutcome::kAnswered);
  auto nan = good;
  nan[7].origin.x() = std::nanf("");
  edge::QueryReply reply = client->query(nan, 0, 1'000 * kMs);
  EXPECT_EQ(reply.outcome, edge::QueryOutcome::kRefused);
  EXPECT_EQ(reply.server_status, wire::STATUS_INVALID_RAY);
  EXPECT_EQ(reply.bad_ray_index, 7u);
  auto zero = good;
  zero[2].direction.setZero();
  EXPECT_EQ(client->query(zero, 0, 1'000 * kMs).server_status, wire::STATUS_INVALID_RAY);
  auto level = good;
  level[0].resolution = 0.05f;
  EXPECT_EQ(client->query(level, 0, 1'000 * kMs).server_status, wire::STATUS_UNKNOWN_RESOLUTION);
  // The client does not even try to send an oversized batch.
  reply = client->query(rays_towards_floor(300, 5), 0, 1'000 * kMs);
  EXPECT_EQ(reply.outcome, edge::QueryOutcome::kTooManyRays);
  EXPECT_EQ(client->query(good, 0, 1'000 * kMs).outcome, edge::QueryOutcome::kAnswered);
  const auto counters = server_->counters();
  ASSERT_EQ(counters.count(client->client_id()), 1u);
  EXPECT_EQ(counters.at(client->client_id()).rejected_requests, 3u);
}

// A foreign or broken peer in another process sends batches beyond the IDL bound (the
// generated code does not enforce bounds on receipt): the server refuses them and serves on.
// (In one process Fast DDS would deliver intra-process into the bounded reader instead.)
TEST_F(LinkDds, OversizedBatchFromAForeignPeerIsRefusedAndServingGoesOn) {
  start_server();
  auto observer = link::Participant::create(loopback("observer"));
  ASSERT_TRUE(observer.ok()) << observer.status();
  auto replies = (*observer)->topic(link::kReplyTopic,
                                    eprosima::fastdds::dds::TypeSupport(new wire::RayReplyBatchPubSubType()));
  ASSERT_TRUE(replies.ok());
  auto reader = (*observer)->reader(*replies, link::kReaderProfile);
  ASSERT_TRUE(reader.ok());
  const std::string command =
      fmt::format("'{}' '{}' {} 4 &", MRVS_OVERSIZED_PEER, loopback("x").profile_file.string(), kDomain);
  ASSERT_EQ(std::system(command.c_str()), 0);
  wire::RayReplyBatch reply;
  eprosima::fastdds::dds::SampleInfo info;
  bool refused = false;
  for (int i = 0; i < 40 && !refused; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    while ((*reader)->take_next_sample(&reply, &info) ==
           eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
      refused = refused || (info.valid_data && reply.client_id() == 4242 &&
                            reply.status() == wire::STATUS_TOO_MANY_RAYS && reply.points().empty());
    }
  }
  EXPECT_TRUE(refused);
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  EXPECT_EQ(query_until_answered(*client, rays_towards_floor(10, 7)).outcome, edge::QueryOutcome::kAnswered);
  EXPECT_GE(server_->counters().at(4242).rejected_requests, 1u);
}

TEST_F(LinkDds, TwoClientsAtOnceGetOnlyTheirOwnReplies) {
  start_server();
  auto a = make_client();
  auto b = make_client();
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  ASSERT_NE(a->client_id(), b->client_id());
  // Both clients are answered once (both readers matched) before either starts its loop, so
  // the loops overlap and each reader sees the other's replies.
  std::atomic<int> ready{0};
  auto run = [this, &ready](edge::MapClient& client, std::uint32_t seed, std::atomic<int>& correct) {
    const auto rays = rays_towards_floor(100, seed);
    const bool matched = query_until_answered(client, rays).outcome == edge::QueryOutcome::kAnswered;
    ready.fetch_add(1);
    while (ready.load() < 2) std::this_thread::yield();
    ASSERT_TRUE(matched);
    for (int k = 0; k < 30; ++k) {
      // A datagram lost on a starved machine is repaired at the next heartbeat (3 s by
      // default); the client gives up per request (transport.md rule 6) and asks again.
      edge::QueryReply reply;
      for (int attempt = 0; attempt < 4 && reply.outcome != edge::QueryOutcome::kAnswered; ++attempt) {
        reply = client.query(rays, 0, 1'000 * kMs);
      }
      ASSERT_EQ(reply.outcome, edge::QueryOutcome::kAnswered);
      bool same = true;
      for (std::size_t i = 0; i < rays.size(); ++i) {
        const map::QueryResult local = engine_->query(rays[i]);
        same = same && reply.answers[i].hit == (local.status == map::QueryStatus::kHit) &&
               (!reply.answers[i].hit || reply.answers[i].point == local.point);
      }
      correct += same;
    }
  };
  std::atomic<int> correct_a{0}, correct_b{0};
  std::thread ta([&] { run(*a, 10, correct_a); });
  std::thread tb([&] { run(*b, 20, correct_b); });
  ta.join();
  tb.join();
  EXPECT_EQ(correct_a.load(), 30);
  EXPECT_EQ(correct_b.load(), 30);
  // Both read the shared reply topic: the other's replies arrived and were dropped.
  EXPECT_GT(a->stats().foreign_dropped + b->stats().foreign_dropped, 0u);
  EXPECT_EQ(server_->counters().size(), 2u);
}

// ---- The localisation service over DDS -------------------------------------------------

/// A cluttered room map and its localiser; `map_` becomes the room so the ray tests' server
/// set-up serves it.
std::shared_ptr<const localise::Localiser> room_localiser(std::shared_ptr<const map::VoxelMap>* map,
                                                          std::vector<Eigen::Vector3d>* samples) {
  *samples = localise::test::cluttered_room(12, 3).sample(0.01);
  const Vec3d origin(332000.0, 4140000.0, 20.0);
  for (auto& p : *samples) p += origin;
  *map = localise::test::voxelise(*samples, {0.03, 0.1}, origin);
  auto l = localise::Localiser::create(*map, localise::LocaliserOptions{});
  EXPECT_TRUE(l.ok()) << l.status();
  return std::make_shared<const localise::Localiser>(std::move(*l));
}

/// Sends until a reply arrives (discovery takes a moment); nullopt after `attempts`.
std::optional<edge::LocalisationAnswer> localise_until_answered(edge::MapClient& client,
                                                                localisation::Request q, float quantum,
                                                                int attempts = 20) {
  for (int i = 0; i < attempts; ++i) {
    q.seq = 100 + i;
    if (!client.send_localisation(q, quantum).ok()) continue;
    for (int k = 0; k < 50; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      for (auto& a : client.take_localisation_replies()) {
        if (a.seq == q.seq) return a;
      }
    }
  }
  return std::nullopt;
}

TEST_F(LinkDds, LocalisationOverDdsEqualsTheInProcessAnswer) {
  std::vector<Vec3d> samples;
  auto localiser = room_localiser(&map_, &samples);
  start_server(localiser);
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  const auto info = client->wait_for_map_info(5'000 * kMs);
  ASSERT_TRUE(info.has_value());
  EXPECT_EQ(info->localisation_protocol_version, wire::LOCALISATION_PROTOCOL_VERSION);
  const SE3d T_o_m =
      localise::test::yaw_pose(0.8, Vec3d(2, -1, 0.2)) * SE3d(Quatd::Identity(), -map_->origin);
  const auto q =
      localise::test::submap_request(samples, map_->origin + Vec3d(3.0, 2.5, 1.3), 4.0, 3000, 0.01, T_o_m, 5);
  const float quantum = 0.005f;
  const auto answer = localise_until_answered(*client, q, quantum);
  ASSERT_TRUE(answer.has_value());
  ASSERT_EQ(answer->result.status, localisation::Status::kOk) << answer->result.detail;
  // The cloud localised what the wire carried: the same request decoded here gives the same answer.
  auto carried = link::decode_localisation_request(link::encode_localisation_request(1, q, quantum));
  ASSERT_TRUE(carried.ok());
  const auto local = localiser->localise(*carried);
  EXPECT_LT((answer->result.T_m_o.translation() - local.T_m_o.translation()).norm(), 1e-9);
  EXPECT_LT(answer->result.T_m_o.quaternion().angularDistance(local.T_m_o.quaternion()), 1e-9);
  EXPECT_NEAR(answer->result.fitness, local.fitness, 1e-6);
  for (int i = 0; i < 6; ++i)
    EXPECT_NEAR(answer->result.covariance(i, i), local.covariance(i, i),
                1e-6 * local.covariance(i, i) + 1e-12);
  // ... and it is right.
  EXPECT_LT((answer->result.T_m_o * q.anchor_o - T_o_m.inverse() * q.anchor_o).norm(), 0.03);
  // Bytes: 6 per point plus a fixed header, well within 64 KB.
  EXPECT_GE(client->stats().localisation_bytes_up, 6 * q.points.size());
  const std::size_t bytes = link::payload_bytes(link::encode_localisation_request(1, q, quantum));
  EXPECT_EQ(bytes,
            link::payload_bytes(link::encode_localisation_request(1, localisation::Request{}, quantum)) +
                6 * q.points.size());
  localisation::Request big = q;
  big.points.assign(20000, Eigen::Vector3f::Zero());
  big.viewpoints.assign(64, localisation::Viewpoint{Eigen::Vector3f::Zero(), 150});
  EXPECT_LT(link::payload_bytes(link::encode_localisation_request(1, big, quantum)), 65536u);
}

TEST_F(LinkDds, MalformedLocalisationRequestsGetAStatusAndServingGoesOn) {
  std::vector<Vec3d> samples;
  start_server(room_localiser(&map_, &samples));
  auto peer = link::Participant::create(loopback("raw_peer"));
  ASSERT_TRUE(peer.ok()) << peer.status();
  auto topics = link::create_link_topics(**peer);
  ASSERT_TRUE(topics.ok()) << topics.status();
  auto writer = (*peer)->writer(topics->localisation_requests, link::kWriterProfile);
  auto reader = (*peer)->reader(topics->localisation_replies, link::kReaderProfile);
  ASSERT_TRUE(writer.ok() && reader.ok());
  const auto good = localise::test::submap_request(samples, map_->origin + Vec3d(4.0, 3.0, 1.2), 4.0, 2000,
                                                   0.01, SE3d(Quatd::Identity(), -map_->origin), 6);
  std::vector<wire::LocalisationRequest> bad(5, link::encode_localisation_request(77, good, 0.005f));
  bad[0].protocol_version(99);
  bad[1].quantum_m(0.0f);
  bad[2].anchor({std::nan(""), 0.0, 0.0});
  bad[3].points().resize(10);  // too few points
  bad[4].gravity({0.0f, 0.0f, -5.0f});
  for (std::size_t i = 0; i < bad.size(); ++i) bad[i].client_id(static_cast<std::uint32_t>(70 + i));
  wire::LocalisationRequest ok = link::encode_localisation_request(77, good, 0.005f);  // one client each
  std::map<std::uint64_t, wire::LocalisationReply> replies;
  for (int attempt = 0; attempt < 10 && replies.size() < bad.size() + 1; ++attempt) {
    for (std::size_t i = 0; i < bad.size(); ++i) {
      bad[i].request_seq(1000 * attempt + i);
      (*writer)->write(&bad[i]);
    }
    ok.request_seq(1000 * attempt + 999);
    (*writer)->write(&ok);
    wire::LocalisationReply r;
    eprosima::fastdds::dds::SampleInfo info;
    for (int k = 0; k < 40 && replies.size() < bad.size() + 1; ++k) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      while ((*reader)->take_next_sample(&r, &info) == eprosima::fastrtps::types::ReturnCode_t::RETCODE_OK) {
        if (info.valid_data && r.client_id() >= 70 && r.client_id() <= 77)
          replies[r.request_seq() % 1000] = r;
      }
    }
  }
  ASSERT_EQ(replies.size(), bad.size() + 1);
  for (std::size_t i = 0; i < bad.size(); ++i) {
    EXPECT_EQ(replies.at(i).status(), wire::LOCALISATION_BAD_REQUEST) << i << ": " << replies.at(i).detail();
    EXPECT_FALSE(std::string(replies.at(i).detail()).empty()) << i;
  }
  EXPECT_EQ(replies.at(999).status(), wire::LOCALISATION_OK) << replies.at(999).detail();
}

TEST_F(LinkDds, ACloudWithoutLocalisationSaysSo) {
  start_server();
  auto client = make_client();
  ASSERT_NE(client, nullptr);
  const auto info = client->wait_for_map_info(5'000 * kMs);
  ASSERT_TRUE(info.has_value());
  EXPECT_EQ(info->localisation_protocol_version, 0u);
}

}  // namespace
}  // namespace mrvs