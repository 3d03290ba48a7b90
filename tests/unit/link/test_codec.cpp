#include <random>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/link/codec.h"

namespace mrvs::link {
namespace {

using ::testing::HasSubstr;

std::vector<voxel::RayQuery> random_rays(std::size_t n, std::mt19937& rng) {
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  std::vector<voxel::RayQuery> rays(n);
  for (auto& r : rays) {
    r.origin = Eigen::Vector3f(u(rng), u(rng), u(rng));
    r.direction = Eigen::Vector3f(u(rng), u(rng), u(rng));
    r.initial_distance = std::abs(u(rng));
    r.resolution = 0.02f;
  }
  return rays;
}

TEST(LinkCodec, RequestRoundTripIsExact) {
  std::mt19937 rng(1);
  const auto rays = random_rays(200, rng);
  const wire::RayQueryBatch batch = encode_request(7, 123456789012ULL, 1403715273262142976LL, rays);
  EXPECT_EQ(batch.client_id(), 7u);
  EXPECT_EQ(batch.frame_seq(), 123456789012ULL);
  EXPECT_EQ(batch.stamp_ns(), 1403715273262142976LL);
  ASSERT_EQ(batch.rays().size(), rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const voxel::RayQuery back = decode_ray(batch.rays()[i]);
    EXPECT_EQ(back.origin, rays[i].origin);
    EXPECT_EQ(back.direction, rays[i].direction);
    EXPECT_EQ(back.initial_distance, rays[i].initial_distance);
    EXPECT_EQ(back.resolution, rays[i].resolution);
  }
}

TEST(LinkCodec, ReplyCarriesOnePointPerHitInRayOrder) {
  for (std::size_t n : {0u, 1u, 7u, 8u, 9u, 200u}) {
    const wire::RayQueryBatch request = encode_request(3, 9, 0, std::vector<voxel::RayQuery>(n));
    std::vector<std::optional<Eigen::Vector3f>> hits(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (i % 3 != 1) hits[i] = Eigen::Vector3f(float(i), -float(i), 0.5f);
    }
    const wire::RayReplyBatch reply = encode_reply(request, RequestCheck{}, hits);
    EXPECT_EQ(reply.hit_mask().size(), hit_mask_bytes(n));
    auto answers = decode_reply(reply, n);
    ASSERT_TRUE(answers.ok()) << answers.status();
    ASSERT_EQ(answers->size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ((*answers)[i].hit, hits[i].has_value()) << i;
      if (hits[i]) {
        EXPECT_EQ((*answers)[i].point, *hits[i]);
      }
    }
    EXPECT_EQ(reply.client_id(), 3u);
    EXPECT_EQ(reply.frame_seq(), 9u);
  }
}

TEST(LinkCodec, InconsistentRepliesAreRejected) {
  const wire::RayQueryBatch request = encode_request(3, 9, 0, std::vector<voxel::RayQuery>(10));
  std::vector<std::optional<Eigen::Vector3f>> hits(10, Eigen::Vector3f::Zero());
  wire::RayReplyBatch reply = encode_reply(request, RequestCheck{}, hits);
  EXPECT_FALSE(decode_reply(reply, 17).ok());  // 3 mask bytes expected
  wire::RayReplyBatch missing_point = reply;
  missing_point.points().pop_back();
  EXPECT_THAT(std::string(decode_reply(missing_point, 10).status().message()), HasSubstr("hit bits"));
  wire::RayReplyBatch padding = reply;
  padding.hit_mask().back() |= 0x80;  // bit for a ray that does not exist
  padding.points().push_back(wire::MapPoint());
  EXPECT_FALSE(decode_reply(padding, 10).ok());
}

TEST(LinkCodec, NormalsTravelOnlyWhenAskedOnePerHitWithin1e4) {
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  const std::size_t n = 50;
  std::vector<std::optional<Eigen::Vector3f>> hits(n);
  std::vector<Eigen::Vector3f> normals(n, Eigen::Vector3f::Zero());
  for (std::size_t i = 0; i < n; ++i) {
    if (i % 4 != 3) hits[i] = Eigen::Vector3f(float(i), 1.0f, 2.0f);
    if (i % 5 != 2) normals[i] = Eigen::Vector3f(g(rng), g(rng), g(rng)).normalized();
  }
  const auto rays = std::vector<voxel::RayQuery>(n);
  const wire::RayReplyBatch plain =
      encode_reply(encode_request(1, 2, 0, rays), RequestCheck{}, hits, normals);
  EXPECT_TRUE(plain.normals().empty()) << "normals not asked for";
  const wire::RayQueryBatch request = encode_request(1, 2, 0, rays, true);
  EXPECT_TRUE(request.want_normals());
  const wire::RayReplyBatch reply = encode_reply(request, RequestCheck{}, hits, normals);
  EXPECT_EQ(reply.normals().size(), reply.points().size());
  auto answers = decode_reply(reply, n);
  ASSERT_TRUE(answers.ok()) << answers.status();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& got = (*answers)[i].normal;
    if (!hits[i] || normals[i].isZero()) {
      EXPECT_TRUE(got.isZero()) << i;
      continue;
    }
    EXPECT_LT((got - normals[i]).norm(), 1e-4f) << i;
    EXPECT_NEAR(got.norm(), 1.0f, 1e-6f) << i;
  }
  wire::RayReplyBatch short_of_one = reply;
  short_of_one.normals().pop_back();
  EXPECT_THAT(std::string(decode_reply(short_of_one, n).status().message()), HasSubstr("normals"));
}

TEST(LinkCodec, NormalEncodingKeepsZeroAndRefusesWhatIsNotAUnitVector) {
  EXPECT_EQ(encode_normal(Eigen::Vector3f::Zero()), (std::array<std::int16_t, 3>{0, 0, 0}));
  EXPECT_EQ(encode_normal(Eigen::Vector3f(0.0f, 0.0f, 2.0f)), (std::array<std::int16_t, 3>{0, 0, 32767}));
  EXPECT_EQ(encode_normal(Eigen::Vector3f(NAN, 0.0f, 1.0f)), (std::array<std::int16_t, 3>{0, 0, 0}));
  EXPECT_TRUE(decode_normal({0, 0, 0}).isZero());
  EXPECT_TRUE(decode_normal({100, 0, 0}).isZero()) << "a corrupt, far from unit encoding";
  EXPECT_EQ(decode_normal({0, -32767, 0}), Eigen::Vector3f(0.0f, -1.0f, 0.0f));
}

TEST(LinkCodec, RequestChecks) {
  const std::vector<double> levels = {0.01, 0.02, 0.03};
  std::vector<voxel::RayQuery> rays(5);
  for (auto& r : rays) {
    r.direction = Eigen::Vector3f(0, 0, 1);
    r.initial_distance = 2.0f;
    r.resolution = 0.02f;
  }
  EXPECT_EQ(check_request(encode_request(1, 1, 0, rays), 256, levels).status, wire::STATUS_OK);
  EXPECT_EQ(check_request(encode_request(1, 1, 0, rays), 4, levels).status, wire::STATUS_TOO_MANY_RAYS);
  auto with = [&](std::size_t i, auto change) {
    auto copy = rays;
    change(copy[i]);
    return check_request(encode_request(1, 1, 0, copy), 256, levels);
  };
  const RequestCheck nan = with(3, [](voxel::RayQuery& r) { r.origin.y() = std::nanf(""); });
  EXPECT_EQ(nan.status, wire::STATUS_INVALID_RAY);
  EXPECT_EQ(nan.bad_ray_index, 3u);
  EXPECT_EQ(with(2, [](voxel::RayQuery& r) { r.direction.setZero(); }).status, wire::STATUS_INVALID_RAY);
  EXPECT_EQ(with(1, [](voxel::RayQuery& r) { r.initial_distance = -1.0f; }).status, wire::STATUS_INVALID_RAY);
  EXPECT_EQ(with(0, [](voxel::RayQuery& r) { r.resolution = INFINITY; }).status, wire::STATUS_INVALID_RAY);
  const RequestCheck level = with(4, [](voxel::RayQuery& r) { r.resolution = 0.05f; });
  EXPECT_EQ(level.status, wire::STATUS_UNKNOWN_RESOLUTION);
  EXPECT_EQ(level.bad_ray_index, 4u);
  EXPECT_THAT(level.detail, HasSubstr("ray 4"));
}

TEST(LinkCodec, ErrorRepliesCarryNoPoints) {
  const wire::RayQueryBatch request = encode_request(1, 2, 0, std::vector<voxel::RayQuery>(3));
  const RequestCheck refused{wire::STATUS_INVALID_RAY, 2, "x"};
  const wire::RayReplyBatch reply = encode_reply(request, refused, {Eigen::Vector3f::Zero(), {}, {}});
  EXPECT_EQ(reply.status(), wire::STATUS_INVALID_RAY);
  EXPECT_EQ(reply.bad_ray_index(), 2u);
  EXPECT_TRUE(reply.points().empty());
  EXPECT_TRUE(reply.hit_mask().empty());
}

TEST(LinkCodec, MapInfoRoundTripAndVersionCheck) {
  MapInfo info;
  info.map_id = "V1_01_sim";
  info.origin = Vec3d(332000.5, 4140000.25, 20.125);
  info.checksum = 0x0123456789ABCDEFULL;
  info.resolutions = {0.01, 0.02, 0.03};
  info.max_rays_per_batch = 256;
  wire::MapInfo w = encode_map_info(info);
  auto back = decode_map_info(w);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->origin, info.origin);  // double on the wire: exact
  EXPECT_EQ(back->checksum, info.checksum);
  EXPECT_EQ(back->map_id, info.map_id);
  ASSERT_EQ(back->resolutions.size(), 3u);
  EXPECT_FLOAT_EQ(static_cast<float>(back->resolutions[1]), 0.02f);
  w.protocol_version(99);
  EXPECT_THAT(std::string(decode_map_info(w).status().message()), HasSubstr("protocol 99"));
}

}  // namespace
}  // namespace mrvs::link
