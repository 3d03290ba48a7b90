// The Localiser on synthetic rooms: a cluttered room is found from anywhere (no prior) within
// centimetres, its covariance bounds the error; a bare rectangular room (symmetric under a
// half turn) answers "ambiguous"; one wall answers "too little structure"; a submap of another
// place answers "outside the map"; malformed requests answer "bad request"; a prior region
// that misses the map answers "outside the map"; a map origin far from zero changes nothing;
// a best pose whose texture disagrees with the map is no answer; a view mostly of floor is
// found with the floor capped in the coarse search.
#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "localise_scene.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/localise/localiser.h"

namespace mrvs::localise {
namespace {

using localisation::Status;

Localiser make(std::shared_ptr<const map::VoxelMap> m, const LocaliserOptions& o = {}) {
  auto l = Localiser::create(std::move(m), o);
  EXPECT_TRUE(l.ok()) << l.status();
  return std::move(*l);
}

struct Error {
  double m = 0.0;
  double deg = 0.0;
};

Error pose_error(const SE3d& T_m_o, const SE3d& truth_T_m_o, const Eigen::Vector3d& anchor_o) {
  const SE3d d = T_m_o * truth_T_m_o.inverse();
  const Eigen::Vector3d a_m = truth_T_m_o * anchor_o;
  return {((T_m_o * anchor_o) - a_m).norm(), Eigen::AngleAxisd(d.quaternion()).angle() * kRadToDeg};
}

TEST(Localiser, FindsAClutteredRoomFromAnywhere) {
  const test::Scene scene = test::cluttered_room(14, 21);
  const auto samples = scene.sample(0.01);
  const Eigen::Vector3d origin(350000.0, 5800000.0, 40.0);  // UTM-like: the map stores offsets
  std::vector<Eigen::Vector3d> shifted;
  for (const auto& p : samples) shifted.push_back(p + origin);
  const Localiser loc = make(test::voxelise(shifted, {0.03, 0.1}, origin));
  const Eigen::Vector3d views[] = {{2.0, 2.0, 1.2}, {6.0, 4.0, 1.0}, {4.0, 1.5, 1.5}, {1.5, 4.5, 1.3}};
  int k = 0;
  for (const Eigen::Vector3d& v : views) {
    const SE3d T_o_m =
        test::yaw_pose(0.4 + 1.3 * k, Eigen::Vector3d(-3.0 + k, 2.0, 0.5)) * SE3d(Quatd::Identity(), -origin);
    const auto q = test::submap_request(shifted, v + origin, 4.0, 4000, 0.01, T_o_m, 7 + k);
    const auto r = loc.localise(q);
    ASSERT_EQ(r.status, Status::kOk) << k << ": " << r.detail;
    const Error e = pose_error(r.T_m_o, T_o_m.inverse(), q.anchor_o);
    EXPECT_LT(e.m, 0.02) << k;
    EXPECT_LT(e.deg, 0.3) << k;
    EXPECT_GT(r.fitness, 0.9);
    EXPECT_LT(r.ambiguity, 0.8);
    // The covariance (inflated) covers the error: 3 sigma per axis.
    const Eigen::Vector3d d = r.T_m_o * q.anchor_o - T_o_m.inverse() * q.anchor_o;
    for (int i = 0; i < 3; ++i)
      EXPECT_LT(std::abs(d[i]), 3.0 * std::sqrt(r.covariance(i, i)) + 1e-4) << k << " " << i;
    EXPECT_GT(r.time_ms, 0.0);
    ++k;
  }
}

TEST(Localiser, ABareRectangularRoomIsAmbiguous) {
  test::Scene scene;  // 8 x 6 x 3 m, no boxes: a half turn about its centre maps it onto itself
  const auto samples = scene.sample(0.01);
  const Localiser loc = make(test::voxelise(samples, {0.03, 0.1}));
  const auto q =
      test::submap_request(samples, {4.3, 3.2, 1.4}, 4.0, 4000, 0.01, test::yaw_pose(1.0, {1, 1, 0}), 3);
  const auto r = loc.localise(q);
  EXPECT_EQ(r.status, Status::kAmbiguous) << r.detail;
  EXPECT_GT(r.ambiguity, 0.9);
}

TEST(Localiser, TextureTellsABareRoomsHalfTurnApart) {
  test::Scene scene;  // the bare room again, its surfaces textured (the map's intensity)
  const auto samples = scene.sample(0.01);
  const auto map = test::voxelise(samples, {0.03, 0.1}, Eigen::Vector3d::Zero(), test::blob_albedo);
  LocaliserOptions o;
  o.appearance_weight = 0.5;
  o.appearance_slide_m = 0.3;
  const Localiser loc = make(map, o);
  const SE3d T_o_m = test::yaw_pose(1.0, {1, 1, 0});
  auto q = test::submap_request(samples, {4.3, 3.2, 1.4}, 4.0, 4000, 0.01, T_o_m, 3);
  test::add_brightness(&q, T_o_m, test::blob_albedo, 4);
  const auto r = loc.localise(q);
  ASSERT_EQ(r.status, Status::kOk) << r.detail;
  const Error e = pose_error(r.T_m_o, T_o_m.inverse(), q.anchor_o);
  EXPECT_LT(e.m, 0.03);
  EXPECT_LT(e.deg, 0.5);
  EXPECT_LT(r.ambiguity, 0.2);
  // Geometry alone cannot: ambiguous.
  const auto geometry_only = make(map).localise(q);
  EXPECT_EQ(geometry_only.status, Status::kAmbiguous) << geometry_only.detail;
  // Brightness unrelated to the map (shuffled): still ambiguous, never a confident pose.
  auto shuffled = q;
  std::mt19937 rng(9);
  std::shuffle(shuffled.brightness.begin(), shuffled.brightness.end(), rng);
  const auto r_shuffled = loc.localise(shuffled);
  EXPECT_EQ(r_shuffled.status, Status::kAmbiguous) << r_shuffled.detail;
  // A map without intensity (constant) tells nothing either.
  const auto untextured = make(test::voxelise(samples, {0.03, 0.1}), o).localise(q);
  EXPECT_EQ(untextured.status, Status::kAmbiguous) << untextured.detail;
}

TEST(Localiser, ABestPoseWhoseTextureDisagreesIsNoAnswer) {
  const auto samples = test::cluttered_room(14, 21).sample(0.01);
  const auto map = test::voxelise(samples, {0.03, 0.1}, Eigen::Vector3d::Zero(), test::blob_albedo);
  LocaliserOptions o;
  o.appearance_weight = 0.5;
  o.appearance_min = 0.4;
  const Localiser loc = make(map, o);
  const SE3d T_o_m = test::yaw_pose(0.7, {-1, 2, 0.3});
  auto q = test::submap_request(samples, {3.0, 2.5, 1.3}, 4.0, 4000, 0.01, T_o_m, 5);
  test::add_brightness(&q, T_o_m, test::blob_albedo, 6);
  const auto r = loc.localise(q);
  ASSERT_EQ(r.status, Status::kOk) << r.detail;
  EXPECT_LT(pose_error(r.T_m_o, T_o_m.inverse(), q.anchor_o).m, 0.03);
  // The same geometry with brightness unrelated to the map (shuffled): the geometry alone
  // would answer (appearance_min -1), the texture's floor refuses it without a guess.
  auto shuffled = q;
  std::mt19937 rng(11);
  std::shuffle(shuffled.brightness.begin(), shuffled.brightness.end(), rng);
  const auto refused = loc.localise(shuffled);
  EXPECT_EQ(refused.status, Status::kAmbiguous) << refused.detail;
  EXPECT_EQ(refused.hypotheses, 0);
  EXPECT_NE(refused.detail.find("appearance_min"), std::string::npos) << refused.detail;
  o.appearance_min = -1.0;
  const auto geometry = make(map, o).localise(shuffled);
  EXPECT_EQ(geometry.status, Status::kOk) << geometry.detail;
}

TEST(Localiser, AViewMostlyOfFloorLocalisesWithTheFloorCapped) {
  const test::Scene scene = test::cluttered_room(14, 21);
  const auto samples = scene.sample(0.01);
  // What a camera looking down sees: the floor around it, and little else (1 in 20 of the rest),
  // with stereo-like noise. The cap must keep enough floor to fix the height and enough of the
  // rest to place it (this room does not reproduce the report set's failure without the cap: an
  // exact search finds it either way; the dumps of cloud_server/localise/README.md do).
  const Eigen::Vector3d view(4.0, 3.0, 1.4);
  std::vector<Eigen::Vector3d> seen;
  int other = 0;
  for (const auto& p : samples) {
    if (p.z() < 0.005 ? (p - view).head<2>().norm() < 3.0 : (other++ % 20 == 0)) seen.push_back(p);
  }
  const SE3d T_o_m = test::yaw_pose(-2.0, {0.5, -1, 0.2});
  const auto q = test::submap_request(seen, view, 4.0, 5000, 0.03, T_o_m, 8);
  LocaliserOptions o;
  o.coarse_layer_share = 0.3;
  const auto r = make(test::voxelise(samples, {0.03, 0.1}), o).localise(q);
  ASSERT_EQ(r.status, Status::kOk) << r.detail;
  const Error e = pose_error(r.T_m_o, T_o_m.inverse(), q.anchor_o);
  EXPECT_LT(e.m, 0.03);
  EXPECT_LT(e.deg, 0.5);
}

TEST(Localiser, OneWallIsTooLittleStructure) {
  const test::Scene scene = test::cluttered_room(8, 5);
  const Localiser loc = make(test::voxelise(scene.sample(0.01), {0.03, 0.1}));
  localisation::Request q;
  for (double y = -1.0; y <= 1.0; y += 0.02) {
    for (double z = -0.5; z <= 0.8; z += 0.02)
      q.points.emplace_back(2.0f, static_cast<float>(y), static_cast<float>(z));
  }
  const auto r = loc.localise(q);
  EXPECT_TRUE(r.status == Status::kTooLittleStructure || r.status == Status::kAmbiguous)
      << localisation::status_name(r.status) << ": " << r.detail;
  EXPECT_NE(r.status, Status::kOk);
}

TEST(Localiser, AnotherPlaceIsOutsideTheMap) {
  const Localiser loc = make(test::voxelise(test::cluttered_room(10, 1).sample(0.01), {0.03, 0.1}));
  test::Scene elsewhere = test::cluttered_room(10, 99);
  elsewhere.room_max = Eigen::Vector3d(3.0, 11.0, 5.0);  // another room shape
  const auto q = test::submap_request(elsewhere.sample(0.01), {1.5, 5.0, 1.5}, 4.0, 4000, 0.01, SE3d(), 4);
  const auto r = loc.localise(q);
  EXPECT_NE(r.status, Status::kOk) << r.detail;
}

TEST(Localiser, APriorRegionOffTheMapIsOutsideTheMap) {
  const auto samples = test::cluttered_room(10, 1).sample(0.01);
  const Localiser loc = make(test::voxelise(samples, {0.03, 0.1}));
  auto q = test::submap_request(samples, {4, 3, 1.2}, 3.0, 3000, 0.01, SE3d(), 4);
  q.prior = localisation::PriorRegion{Eigen::Vector3d(100, 100, 0), 5.0};
  EXPECT_EQ(loc.localise(q).status, Status::kOutsideMap);
  q.prior = localisation::PriorRegion{Eigen::Vector3d(4.5, 3.5, 1.0), 1.5};  // the right place
  const auto r = loc.localise(q);
  EXPECT_EQ(r.status, Status::kOk) << r.detail;
}

TEST(Localiser, MalformedRequestsAreBadRequests) {
  const auto samples = test::cluttered_room(10, 1).sample(0.01);
  const Localiser loc = make(test::voxelise(samples, {0.03, 0.1}));
  const auto good = test::submap_request(samples, {4, 3, 1.2}, 3.0, 3000, 0.01, SE3d(), 4);
  auto q = good;
  q.points.resize(20);
  EXPECT_EQ(loc.localise(q).status, Status::kBadRequest);
  q = good;
  q.points[5].x() = NAN;
  EXPECT_EQ(loc.localise(q).status, Status::kBadRequest);
  q = good;
  q.gravity_o = Eigen::Vector3d(0, 0, -3);
  EXPECT_EQ(loc.localise(q).status, Status::kBadRequest);
  q = good;
  q.prior = localisation::PriorRegion{Eigen::Vector3d(4, 3, 1), -1.0};
  EXPECT_EQ(loc.localise(q).status, Status::kBadRequest);
  q = good;
  q.anchor_o.z() = INFINITY;
  EXPECT_EQ(loc.localise(q).status, Status::kBadRequest);
}

TEST(Localiser, TiltedGravityIsTakenIntoAccount) {
  const auto samples = test::cluttered_room(12, 6).sample(0.01);
  const Localiser loc = make(test::voxelise(samples, {0.03, 0.1}));
  // An odometry frame whose z is not up: gravity in it is R_o_m * (0, 0, -1).
  const SE3d T_o_m(Quatd(Eigen::AngleAxisd(0.2, Eigen::Vector3d(1, 1, 0).normalized())) *
                       Quatd(Eigen::AngleAxisd(2.0, Eigen::Vector3d::UnitZ())),
                   Eigen::Vector3d(1, -2, 0.3));
  auto q = test::submap_request(samples, {3, 3, 1.3}, 4.0, 4000, 0.01, T_o_m, 9);
  q.gravity_o = T_o_m.quaternion() * Eigen::Vector3d(0, 0, -1);
  const auto r = loc.localise(q);
  ASSERT_EQ(r.status, Status::kOk) << r.detail;
  const Error e = pose_error(r.T_m_o, T_o_m.inverse(), q.anchor_o);
  EXPECT_LT(e.m, 0.02);
  EXPECT_LT(e.deg, 0.3);
}

TEST(Localiser, CreateNamesAMissingFineLevel) {
  LocaliserOptions o;
  o.fine_resolution_m = 0.05;
  const auto l = Localiser::create(test::voxelise(test::Scene().sample(0.02), {0.03, 0.1}), o);
  ASSERT_FALSE(l.ok());
  EXPECT_NE(std::string(l.status().message()).find("fine_resolution_m"), std::string::npos);
}

}  // namespace
}  // namespace mrvs::localise
