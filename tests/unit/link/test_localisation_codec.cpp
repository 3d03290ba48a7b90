// The localisation service's wire form: points quantised to the quantum (error at most half a
// quantum per axis), those out of the int16 range or beyond the bound left out and counted,
// the prior region and gravity carried, replies exact in the pose and float in the covariance,
// and every malformed sample refused by name.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/link/localisation_codec.h"

namespace mrvs::link {
namespace {

localisation::Request sample_request(int n, float spread) {
  localisation::Request q;
  q.seq = 42;
  q.stamp_ns = 1'403'715'274'302'140'000;
  q.anchor_o = Vec3d(1.25, -3.5, 0.75);
  q.gravity_o = Vec3d(0.01, -0.02, -1.0).normalized();
  q.prior = localisation::PriorRegion{Vec3d(332001.5, 4140002.25, 20.5), 15.0};
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-spread, spread);
  std::uniform_int_distribution<int> grey(0, 255);
  for (int i = 0; i < n; ++i) {
    q.points.emplace_back(u(rng), u(rng), u(rng));
    q.brightness.push_back(static_cast<std::uint8_t>(grey(rng)));
  }
  return q;
}

TEST(LocalisationCodec, RequestRoundTripWithinHalfAQuantum) {
  const auto q = sample_request(3000, 40.0f);
  std::size_t dropped = 1;
  const auto w = encode_localisation_request(7, q, 0.005f, &dropped);
  EXPECT_EQ(dropped, 0u);
  EXPECT_EQ(w.client_id(), 7u);
  auto d = decode_localisation_request(w);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->seq, q.seq);
  EXPECT_EQ(d->stamp_ns, q.stamp_ns);
  EXPECT_EQ(d->anchor_o, q.anchor_o);
  EXPECT_LT((d->gravity_o - q.gravity_o).norm(), 1e-6);
  ASSERT_TRUE(d->prior.has_value());
  EXPECT_EQ(d->prior->centre_m, q.prior->centre_m);
  EXPECT_EQ(d->prior->radius_m, 15.0);
  ASSERT_EQ(d->points.size(), q.points.size());
  float worst = 0.0f;
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    worst = std::max(worst, (d->points[i] - q.points[i]).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, 0.0025f + 1e-5f);
  EXPECT_GT(worst, 0.001f);  // it is quantised
  EXPECT_EQ(d->brightness, q.brightness);
  EXPECT_EQ(payload_bytes(w),
            payload_bytes(encode_localisation_request(7, localisation::Request{}, 0.005f)) + 7 * 3000);
  auto plain = q;  // no brightness: none on the wire, none decoded
  plain.brightness.clear();
  const auto wp = encode_localisation_request(7, plain, 0.005f);
  EXPECT_TRUE(wp.brightness().empty());
  EXPECT_TRUE(decode_localisation_request(wp)->brightness.empty());
}

TEST(LocalisationCodec, PointsOutOfRangeOrBeyondTheBoundAreLeftOutAndCounted) {
  auto q = sample_request(10, 1.0f);
  q.points.insert(q.points.begin() + 3, Eigen::Vector3f(200.0f, 0.0f, 0.0f));  // beyond 32767 * 5 mm
  q.brightness.insert(q.brightness.begin() + 3, 7);
  q.points.emplace_back(0.0f, std::nanf(""), 0.0f);
  q.brightness.push_back(9);
  std::size_t dropped = 0;
  auto w = encode_localisation_request(1, q, 0.005f, &dropped);
  EXPECT_EQ(dropped, 2u);
  EXPECT_EQ(w.points().size(), 10u);
  // The brightness of the points left out goes too: the others keep theirs.
  auto kept = q.brightness;
  kept.pop_back();
  kept.erase(kept.begin() + 3);
  EXPECT_EQ(w.brightness(), kept);
  q = sample_request(wire::MAX_SUBMAP_POINTS + 5, 1.0f);
  w = encode_localisation_request(1, q, 0.005f, &dropped);
  EXPECT_EQ(dropped, 5u);
  EXPECT_EQ(w.points().size(), wire::MAX_SUBMAP_POINTS);
  EXPECT_LT(payload_bytes(w), 65536u);
  q.prior.reset();
  EXPECT_FALSE(decode_localisation_request(encode_localisation_request(1, q, 0.005f))->prior.has_value());
}

TEST(LocalisationCodec, MalformedRequestsAreRefusedByName) {
  const auto good = encode_localisation_request(1, sample_request(100, 1.0f), 0.005f);
  auto w = good;
  w.protocol_version(9);
  auto d = decode_localisation_request(w);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(std::string(d.status().message()).find("protocol"), std::string::npos);
  w = good;
  w.quantum_m(-1.0f);
  EXPECT_NE(std::string(decode_localisation_request(w).status().message()).find("quantum"),
            std::string::npos);
  w = good;
  w.gravity({0.0f, std::nanf(""), -1.0f});
  EXPECT_FALSE(decode_localisation_request(w).ok());
  w = good;
  w.points().resize(wire::MAX_SUBMAP_POINTS + 1);
  EXPECT_FALSE(decode_localisation_request(w).ok());
  w = good;
  w.brightness().pop_back();  // not one per point
  d = decode_localisation_request(w);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(std::string(d.status().message()).find("brightness"), std::string::npos) << d.status();
}

TEST(LocalisationCodec, ReplyRoundTrip) {
  const auto request = encode_localisation_request(5, sample_request(10, 1.0f), 0.005f);
  localisation::Result r;
  r.status = localisation::Status::kOk;
  r.detail = "fitness 0.9";
  r.T_m_o = SE3d(Quatd(Eigen::AngleAxisd(1.2, Vec3d(0.1, 0.2, 1.0).normalized())),
                 Vec3d(332000.125, 4140000.5, 21.0));
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) r.covariance(i, j) = (i == j ? 1e-4 : 1e-6) * (1 + i + j);
  r.fitness = 0.91;
  r.ambiguity = 0.3;
  r.hypotheses = 4;
  r.time_ms = 212.5;
  const auto w = encode_localisation_reply(request, r);
  EXPECT_EQ(w.request_seq(), 42u);
  EXPECT_EQ(w.client_id(), 5u);
  auto d = decode_localisation_reply(w);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->status, r.status);
  EXPECT_EQ(d->detail, r.detail);
  EXPECT_LT((d->T_m_o.translation() - r.T_m_o.translation()).norm(), 1e-9);
  EXPECT_LT(d->T_m_o.quaternion().angularDistance(r.T_m_o.quaternion()), 1e-12);
  EXPECT_TRUE(d->covariance.isApprox(r.covariance, 1e-6));
  EXPECT_EQ(d->covariance, d->covariance.transpose());
  EXPECT_NEAR(d->fitness, 0.91, 1e-6);
  EXPECT_EQ(d->hypotheses, 4);
  EXPECT_LT(payload_bytes(w), 300u);
}

TEST(LocalisationCodec, CorruptRepliesAreDataLoss) {
  const auto request = encode_localisation_request(5, sample_request(10, 1.0f), 0.005f);
  localisation::Result r;
  r.status = localisation::Status::kOk;
  auto w = encode_localisation_reply(request, r);
  w.rotation({0.0, 0.0, 0.5, 0.5});  // not a unit quaternion
  EXPECT_EQ(decode_localisation_reply(w).status().code(), absl::StatusCode::kDataLoss);
  w = encode_localisation_reply(request, r);
  w.protocol_version(wire::LOCALISATION_PROTOCOL_VERSION + 1);
  EXPECT_EQ(decode_localisation_reply(w).status().code(), absl::StatusCode::kDataLoss);
  w = encode_localisation_reply(request, r);
  w.status(static_cast<wire::LocalisationStatus>(77));
  EXPECT_EQ(decode_localisation_reply(w).status().code(), absl::StatusCode::kDataLoss);
  // A refusal carries no pose and needs none.
  const auto refused = refuse_localisation(request, localisation::Status::kBusy, "later");
  auto d = decode_localisation_reply(refused);
  ASSERT_TRUE(d.ok());
  EXPECT_EQ(d->status, localisation::Status::kBusy);
  EXPECT_EQ(d->detail, "later");
}

}  // namespace
}  // namespace mrvs::link
