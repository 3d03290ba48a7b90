#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/test/numeric_jacobian.h"
#include "synthetic.h"

namespace mrvs::eval {
namespace {

constexpr TimestampNs kT0 = 1'000'000'000'000;
constexpr DurationNs kMs = 1'000'000;

io::Trajectory smooth_ground_truth(std::uint32_t seed, int n, DurationNs dt_ns = 50 * kMs) {
  const synthetic::SmoothTrajectory traj(seed);
  return synthetic::sample([&](double t) { return traj.pose(t); }, kT0, dt_ns, n);
}

Association associate_or_die(const io::Trajectory& est, const io::Trajectory& gt) {
  auto a = associate(est, gt, {});
  EXPECT_TRUE(a.ok()) << a.status();
  return a.ok() ? *a : Association{};
}

void expect_se3_near(const SE3d& a, const SE3d& b, double tol_m, double tol_rad) {
  EXPECT_MATRIX_NEAR(a.translation(), b.translation(), tol_m);
  EXPECT_LE(quat::angular_distance(a.quaternion(), b.quaternion()), tol_rad);
}

TEST(EvalAlignment, RigidOffsetIsRecoveredAndUnalignedErrorMatchesAnalytic) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 5; ++trial) {
    const io::Trajectory gt = smooth_ground_truth(100 + trial, 500);
    const SE3d T_est_gt = synthetic::random_se3(rng, 5.0);
    const Association a = associate_or_die(synthetic::transform(T_est_gt, gt), gt);

    // Unaligned: per pose |p - (R p + t)|; every rotation error is the offset's angle.
    auto none = compute_ate(a, Alignment{});
    ASSERT_TRUE(none.ok()) << none.status();
    double sum_sq = 0.0;
    for (const io::StampedPose& p : gt) {
      sum_sq += (p.T_w_b.translation() - T_est_gt * p.T_w_b.translation()).squaredNorm();
    }
    EXPECT_NEAR(none->position_m.rmse, std::sqrt(sum_sq / gt.size()), 1e-9);
    const double offset_angle_deg = so3::log<double>(T_est_gt.quaternion()).norm() * kRadToDeg;
    EXPECT_NEAR(none->rotation_deg.rmse, offset_angle_deg, 1e-7);
    EXPECT_NEAR(none->rotation_deg.max, offset_angle_deg, 1e-7);

    // SE(3): the inverse offset, zero residual.
    auto se3 = align(a, AlignmentMethod::kSE3);
    ASSERT_TRUE(se3.ok()) << se3.status();
    EXPECT_EQ(se3->method, AlignmentMethod::kSE3);
    EXPECT_EQ(se3->scale, 1.0);
    expect_se3_near(se3->T_gt_est, T_est_gt.inverse(), 1e-9, 1e-10);
    auto ate = compute_ate(a, *se3);
    ASSERT_TRUE(ate.ok()) << ate.status();
    EXPECT_LT(ate->position_m.rmse, 1e-9);
    EXPECT_LT(ate->position_m.max, 1e-9);
    EXPECT_LT(ate->rotation_deg.rmse, 1e-6);
  }
}

TEST(EvalAlignment, PureTranslationOffsetGivesConstantUnalignedError) {
  const io::Trajectory gt = smooth_ground_truth(3, 300);
  const Vec3d t(0.3, -0.4, 1.2);  // |t| = 1.3 m
  const Association a = associate_or_die(synthetic::transform(SE3d(Quatd::Identity(), t), gt), gt);
  auto ate = compute_ate(a, Alignment{});
  ASSERT_TRUE(ate.ok()) << ate.status();
  EXPECT_NEAR(ate->position_m.rmse, 1.3, 1e-12);
  EXPECT_NEAR(ate->position_m.mean, 1.3, 1e-12);
  EXPECT_NEAR(ate->position_m.median, 1.3, 1e-12);
  EXPECT_NEAR(ate->position_m.max, 1.3, 1e-12);
  EXPECT_NEAR(ate->position_m.std, 0.0, 1e-9);
  EXPECT_NEAR(ate->rotation_deg.max, 0.0, 1e-9);
  EXPECT_EQ(ate->position_m.count, gt.size());
}

TEST(EvalAlignment, IsotropicNoiseGivesRmseOfSigmaSqrt3) {
  const double sigma = 0.05;  // m per axis
  const io::Trajectory gt = smooth_ground_truth(4, 4000);
  std::mt19937 rng(12);
  const SE3d T_est_gt = synthetic::random_se3(rng, 3.0);
  io::Trajectory est = synthetic::transform(T_est_gt, gt);
  std::normal_distribution<double> noise(0.0, sigma);
  for (io::StampedPose& p : est) p.T_w_b.translation() += Vec3d(noise(rng), noise(rng), noise(rng));
  const Association a = associate_or_die(est, gt);
  auto se3 = align(a, AlignmentMethod::kSE3);
  ASSERT_TRUE(se3.ok()) << se3.status();
  auto ate = compute_ate(a, *se3);
  ASSERT_TRUE(ate.ok()) << ate.status();
  const double expected = sigma * std::sqrt(3.0);
  EXPECT_NEAR(ate->position_m.rmse, expected, 0.03 * expected);
  // 4000 points pin the transform down to a few mm / hundredths of a degree.
  expect_se3_near(se3->T_gt_est, T_est_gt.inverse(), 5e-3, 5e-4);
}

TEST(EvalAlignment, Sim3RecoversScale) {
  const io::Trajectory gt = smooth_ground_truth(5, 400);
  std::mt19937 rng(13);
  const SE3d T = synthetic::random_se3(rng, 4.0);
  const double s_est = 0.62;  // the estimate is 0.62 times too small
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) {
    p.T_w_b = SE3d(T.quaternion() * p.T_w_b.quaternion(),
                   s_est * (T.quaternion() * p.T_w_b.translation()) + T.translation());
  }
  const Association a = associate_or_die(est, gt);
  auto sim3 = align(a, AlignmentMethod::kSim3);
  ASSERT_TRUE(sim3.ok()) << sim3.status();
  EXPECT_EQ(sim3->method, AlignmentMethod::kSim3);
  EXPECT_NEAR(sim3->scale, 1.0 / s_est, 1e-9);
  EXPECT_LE(quat::angular_distance(sim3->T_gt_est.quaternion(), T.quaternion().conjugate()), 1e-9);
  auto ate = compute_ate(a, *sim3);
  ASSERT_TRUE(ate.ok()) << ate.status();
  EXPECT_LT(ate->position_m.rmse, 1e-9);
  EXPECT_LT(ate->rotation_deg.rmse, 1e-6);
  // A rigid alignment cannot absorb the scale error.
  auto se3 = align(a, AlignmentMethod::kSE3);
  ASSERT_TRUE(se3.ok());
  EXPECT_GT(compute_ate(a, *se3)->position_m.rmse, 0.1);
}

TEST(EvalAlignment, FirstPoseAlignmentMatchesTheFirstPoseExactly) {
  const io::Trajectory gt = smooth_ground_truth(6, 200);
  std::mt19937 rng(14);
  const SE3d T_est_gt = synthetic::random_se3(rng, 2.0);
  io::Trajectory est = synthetic::transform(T_est_gt, gt);
  est.back().T_w_b.translation() += Vec3d(0.0, 0.0, 0.5);  // an error at the end only
  const Association a = associate_or_die(est, gt);
  auto first = align(a, AlignmentMethod::kFirstPose);
  ASSERT_TRUE(first.ok()) << first.status();
  expect_se3_near(first->T_gt_est, T_est_gt.inverse(), 1e-12, 1e-12);
  auto ate = compute_ate(a, *first);
  ASSERT_TRUE(ate.ok());
  EXPECT_NEAR(ate->position_m.max, 0.5, 1e-9);
  EXPECT_NEAR(ate->position_errors_m.front(), 0.0, 1e-12);
  EXPECT_NEAR(ate->position_m.median, 0.0, 1e-9);
}

TEST(EvalAlignment, PlanarTrajectoryIsNotDegenerate) {
  const auto circle = [](double t) { return SE3d(Quatd::Identity(), Vec3d(std::cos(t), std::sin(t), 0.0)); };
  const io::Trajectory gt = synthetic::sample(circle, kT0, 100 * kMs, 50);
  const SE3d T(so3::exp_quat<double>(Vec3d(0.3, -1.0, 0.4)), Vec3d(1, 2, 3));
  const Association a = associate_or_die(synthetic::transform(T, gt), gt);
  auto se3 = align(a, AlignmentMethod::kSE3);
  ASSERT_TRUE(se3.ok()) << se3.status();
  expect_se3_near(se3->T_gt_est, T.inverse(), 1e-9, 1e-9);
}

TEST(EvalAlignment, TooFewPosesAreReported) {
  const io::Trajectory gt = smooth_ground_truth(7, 2);
  const Association a = associate_or_die(gt, gt);
  ASSERT_EQ(a.matches.size(), 2u);
  for (AlignmentMethod m : {AlignmentMethod::kSE3, AlignmentMethod::kSim3}) {
    auto r = align(a, m);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition) << alignment_name(m);
    EXPECT_NE(r.status().message().find("at least 3 associated poses, got 2"), std::string::npos)
        << r.status();
  }
  EXPECT_TRUE(align(a, AlignmentMethod::kFirstPose).ok());
  EXPECT_TRUE(align(a, AlignmentMethod::kNone).ok());
  EXPECT_EQ(align(Association{}, AlignmentMethod::kFirstPose).status().code(),
            absl::StatusCode::kFailedPrecondition);
  EXPECT_EQ(compute_ate(Association{}, Alignment{}).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(EvalAlignment, DegenerateGeometryIsReported) {
  const auto line = [](double t) {
    return SE3d(Quatd::Identity(), Vec3d(1.0, 2.0, 3.0) + t * Vec3d(1, -1, 2));
  };
  const io::Trajectory gt = synthetic::sample(line, kT0, 100 * kMs, 30);
  const Association a = associate_or_die(gt, gt);
  for (AlignmentMethod m : {AlignmentMethod::kSE3, AlignmentMethod::kSim3}) {
    auto r = align(a, m);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_NE(r.status().message().find("collinear"), std::string::npos) << r.status();
  }
  const auto still = [](double) { return SE3d(Quatd::Identity(), Vec3d(1.0, 2.0, 3.0)); };
  const io::Trajectory parked = synthetic::sample(still, kT0, 100 * kMs, 30);
  auto r = align(associate_or_die(parked, parked), AlignmentMethod::kSE3);
  EXPECT_EQ(r.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(r.status().message().find("same point"), std::string::npos) << r.status();
}

TEST(EvalAlignment, ApplyIsTheSimilarityTransform) {
  Alignment al;
  al.method = AlignmentMethod::kSim3;
  al.T_gt_est = SE3d(so3::exp_quat<double>(Vec3d(0.1, 0.2, -0.3)), Vec3d(1, -2, 0.5));
  al.scale = 2.5;
  const SE3d T_west_b(so3::exp_quat<double>(Vec3d(-0.4, 0.0, 0.9)), Vec3d(0.3, 0.7, -1.1));
  const SE3d out = al.apply(T_west_b);
  const Mat3d R = al.T_gt_est.rotation_matrix();
  EXPECT_MATRIX_NEAR(out.translation(), Vec3d(2.5 * R * T_west_b.translation() + al.T_gt_est.translation()),
                     1e-12);
  EXPECT_MATRIX_NEAR(out.rotation_matrix(), Mat3d(R * T_west_b.rotation_matrix()), 1e-12);
}

TEST(EvalAlignment, NamesRoundTrip) {
  for (AlignmentMethod m :
       {AlignmentMethod::kNone, AlignmentMethod::kSE3, AlignmentMethod::kSim3, AlignmentMethod::kFirstPose}) {
    auto parsed = parse_alignment_method(alignment_name(m));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, m);
  }
  auto bad = parse_alignment_method("affine");
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status().message().find("affine"), std::string::npos);
}

}  // namespace
}  // namespace mrvs::eval
