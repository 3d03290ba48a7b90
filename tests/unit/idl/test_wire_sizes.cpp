// The wire types must keep the paper's budget: 32 bytes up per ray, 12 bytes down per
// hit, and a small constant header per batch. Measured by serialising with the
// generated type support (the exact bytes Fast DDS puts in a DATA submessage).
#include <gtest/gtest.h>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "mrvs_link.h"
#include "mrvs_linkPubSubTypes.h"

namespace {

using eprosima::fastrtps::rtps::SerializedPayload_t;

template <typename PubSubType, typename T>
SerializedPayload_t serialize(PubSubType& type, T& sample) {
  SerializedPayload_t payload(type.getSerializedSizeProvider(&sample)());
  EXPECT_TRUE(type.serialize(&sample, &payload));
  return payload;
}

mrvs::wire::RayQueryBatch make_batch(std::size_t n) {
  mrvs::wire::RayQueryBatch batch;
  batch.client_id(7);
  batch.frame_seq(123456789012ULL);
  batch.stamp_ns(1403715273262142976LL);
  for (std::size_t i = 0; i < n; ++i) {
    mrvs::wire::RayQuery q;
    q.origin({1.0f * i, 2.0f, 3.0f});
    q.initial_distance(4.5f);
    q.direction({0.0f, 0.6f, 0.8f});
    q.resolution(0.02f);
    batch.rays().push_back(q);
  }
  return batch;
}

TEST(WireSizes, RayQueryIs32BytesAndMapPointIs12) {
  EXPECT_EQ(mrvs::wire::RayQuery::getCdrSerializedSize(mrvs::wire::RayQuery()), 32u);
  EXPECT_EQ(mrvs::wire::MapPoint::getCdrSerializedSize(mrvs::wire::MapPoint()), 12u);
}

TEST(WireSizes, RequestBatchIsHeaderPlus32BytesPerRay) {
  mrvs::wire::RayQueryBatchPubSubType type;
  auto empty = make_batch(0);
  auto full = make_batch(200);
  const auto empty_len = serialize(type, empty).length;
  const auto full_len = serialize(type, full).length;
  // 4 B encapsulation + 8 seq + 8 stamp + 4 client + 4 sequence length + 1 want_normals.
  EXPECT_EQ(empty_len, 29u);
  EXPECT_EQ(full_len - empty_len, 200u * 32u);
}

TEST(WireSizes, ReplyBatchIsHeaderPlus12BytesPerHitAndOneBitPerRay) {
  mrvs::wire::RayReplyBatchPubSubType type;
  mrvs::wire::RayReplyBatch reply;
  reply.frame_seq(1);
  reply.client_id(7);
  reply.status(mrvs::wire::STATUS_OK);
  reply.hit_mask(std::vector<uint8_t>(25, 0xFF));  // 200 rays
  const auto no_points = serialize(type, reply).length;
  reply.points().resize(200);
  const auto all_points = serialize(type, reply).length;
  EXPECT_EQ(all_points - no_points, 200u * 12u);
  // encapsulation 4 + seq 8 + client 4 + status 4 + bad index 4 + mask (4 + 25, padded to
  // 32) + points length 4 + normals length 4
  EXPECT_EQ(no_points, 4u + 8u + 4u + 4u + 4u + 32u + 4u + 4u);
  // Surface normals (when asked): 6 B more per hit.
  reply.normals().resize(200);
  EXPECT_EQ(serialize(type, reply).length - all_points, 200u * 6u);
  EXPECT_EQ(mrvs::wire::SurfaceNormal::getCdrSerializedSize(mrvs::wire::SurfaceNormal()), 6u);
}

TEST(WireSizes, RoundTripPreservesEveryField) {
  mrvs::wire::RayQueryBatchPubSubType type;
  auto batch = make_batch(200);
  auto payload = serialize(type, batch);
  mrvs::wire::RayQueryBatch back;
  ASSERT_TRUE(type.deserialize(&payload, &back));
  EXPECT_EQ(back, batch);
}

// Characterisation of fastddsgen 2.3 / Fast CDR 1.0: the sequence bound sizes buffers but
// is NOT enforced by the generated (de)serialisers. An oversized batch from a peer arrives
// intact, so the server must count the rays itself and answer STATUS_TOO_MANY_RAYS.
// If a future fastddsgen starts enforcing the bound this test fails and the note can go.
TEST(WireSizes, GeneratedCodeDoesNotEnforceTheSequenceBound) {
  mrvs::wire::RayQueryBatchPubSubType type;
  auto batch = make_batch(mrvs::wire::MAX_RAYS_PER_BATCH + 44);
  SerializedPayload_t payload(type.getSerializedSizeProvider(&batch)());
  ASSERT_TRUE(type.serialize(&batch, &payload));
  mrvs::wire::RayQueryBatch back;
  ASSERT_TRUE(type.deserialize(&payload, &back));
  EXPECT_EQ(back.rays().size(), mrvs::wire::MAX_RAYS_PER_BATCH + 44);
}

}  // namespace
