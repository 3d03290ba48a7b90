// The trajectory edge_client writes: poses held in the odometry frame until the cloud places
// their run, moved by that answer; a doubted lock gives back what it placed, the next answer
// places it; poses never placed are kept as the filter had them and counted; each lock's own
// placement is kept as accepted.
#include <gtest/gtest.h>

#include "mrvs/edge/map_trajectory.h"

namespace mrvs::edge {
namespace {

constexpr TimestampNs kSecond = 1'000'000'000;

/// A walk along x in the map frame; the odometry frame is the map turned by yaw and moved.
SE3d truth(int k) { return SE3d(Quatd::Identity(), Vec3d(0.1 * k, 0.0, 1.0)); }
SE3d frame(double yaw, const Vec3d& t) { return SE3d(Quatd(Eigen::AngleAxisd(yaw, Vec3d::UnitZ())), t); }

double max_error(const io::Trajectory& out, int first, int count) {
  double e = 0.0;
  for (int k = first; k < first + count; ++k) {
    const io::StampedPose& p = out.at(static_cast<std::size_t>(k - first));
    EXPECT_EQ(p.t_ns, k * kSecond);
    e = std::max(e, (p.T_w_b.translation() - truth(k).translation()).norm());
  }
  return e;
}

TEST(MapTrajectory, APlacedRunsEarlierPosesFollowItsAnswer) {
  const SE3d T_o_m = frame(0.7, Vec3d(3.0, -2.0, 0.5));
  MapTrajectory t;
  for (int k = 0; k < 10; ++k) {
    const bool placed = k == 4;
    const SE3d T_w_b = k < 4 ? T_o_m * truth(k) : truth(k);  // the state moves into the map at the lock
    t.add(0, {k * kSecond, T_w_b}, k >= 4, placed ? std::optional<SE3d>(T_o_m.inverse()) : std::nullopt,
          false);
  }
  t.finish();
  ASSERT_EQ(t.trajectory().size(), 10u);
  EXPECT_LT(max_error(t.trajectory(), 0, 10), 1e-12);
  EXPECT_EQ(t.never_mapped(), 0);
  EXPECT_EQ(t.odometry().size(), 4u);
}

// A wrong lock (4 m and 180 deg off) places the run, a later refused fix doubts it, the cloud
// then places the filter right: every pose, those the wrong lock placed too, ends in the map.
TEST(MapTrajectory, ADoubtedLocksPosesAreMovedByTheNextAnswer) {
  const SE3d T_o_m = frame(0.3, Vec3d(1.0, 2.0, 0.0));
  const SE3d wrong =
      frame(M_PI, Vec3d(4.0, 0.0, 0.0)) * T_o_m.inverse();  // what the wrong lock says T_m_o is
  // The filter's frame after the wrong lock: f = wrong * o; the right answer then is T_m_f.
  const SE3d T_m_f = T_o_m.inverse() * wrong.inverse();
  MapTrajectory t;
  for (int k = 0; k < 20; ++k) {
    std::optional<SE3d> placed;
    bool in_map = false, doubted = false;
    SE3d T_w_b = T_o_m * truth(k);                 // odometry frame before the wrong lock
    if (k >= 3) T_w_b = wrong * T_o_m * truth(k);  // the filter's frame from the wrong lock on
    if (k == 3) placed = wrong;
    in_map = (k >= 3 && k < 8) || k >= 12;
    doubted = k == 8;
    if (k == 12) placed = T_m_f;
    if (k >= 12) T_w_b = truth(k);  // moved into the map by the right answer
    t.add(0, {k * kSecond, T_w_b}, in_map, placed, doubted);
  }
  t.finish();
  ASSERT_EQ(t.trajectory().size(), 20u);
  EXPECT_LT(max_error(t.trajectory(), 0, 20), 1e-9);
  EXPECT_EQ(t.never_mapped(), 0);
  // The locks as accepted: the wrong one where it put the body (4 m off), the right one right.
  ASSERT_EQ(t.locks().size(), 2u);
  EXPECT_EQ(t.locks()[0].t_ns, 3 * kSecond);
  EXPECT_GT((t.locks()[0].T_w_b.translation() - truth(3).translation()).norm(), 3.0);
  EXPECT_EQ(t.locks()[1].t_ns, 12 * kSecond);
  EXPECT_LT((t.locks()[1].T_w_b.translation() - truth(12).translation()).norm(), 1e-9);
}

// A right lock, then the filter drifts (a linear walk in se(3), 6 cm and 1.5 deg by the doubt) and
// stops drifting; the next answer corrects the drift: the poses the doubted lock placed get the
// correction ramped in (none at the lock, all of it at the doubt) and end on the truth, where
// moving them in full would put the first ones 6 cm off.
TEST(MapTrajectory, ARightLockDoubtedForDriftKeepsItsPlacementAndRampsTheCorrectionIn) {
  Vec6d drift;
  drift << 0.05, -0.03, 0.01, 0.0, 0.0, 1.5 * M_PI / 180.0;
  auto D = [&](int k) { return SE3d::exp(std::clamp((k - 3) / 4.0, 0.0, 1.0) * drift); };
  const SE3d T_o_m = frame(0.4, Vec3d(2.0, 1.0, 0.0));
  MapTrajectory t;
  for (int k = 0; k < 16; ++k) {
    std::optional<SE3d> placed;
    SE3d T_w_b = T_o_m * truth(k);
    if (k >= 3) T_w_b = D(k) * truth(k);  // the map frame from the right lock on, drifting
    if (k == 3) placed = T_o_m.inverse();
    const bool in_map = (k >= 3 && k < 8) || k >= 12;
    if (k == 12) placed = D(12).inverse();  // the correction of the drift
    if (k >= 12) T_w_b = truth(k);
    t.add(0, {k * kSecond, T_w_b}, in_map, placed, k == 8);
  }
  t.finish();
  ASSERT_EQ(t.trajectory().size(), 16u);
  EXPECT_LT(max_error(t.trajectory(), 0, 16), 1e-9);
}

// Doubted and never placed again before a restart: the poses are kept as the filter had them
// (the wrong lock's frame), counted as never placed; the next run is placed on its own.
TEST(MapTrajectory, PosesNeverPlacedAgainAreKeptAndCounted) {
  MapTrajectory t;
  const SE3d off = frame(0.0, Vec3d(0.5, 0.0, 0.0));
  for (int k = 0; k < 6; ++k) {
    t.add(0, {k * kSecond, off * truth(k)}, k >= 2 && k < 4,
          k == 2 ? std::optional<SE3d>(SE3d()) : std::nullopt, k == 4);
  }
  for (int k = 6; k < 10; ++k) {
    t.add(1, {k * kSecond, truth(k)}, k >= 7, k == 7 ? std::optional<SE3d>(SE3d()) : std::nullopt, false);
  }
  t.finish();
  ASSERT_EQ(t.trajectory().size(), 10u);
  EXPECT_EQ(t.never_mapped(), 6);  // run 0: the two before the lock and the four it placed or held
  EXPECT_NEAR(max_error(t.trajectory(), 0, 6), 0.5, 1e-12);
  for (std::size_t i = 6; i < 10; ++i)
    EXPECT_LT((t.trajectory()[i].T_w_b.translation() - truth(static_cast<int>(i)).translation()).norm(),
              1e-12);
}

}  // namespace
}  // namespace mrvs::edge
