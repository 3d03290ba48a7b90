#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/quaternion.h"
#include "synthetic.h"

namespace mrvs::eval {
namespace {

constexpr TimestampNs kT0 = 2'000'000'000'000;
constexpr DurationNs kMs = 1'000'000;

Association associate_or_die(const io::Trajectory& est, const io::Trajectory& gt) {
  auto a = associate(est, gt, {});
  EXPECT_TRUE(a.ok()) << a.status();
  return a.ok() ? *a : Association{};
}

/// RPE errors of one pair through plain 4x4 matrices (independent of SE3d's operators).
std::pair<double, double> brute_force_rpe_error(const Match& i, const Match& j, double scale) {
  Mat4d est_i = i.T_west_b.matrix(), est_j = j.T_west_b.matrix();
  est_i.topRightCorner<3, 1>() *= scale;
  est_j.topRightCorner<3, 1>() *= scale;
  const Mat4d gt_rel = i.T_wgt_b.matrix().inverse() * j.T_wgt_b.matrix();
  const Mat4d E = gt_rel.inverse() * est_i.inverse() * est_j;
  const double cos_angle = std::clamp((E.topLeftCorner<3, 3>().trace() - 1.0) / 2.0, -1.0, 1.0);
  return {E.topRightCorner<3, 1>().norm(), std::acos(cos_angle) * kRadToDeg};
}

TEST(EvalStats, KnownValues) {
  auto even = compute_stats({4.0, 1.0, 3.0, 2.0});
  ASSERT_TRUE(even.ok());
  EXPECT_EQ(even->count, 4u);
  EXPECT_DOUBLE_EQ(even->mean, 2.5);
  EXPECT_DOUBLE_EQ(even->median, 2.5);
  EXPECT_DOUBLE_EQ(even->rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(even->std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(even->min, 1.0);
  EXPECT_DOUBLE_EQ(even->max, 4.0);
  auto odd = compute_stats({3.0, 10.0, 1.0});
  ASSERT_TRUE(odd.ok());
  EXPECT_DOUBLE_EQ(odd->median, 3.0);
  EXPECT_EQ(compute_stats({}).status().code(), absl::StatusCode::kInvalidArgument);
}

TEST(EvalRpe, PairSelectionMatchesBruteForce) {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> step(0.0, 0.3);
  std::bernoulli_distribution pause(0.2);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> key = {0.0};
    for (int k = 0; k < 200; ++k) key.push_back(key.back() + (pause(rng) ? 0.0 : step(rng)));
    const double delta = 0.5 + trial * 0.2;
    std::vector<std::pair<std::size_t, std::size_t>> expected;
    for (std::size_t i = 0; i < key.size(); ++i) {
      if (key.back() < key[i] + delta) break;
      std::size_t best = 0;
      double best_err = INFINITY;
      for (std::size_t j = i + 1; j < key.size(); ++j) {
        const double err = std::abs(key[j] - key[i] - delta);
        // Candidates: anything up to the first j that reaches delta; ties go to the later j.
        if (err <= best_err) {
          best = j;
          best_err = err;
        }
        if (key[j] >= key[i] + delta) break;
      }
      expected.emplace_back(i, best);
    }
    EXPECT_EQ(select_rpe_pairs(key, delta), expected) << "trial " << trial;
  }
}

TEST(EvalRpe, ConstantTranslationDriftPerMetre) {
  // Straight line at 1 m/s sampled every 10 ms; the estimate drifts sideways by 2 cm per
  // metre travelled, so every 1 m pair has a 2 cm relative error.
  const double drift = 0.02;
  const auto line = [](double t) { return SE3d(Quatd::Identity(), Vec3d(t, 0.0, 0.0)); };
  const io::Trajectory gt = synthetic::sample(line, kT0, 10 * kMs, 1001);  // 10 m
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) p.T_w_b.translation().y() += drift * p.T_w_b.translation().x();
  auto rpe = compute_rpe(associate_or_die(est, gt), {1.0, RpeUnit::kMetres});
  ASSERT_TRUE(rpe.ok()) << rpe.status();
  EXPECT_EQ(rpe->num_pairs, 901u);
  EXPECT_NEAR(rpe->mean_pair_delta, 1.0, 1e-9);
  EXPECT_NEAR(rpe->translation_m.rmse, drift, 1e-9);
  EXPECT_NEAR(rpe->translation_m.max, drift, 1e-9);
  EXPECT_NEAR(rpe->rotation_deg.max, 0.0, 1e-9);
}

TEST(EvalRpe, ConstantYawDriftPerMetreOnACurvedPath) {
  // The estimate's world yaws away at k rad per metre of path: every pair's rotation error
  // is exactly k times its path length.
  const double k = 0.01;  // rad/m
  const synthetic::SmoothTrajectory traj(22);
  const io::Trajectory gt = synthetic::sample([&](double t) { return traj.pose(t); }, kT0, 5 * kMs, 6000);
  const Association gt_only = associate_or_die(gt, gt);
  const std::vector<double> s = ground_truth_path_length(gt_only);
  io::Trajectory est = gt;
  for (std::size_t i = 0; i < est.size(); ++i) {
    est[i].T_w_b.set_quaternion(so3::exp_quat<double>(Vec3d(0, 0, k * s[i])) * gt[i].T_w_b.quaternion());
  }
  const Association a = associate_or_die(est, gt);
  auto rpe = compute_rpe(a, {2.0, RpeUnit::kMetres});
  ASSERT_TRUE(rpe.ok()) << rpe.status();
  const auto pairs = select_rpe_pairs(s, 2.0);
  ASSERT_EQ(rpe->num_pairs, pairs.size());
  std::vector<double> expected_rot, expected_trans;
  for (const auto& [i, j] : pairs) {
    expected_rot.push_back(k * (s[j] - s[i]) * kRadToDeg);
    expected_trans.push_back(brute_force_rpe_error(a.matches[i], a.matches[j], 1.0).first);
  }
  EXPECT_NEAR(rpe->rotation_deg.rmse, compute_stats(expected_rot)->rmse, 1e-9);
  EXPECT_NEAR(rpe->rotation_deg.rmse, k * 2.0 * kRadToDeg, 0.01 * k * 2.0 * kRadToDeg);
  EXPECT_NEAR(rpe->translation_m.rmse, compute_stats(expected_trans)->rmse, 1e-9);
}

TEST(EvalAte, HeadingIsTheTwistAboutZ) {
  // A rotation about z, then any tilt about a horizontal axis applied before it: the heading
  // is exactly the z angle (the tilt's swing does not leak in), wrapped into (-180, 180].
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> yaw(-179.0, 179.0), tilt(-60.0, 60.0), dir(0.0, 2.0 * kPi);
  for (int trial = 0; trial < 200; ++trial) {
    const double psi = yaw(rng);
    const double a = dir(rng);
    const Quatd q = so3::exp_quat<double>(Vec3d(0, 0, psi * kDegToRad)) *
                    so3::exp_quat<double>(tilt(rng) * kDegToRad * Vec3d(std::cos(a), std::sin(a), 0.0));
    EXPECT_NEAR(heading_about_z_deg(q), psi, 1e-9) << trial;
    EXPECT_NEAR(heading_about_z_deg(Quatd(-q.coeffs())), psi, 1e-9) << trial;  // same rotation
  }
  EXPECT_NEAR(heading_about_z_deg(so3::exp_quat<double>(Vec3d(0, 0, 190.0 * kDegToRad))), -170.0, 1e-9);
  EXPECT_NEAR(heading_about_z_deg(so3::exp_quat<double>(Vec3d(0.3, -0.2, 0.0))), 0.0, 1e-12);
}

TEST(EvalAte, HeadingErrorOfAYawDriftAndNotOfATilt) {
  // The estimate's world turns about z at 0.5 deg/s (a gyro bias's heading drift), and
  // separately every pose tilts 2 deg about a horizontal world axis (roll / pitch, no heading):
  // the signed heading error is minus the drift's angle, the tilt gives none.
  const synthetic::SmoothTrajectory traj(24);
  const io::Trajectory gt = synthetic::sample([&](double t) { return traj.pose(t); }, kT0, 10 * kMs, 2000);
  const double rate_deg = 0.5;
  io::Trajectory drift = gt, tilt = gt;
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const double psi = rate_deg * to_seconds(gt[i].t_ns - kT0) * kDegToRad;
    drift[i].T_w_b = SE3d(so3::exp_quat<double>(Vec3d(0, 0, psi)), Vec3d::Zero()) * gt[i].T_w_b;
    const Vec3d axis(std::cos(0.01 * i), std::sin(0.01 * i), 0.0);  // horizontal, turning
    tilt[i].T_w_b.set_quaternion(so3::exp_quat<double>(2.0 * kDegToRad * axis) * gt[i].T_w_b.quaternion());
  }
  const Alignment none{AlignmentMethod::kNone, SE3d(), 1.0};
  auto ate = compute_ate(associate_or_die(drift, gt), none);
  ASSERT_TRUE(ate.ok()) << ate.status();
  ASSERT_EQ(ate->heading_errors_deg.size(), gt.size());
  for (std::size_t i = 0; i < gt.size(); i += 97)
    EXPECT_NEAR(ate->heading_errors_deg[i], -rate_deg * to_seconds(gt[i].t_ns - kT0), 1e-9) << i;
  EXPECT_NEAR(ate->heading_deg.max, rate_deg * to_seconds(gt.back().t_ns - kT0), 1e-9);
  EXPECT_NEAR(ate->heading_deg.max, ate->rotation_deg.max, 1e-9);  // all of it is heading
  auto tilted = compute_ate(associate_or_die(tilt, gt), none);
  ASSERT_TRUE(tilted.ok()) << tilted.status();
  EXPECT_NEAR(tilted->rotation_deg.min, 2.0, 1e-9);
  EXPECT_LT(tilted->heading_deg.max, 1e-9);
}

TEST(EvalRpe, MatchesBruteForceAndIgnoresRigidAlignment) {
  const synthetic::SmoothTrajectory traj(23);
  const io::Trajectory gt = synthetic::sample([&](double t) { return traj.pose(t); }, kT0, 20 * kMs, 1500);
  std::mt19937 rng(24);
  std::normal_distribution<double> n(0.0, 0.01);
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) {
    p.T_w_b =
        p.T_w_b * SE3d(so3::exp_quat<double>(Vec3d(n(rng), n(rng), n(rng))), Vec3d(n(rng), n(rng), n(rng)));
  }
  const Association a = associate_or_die(est, gt);
  const Association moved = associate_or_die(synthetic::transform(synthetic::random_se3(rng, 10.0), est), gt);
  for (RpeUnit unit : {RpeUnit::kMetres, RpeUnit::kSeconds}) {
    auto rpe = compute_rpe(a, {1.5, unit});
    auto rpe_moved = compute_rpe(moved, {1.5, unit});
    ASSERT_TRUE(rpe.ok() && rpe_moved.ok());
    EXPECT_NEAR(rpe->translation_m.rmse, rpe_moved->translation_m.rmse, 1e-9);
    EXPECT_NEAR(rpe->rotation_deg.rmse, rpe_moved->rotation_deg.rmse, 1e-7);
    std::vector<double> key;
    if (unit == RpeUnit::kMetres) {
      key = ground_truth_path_length(a);
    } else {
      for (const Match& m : a.matches) key.push_back(to_seconds(m.t_ns - kT0));
    }
    std::vector<double> trans, rot;
    for (const auto& [i, j] : select_rpe_pairs(key, 1.5)) {
      const auto [t_err, r_err] = brute_force_rpe_error(a.matches[i], a.matches[j], 1.0);
      trans.push_back(t_err);
      rot.push_back(r_err);
    }
    EXPECT_EQ(rpe->num_pairs, trans.size());
    EXPECT_NEAR(rpe->translation_m.rmse, compute_stats(trans)->rmse, 1e-12);
    EXPECT_NEAR(rpe->rotation_deg.rmse, compute_stats(rot)->rmse, 1e-6);
  }
}

TEST(EvalRpe, PerTimeDeltaWithConstantDriftRate) {
  // 0.5 m/s forward, the estimate gains 3 mm/s upwards: 1 s pairs carry 3 mm of error.
  const auto line = [](double t) { return SE3d(Quatd::Identity(), Vec3d(0.5 * t, 0.0, 0.0)); };
  const io::Trajectory gt = synthetic::sample(line, kT0, 20 * kMs, 501);  // 10 s
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) p.T_w_b.translation().z() += 0.003 * to_seconds(p.t_ns - kT0);
  auto rpe = compute_rpe(associate_or_die(est, gt), {1.0, RpeUnit::kSeconds});
  ASSERT_TRUE(rpe.ok()) << rpe.status();
  EXPECT_EQ(rpe->num_pairs, 451u);
  EXPECT_NEAR(rpe->translation_m.rmse, 0.003, 1e-9);
  EXPECT_NEAR(rpe->mean_pair_delta, 1.0, 1e-9);
}

TEST(EvalRpe, ScaleCorrectsAScaledEstimate) {
  const synthetic::SmoothTrajectory traj(25);
  const io::Trajectory gt = synthetic::sample([&](double t) { return traj.pose(t); }, kT0, 20 * kMs, 500);
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) p.T_w_b.translation() *= 0.8;
  const Association a = associate_or_die(est, gt);
  auto unscaled = compute_rpe(a, {1.0, RpeUnit::kMetres});
  auto scaled = compute_rpe(a, {1.0, RpeUnit::kMetres}, 1.0 / 0.8);
  ASSERT_TRUE(unscaled.ok() && scaled.ok());
  EXPECT_GT(unscaled->translation_m.rmse, 0.1);
  EXPECT_LT(scaled->translation_m.rmse, 1e-9);
}

TEST(EvalRpe, ReportsBadOptionsAndShortTrajectories) {
  const auto line = [](double t) { return SE3d(Quatd::Identity(), Vec3d(t, 0.0, 0.0)); };
  const io::Trajectory gt = synthetic::sample(line, kT0, 100 * kMs, 11);  // 1 m, 1 s
  const Association a = associate_or_die(gt, gt);
  EXPECT_EQ(compute_rpe(a, {0.0, RpeUnit::kMetres}).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(compute_rpe(a, {-1.0, RpeUnit::kSeconds}).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(compute_rpe(a, {1.0, RpeUnit::kMetres}, 0.0).status().code(), absl::StatusCode::kInvalidArgument);
  auto too_short = compute_rpe(a, {1.5, RpeUnit::kMetres});
  EXPECT_EQ(too_short.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_NE(too_short.status().message().find("no pose pair"), std::string::npos) << too_short.status();
  auto just_enough = compute_rpe(a, {1.0, RpeUnit::kSeconds});
  ASSERT_TRUE(just_enough.ok()) << just_enough.status();
  EXPECT_EQ(just_enough->num_pairs, 1u);
}

}  // namespace
}  // namespace mrvs::eval
