#include <cmath>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/test/numeric_jacobian.h"
#include "synthetic.h"

namespace mrvs::eval {
namespace {

constexpr TimestampNs kT0 = 1'403'715'273'262'142'976;  // a EuRoC-sized stamp
constexpr DurationNs kMs = 1'000'000;

/// Constant linear velocity and constant angular rate about a fixed axis: linear position
/// interpolation and slerp are exact for it.
SE3d constant_twist(double t_s) {
  const Vec3d v(0.7, -0.2, 0.1);  // m/s
  const Vec3d w(0.1, 0.3, -0.5);  // rad/s
  return SE3d(so3::exp_quat<double>(w * t_s), Vec3d(1.0, 2.0, 3.0) + v * t_s);
}

/// Brute-force reference: linear scan for the bracket, slerp through exp/log.
SE3d brute_force_ground_truth(const io::Trajectory& gt, TimestampNs t) {
  for (std::size_t k = 0; k + 1 < gt.size(); ++k) {
    if (gt[k].t_ns <= t && t <= gt[k + 1].t_ns) {
      const double a = static_cast<double>(t - gt[k].t_ns) / static_cast<double>(gt[k + 1].t_ns - gt[k].t_ns);
      const Quatd qa = gt[k].T_w_b.quaternion();
      const Quatd qb = gt[k + 1].T_w_b.quaternion();
      const Quatd q = qa * so3::exp_quat<double>(a * so3::log<double>(qa.conjugate() * qb));
      return SE3d(q, (1 - a) * gt[k].T_w_b.translation() + a * gt[k + 1].T_w_b.translation());
    }
  }
  ADD_FAILURE() << "no bracket for " << t;
  return SE3d();
}

void expect_pose_near(const SE3d& a, const SE3d& b, double tol) {
  EXPECT_MATRIX_NEAR(a.translation(), b.translation(), tol);
  EXPECT_LE(quat::angular_distance(a.quaternion(), b.quaternion()), tol);
}

TEST(EvalAssociation, IdenticalStampsAreExactMatches) {
  const io::Trajectory gt = synthetic::sample(synthetic::SmoothTrajectory(1), kT0, 5 * kMs, 200);
  auto a = associate(gt, gt, {});
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->matches.size(), gt.size());
  EXPECT_EQ(a->num_exact, gt.size());
  EXPECT_EQ(a->num_interpolated + a->num_nearest + a->num_unmatched, 0u);
  for (std::size_t i = 0; i < gt.size(); ++i) {
    EXPECT_EQ(a->matches[i].t_ns, gt[i].t_ns);
    expect_pose_near(a->matches[i].T_wgt_b, gt[i].T_w_b, 0.0);
  }
}

TEST(EvalAssociation, InterpolationIsExactForConstantTwistAtJitteredStamps) {
  const io::Trajectory gt = synthetic::sample(constant_twist, kT0, 5 * kMs, 400);  // 200 Hz, 2 s
  std::mt19937 rng(7);
  std::uniform_int_distribution<DurationNs> jitter(-3 * kMs, 3 * kMs);
  io::Trajectory est;
  for (int k = 1; k < 60; ++k) {  // ~30 Hz, off the ground-truth grid
    const TimestampNs t = kT0 + k * 33 * kMs + jitter(rng) + 123;
    est.push_back({t, constant_twist(to_seconds(t - kT0))});
  }
  auto a = associate(est, gt, {});
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_EQ(a->matches.size(), est.size());
  EXPECT_EQ(a->num_interpolated, est.size());
  for (const Match& m : a->matches) {
    EXPECT_EQ(m.kind, MatchKind::kInterpolated);
    expect_pose_near(m.T_wgt_b, constant_twist(to_seconds(m.t_ns - kT0)), 1e-9);
  }
}

TEST(EvalAssociation, MatchesBruteForceOnSmoothTrajectoryAtDifferentRates) {
  const synthetic::SmoothTrajectory traj(2);
  const auto f = [&](double t) { return traj.pose(t); };
  const io::Trajectory gt = synthetic::sample(f, kT0, 5 * kMs, 2000);  // 200 Hz
  std::mt19937 rng(8);
  std::uniform_int_distribution<DurationNs> jitter(-20 * kMs, 20 * kMs);
  io::Trajectory est;
  for (int k = 1; k < 190; ++k) {  // 20 Hz with +-20 ms jitter
    const TimestampNs t = kT0 + k * 50 * kMs + jitter(rng);
    est.push_back({t, f(to_seconds(t - kT0))});
  }
  auto a = associate(est, gt, {});
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_EQ(a->matches.size(), est.size());
  for (const Match& m : a->matches) {
    expect_pose_near(m.T_wgt_b, brute_force_ground_truth(gt, m.t_ns), 1e-12);
    // Interpolation error of a smooth trajectory sampled at 200 Hz is tiny.
    expect_pose_near(m.T_wgt_b, f(to_seconds(m.t_ns - kT0)), 1e-4);
  }
}

TEST(EvalAssociation, KnownTimeOffsetIsCompensated) {
  // The estimator's clock is 37.5 ms behind: its pose stamped t is the true pose at t + offset.
  const DurationNs offset = 37'500'000;
  const io::Trajectory gt = synthetic::sample(constant_twist, kT0, 5 * kMs, 400);
  io::Trajectory est;
  for (int k = 0; k < 50; ++k) {
    const TimestampNs t_true = kT0 + 100 * kMs + k * 30 * kMs + 1'234;
    est.push_back({t_true - offset, constant_twist(to_seconds(t_true - kT0))});
  }
  auto fixed = associate(est, gt, {10 * kMs, offset});
  ASSERT_TRUE(fixed.ok()) << fixed.status();
  ASSERT_EQ(fixed->matches.size(), est.size());
  for (std::size_t i = 0; i < est.size(); ++i) {
    EXPECT_EQ(fixed->matches[i].t_ns, est[i].t_ns + offset);
    expect_pose_near(fixed->matches[i].T_wgt_b, est[i].T_w_b, 1e-9);
  }
  // Without the offset every position is off by |v| * offset.
  auto raw = associate(est, gt, {});
  ASSERT_TRUE(raw.ok()) << raw.status();
  const double expected = Vec3d(0.7, -0.2, 0.1).norm() * to_seconds(offset);
  for (const Match& m : raw->matches) {
    EXPECT_NEAR((m.T_wgt_b.translation() - m.T_west_b.translation()).norm(), expected, 1e-9);
  }
}

TEST(EvalAssociation, CountsNearestAndUnmatchedAroundGapsAndEnds) {
  // Ground truth at 100 Hz over [0, 1] s with the samples strictly inside (0.5, 0.7) s removed.
  io::Trajectory gt;
  for (int k = 0; k <= 100; ++k) {
    if (k > 50 && k < 70) continue;
    gt.push_back({kT0 + k * 10 * kMs, constant_twist(k * 0.01)});
  }
  const auto at = [&](DurationNs dt) { return io::StampedPose{kT0 + dt, SE3d()}; };
  const io::Trajectory est = {
      at(-20 * kMs),      // before the start, beyond tolerance: unmatched
      at(-5 * kMs),       // before the start, within tolerance: nearest (t = 0)
      at(250 * kMs),      // on a sample: exact
      at(255 * kMs),      // bracketed: interpolated
      at(505 * kMs),      // bracket 0.5 / 0.7 too wide, 0.5 within tolerance: nearest
      at(600 * kMs),      // in the gap: unmatched
      at(695 * kMs),      // nearest (0.7)
      at(1000 * kMs),     // last sample: exact
      at(1010 * kMs),     // exactly max_dt after the end: nearest
      at(1010 * kMs + 1)  // just beyond: unmatched
  };
  auto a = associate(est, gt, {10 * kMs, 0});
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->num_exact, 2u);
  EXPECT_EQ(a->num_interpolated, 1u);
  EXPECT_EQ(a->num_nearest, 4u);
  EXPECT_EQ(a->num_unmatched, 3u);
  ASSERT_EQ(a->matches.size(), 7u);
  expect_pose_near(a->matches[0].T_wgt_b, constant_twist(0.0), 1e-12);   // -5 ms -> t = 0
  expect_pose_near(a->matches[3].T_wgt_b, constant_twist(0.5), 1e-12);   // 505 ms -> 0.5 s
  expect_pose_near(a->matches[4].T_wgt_b, constant_twist(0.7), 1e-12);   // 695 ms -> 0.7 s
  expect_pose_near(a->matches[6].T_wgt_b, constant_twist(1.0), 1e-12);   // 1010 ms -> 1.0 s
  expect_pose_near(a->matches[2].T_wgt_b, constant_twist(0.255), 1e-9);  // interpolated
}

TEST(EvalAssociation, ReportsBadInput) {
  const io::Trajectory gt = synthetic::sample(constant_twist, kT0, 10 * kMs, 10);
  EXPECT_EQ(associate({}, gt, {}).status().code(), absl::StatusCode::kInvalidArgument);
  const auto empty_gt = associate(gt, {}, {});
  EXPECT_EQ(empty_gt.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(empty_gt.status().message().find("ground-truth trajectory is empty"), std::string::npos);

  io::Trajectory unordered = gt;
  std::swap(unordered[3], unordered[4]);
  const auto s = associate(unordered, gt, {});
  EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.status().message().find("not strictly increasing"), std::string::npos) << s.status();

  io::Trajectory nan_pose = gt;
  nan_pose[2].T_w_b.translation().x() = std::nan("");
  EXPECT_EQ(associate(nan_pose, gt, {}).status().code(), absl::StatusCode::kInvalidArgument);

  EXPECT_EQ(associate(gt, gt, {-1, 0}).status().code(), absl::StatusCode::kInvalidArgument);

  // Disjoint time ranges: nothing matches, the message suggests what to check.
  const auto none = associate(gt, gt, {10 * kMs, 5 * kNanosecondsPerSecond});
  EXPECT_EQ(none.status().code(), absl::StatusCode::kNotFound);
  EXPECT_NE(none.status().message().find("no estimate pose has ground truth"), std::string::npos);
}

TEST(EvalAssociation, InterpolatePoseEndpointsAndMidpoint) {
  const SE3d a(so3::exp_quat<double>(Vec3d(0, 0, 0.2)), Vec3d(1, 0, 0));
  const SE3d b(so3::exp_quat<double>(Vec3d(0, 0, 1.0)), Vec3d(3, 2, 0));
  expect_pose_near(interpolate_pose(a, b, 0.0), a, 1e-15);
  expect_pose_near(interpolate_pose(a, b, 1.0), b, 1e-15);
  const SE3d mid(so3::exp_quat<double>(Vec3d(0, 0, 0.6)), Vec3d(2, 1, 0));
  expect_pose_near(interpolate_pose(a, b, 0.5), mid, 1e-15);
  // Takes the short way even when the quaternions have opposite signs.
  SE3d b_neg = b;
  b_neg.set_quaternion(Quatd(-b.quaternion().coeffs()));
  expect_pose_near(interpolate_pose(a, b_neg, 0.5), mid, 1e-15);
}

}  // namespace
}  // namespace mrvs::eval
