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

#include "mrvs/cloud/ray_server.h"
#include "mrvs/edge/map_client.h"

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
  void start_server() {
    auto engine = map::QueryEngine::create(map_, map::QueryOptions{});
    ASSERT_TRUE(engine.ok()) << engine.status();
    engine_ = std::make_unique<map::QueryEngine>(*engine);
    cloud::RayServerOptions options;
    options.dds = loopback("test_server");
    options.map_id = "test_map";
    options.map_checksum = 1234;
    options.stats_period_ns = 0;
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

}  // namespace
}  // namespace mrvs
