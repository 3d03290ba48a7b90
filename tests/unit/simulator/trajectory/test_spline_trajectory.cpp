// SplineTrajectory: exactness on analytic motion, derivatives vs numeric differences, fit
// quality on the real EuRoC ground truth, GT self-consistency (simulator.md 6.3), start
// handling (static prefix, start at motion, windows) and input errors.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

#include <gtest/gtest.h>

#include "mrvs/sim/spline_trajectory.h"
#include "mrvs/sim/test/strapdown.h"

namespace mrvs::sim {
namespace {

using test::kRadToDeg;
using test::load_euroc_gt;

constexpr DurationNs kKnot = 50'000'000;
constexpr DurationNs kImuDt = 5'000'000;

class SplineOnEuroc : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    v101_ = new io::Trajectory(load_euroc_gt("V1_01_easy.txt"));
    v201_ = new io::Trajectory(load_euroc_gt("V2_01_easy.txt"));
  }
  static void TearDownTestSuite() {
    delete v101_;
    delete v201_;
  }
  static io::Trajectory* v101_;
  static io::Trajectory* v201_;
};
io::Trajectory* SplineOnEuroc::v101_ = nullptr;
io::Trajectory* SplineOnEuroc::v201_ = nullptr;

TEST(SplineTrajectory, ExactForConstantVelocityAndBodyRate) {
  const Vec3d p0(1.0, -2.0, 0.5), vel(0.3, -0.2, 0.1), w_b(0.4, -0.7, 1.1);
  const Quatd q0 = so3::exp_quat<double>(Vec3d(0.3, 0.2, -1.0));
  const TimestampNs t_first = 1'403'715'274'302'140'000;
  std::vector<SE3d> cps;
  for (int k = 0; k < 12; ++k) {
    const double t = 0.05 * k;
    cps.emplace_back(q0 * so3::exp_quat<double>(w_b * t), p0 + vel * t);
  }
  auto spline = SplineTrajectory::from_control_points(t_first, kKnot, cps);
  ASSERT_TRUE(spline.ok()) << spline.status();
  EXPECT_EQ(spline->t_begin_ns(), t_first + 2 * kKnot);
  for (TimestampNs t = spline->support_begin_ns(); t <= spline->support_end_ns(); t += 7'777'777) {
    auto k = spline->evaluate(t);
    ASSERT_TRUE(k.ok()) << k.status();
    const double s = to_seconds(t - t_first);
    EXPECT_LT((k->T_w_b.translation() - (p0 + vel * s)).norm(), 1e-12);
    EXPECT_LT(quat::angular_distance(k->T_w_b.quaternion(), q0 * so3::exp_quat<double>(w_b * s)), 1e-12);
    EXPECT_LT((k->v_w - vel).norm(), 1e-12);
    EXPECT_LT(k->a_w.norm(), 1e-10);
    EXPECT_LT((k->omega_b - w_b).norm(), 1e-12);
  }
}

TEST_F(SplineOnEuroc, AnalyticDerivativesMatchNumericDifferences) {
  auto spline = SplineTrajectory::fit(*v101_);
  ASSERT_TRUE(spline.ok()) << spline.status();
  const DurationNs h_ns = 10'000;  // 10 us
  const double h = to_seconds(h_ns);
  double max_dv = 0.0, max_da = 0.0, max_dw = 0.0;
  // 200 instants spread over the sequence, off the knots.
  const DurationNs step = (spline->t_end_ns() - spline->t_begin_ns() - 2 * h_ns) / 200 + 1'234'567;
  for (TimestampNs t = spline->t_begin_ns() + h_ns; t + h_ns <= spline->t_end_ns(); t += step) {
    const Kinematics k = *spline->evaluate(t);
    const Kinematics km = *spline->evaluate(t - h_ns);
    const Kinematics kp = *spline->evaluate(t + h_ns);
    const Vec3d v_num = (kp.T_w_b.translation() - km.T_w_b.translation()) / (2.0 * h);
    const Vec3d a_num = (kp.v_w - km.v_w) / (2.0 * h);
    const Vec3d w_num =
        so3::log<double>(km.T_w_b.quaternion().conjugate() * kp.T_w_b.quaternion()) / (2.0 * h);
    max_dv = std::max(max_dv, (k.v_w - v_num).norm());
    max_da = std::max(max_da, (k.a_w - a_num).norm());
    max_dw = std::max(max_dw, (k.omega_b - w_num).norm());
  }
  std::printf("[derivatives] max |v - dp/dt| %.3g m/s, |a - dv/dt| %.3g m/s^2, |w - dR| %.3g rad/s\n", max_dv,
              max_da, max_dw);
  EXPECT_LT(max_dv, 1e-6);
  EXPECT_LT(max_da, 1e-4);
  EXPECT_LT(max_dw, 1e-6);
}

/// Position and rotation RMS of the spline against the input samples inside its window.
void expect_fit_quality(const io::Trajectory& gt, const char* name, double max_pos_rms_m,
                        double max_rot_rms_deg) {
  auto spline = SplineTrajectory::fit(gt);
  ASSERT_TRUE(spline.ok()) << spline.status();
  double sum_p2 = 0.0, sum_r2 = 0.0, max_p = 0.0, max_r = 0.0;
  int n = 0;
  for (const io::StampedPose& s : gt) {
    if (s.t_ns < spline->t_begin_ns() || s.t_ns > spline->t_end_ns()) continue;
    const SE3d T = spline->evaluate(s.t_ns)->T_w_b;
    const double dp = (T.translation() - s.T_w_b.translation()).norm();
    const double dr = quat::angular_distance(T.quaternion(), s.T_w_b.quaternion()) * kRadToDeg;
    sum_p2 += dp * dp;
    sum_r2 += dr * dr;
    max_p = std::max(max_p, dp);
    max_r = std::max(max_r, dr);
    ++n;
  }
  const double rms_p = std::sqrt(sum_p2 / n), rms_r = std::sqrt(sum_r2 / n);
  std::printf("[fit %s] %d poses: position RMS %.3f mm (max %.3f), rotation RMS %.4f deg (max %.4f)\n", name,
              n, rms_p * 1e3, max_p * 1e3, rms_r, max_r);
  EXPECT_GT(n, 20000);
  EXPECT_LT(rms_p, max_pos_rms_m);
  EXPECT_LT(rms_r, max_rot_rms_deg);
}

TEST_F(SplineOnEuroc, FitsRealGroundTruth) {
  expect_fit_quality(*v101_, "V1_01", 2e-3, 0.2);
  expect_fit_quality(*v201_, "V2_01", 2e-3, 0.2);
}

TEST_F(SplineOnEuroc, GroundTruthSelfConsistency) {
  // simulator.md 6.3 on the 200 Hz GT grid: v vs central differences, log(R_k^T R_k+1)/dt
  // vs the mean of the (noiseless) gyro at k and k+1, |q| = 1.
  for (const io::Trajectory* gt : {v101_, v201_}) {
    auto spline = SplineTrajectory::fit(*gt);
    ASSERT_TRUE(spline.ok()) << spline.status();
    std::vector<Kinematics> ks;
    for (TimestampNs t = spline->t_begin_ns(); t <= spline->t_end_ns(); t += kImuDt)
      ks.push_back(*spline->evaluate(t));
    const double dt = to_seconds(kImuDt);
    double max_dv = 0.0, max_dw = 0.0, max_qn = 0.0;
    for (std::size_t k = 1; k + 1 < ks.size(); ++k) {
      const Vec3d v_cd = (ks[k + 1].T_w_b.translation() - ks[k - 1].T_w_b.translation()) / (2.0 * dt);
      max_dv = std::max(max_dv, (ks[k].v_w - v_cd).norm());
      const Vec3d w_inc =
          so3::log<double>(ks[k].T_w_b.quaternion().conjugate() * ks[k + 1].T_w_b.quaternion()) / dt;
      max_dw = std::max(max_dw, (w_inc - 0.5 * (ks[k].omega_b + ks[k + 1].omega_b)).norm());
      max_qn = std::max(max_qn, std::abs(ks[k].T_w_b.quaternion().norm() - 1.0));
    }
    std::printf(
        "[gt consistency] %zu states: max |v - central diff| %.3f mm/s, max |dR/dt - mean gyro| %.3g rad/s\n",
        ks.size(), max_dv * 1e3, max_dw);
    EXPECT_LT(max_dv, 5e-3);
    EXPECT_LT(max_dw, 5e-3);
    EXPECT_LT(max_qn, 1e-8);
  }
}

TEST_F(SplineOnEuroc, ValidRangeAndEvaluationOutsideIt) {
  auto spline = SplineTrajectory::fit(*v101_);
  ASSERT_TRUE(spline.ok()) << spline.status();
  const TimestampNs t_in = v101_->front().t_ns;
  EXPECT_EQ(spline->knot_spacing_ns(), kKnot);  // max(5 ms mean, 50 ms)
  EXPECT_EQ(spline->first_control_point_ns(), ceil_to_microsecond(t_in));
  EXPECT_EQ(spline->t_begin_ns(), spline->first_control_point_ns() + 2 * kKnot);
  EXPECT_EQ(spline->t_begin_ns() % 1000, 0);
  EXPECT_LE(spline->t_end_ns(), spline->first_control_point_ns() +
                                    static_cast<std::int64_t>(spline->control_points().size() - 2) * kKnot);
  EXPECT_LE(spline->t_end_ns() + kKnot, v101_->back().t_ns);
  EXPECT_TRUE(spline->evaluate(spline->support_begin_ns()).ok());
  EXPECT_TRUE(spline->evaluate(spline->support_end_ns()).ok());
  EXPECT_TRUE(spline->evaluate(spline->t_begin_ns() - kImuDt).ok());  // IMU averaging margin
  const auto before = spline->evaluate(spline->support_begin_ns() - 1);
  EXPECT_EQ(before.status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_EQ(spline->evaluate(spline->support_end_ns() + 1).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_NE(std::string(before.status().message()).find("outside the evaluable range"), std::string::npos);

  EXPECT_EQ(ceil_to_microsecond(1'403'715'274'302'140'001), 1'403'715'274'302'141'000);
  EXPECT_EQ(ceil_to_microsecond(-1'500), -1'000);
  EXPECT_EQ(ceil_to_microsecond(7'000), 7'000);
}

TEST(SplineTrajectory, KnotSpacingChoice) {
  io::Trajectory slow;  // 10 Hz input: knot = mean dt = 0.1 s
  for (int k = 0; k < 30; ++k)
    slow.push_back({1'000'000'123 + k * 100'000'000LL, SE3d(Quatd::Identity(), Vec3d(0.1 * k, 0, 0))});
  auto a = SplineTrajectory::fit(slow);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->knot_spacing_ns(), 100'000'000);
  EXPECT_EQ(a->first_control_point_ns(), 1'000'001'000);
  TrajectoryOptions options;
  options.knot_spacing_s = 0.25;
  auto b = SplineTrajectory::fit(slow, options);
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(b->knot_spacing_ns(), 250'000'000);
  EXPECT_NEAR(b->evaluate(b->t_begin_ns() + 123'456'000)->v_w.x(), 1.0, 1e-9);  // linear motion is exact
}

TEST_F(SplineOnEuroc, StaticPrefixIsExactlyAtRest) {
  TrajectoryOptions options;
  options.static_prefix_s = 2.0;
  auto spline = SplineTrajectory::fit(*v101_, options);
  auto plain = SplineTrajectory::fit(*v101_);
  ASSERT_TRUE(spline.ok() && plain.ok());
  const SE3d first = spline->control_points().front();
  const TimestampNs prefix_end = spline->t_begin_ns() + 2'000'000'000;
  int n = 0;
  for (TimestampNs t = spline->t_begin_ns(); t <= prefix_end; t += 1'000'000, ++n) {
    const Kinematics k = *spline->evaluate(t);
    ASSERT_EQ(k.v_w, Vec3d::Zero()) << "at " << t;
    ASSERT_EQ(k.a_w, Vec3d::Zero()) << "at " << t;
    ASSERT_EQ(k.omega_b, Vec3d::Zero()) << "at " << t;
    ASSERT_EQ(k.T_w_b.translation(), first.translation());
  }
  EXPECT_EQ(n, 2001);
  // Just after the prefix the blend starts; the original data part is unchanged (local support).
  EXPECT_GT(spline->evaluate(prefix_end + 4 * kKnot)->v_w.norm(), 0.0);
  for (TimestampNs t = plain->t_begin_ns() + kKnot; t < plain->t_begin_ns() + 30 * kKnot; t += 3'000'000) {
    const Kinematics a = *spline->evaluate(t), b = *plain->evaluate(t);
    EXPECT_LT((a.T_w_b.translation() - b.T_w_b.translation()).norm(), 1e-12);
    EXPECT_LT((a.v_w - b.v_w).norm(), 1e-12);
    EXPECT_LT((a.omega_b - b.omega_b).norm(), 1e-12);
  }
}

TEST_F(SplineOnEuroc, StartAtMotionSkipsTheStaticStart) {
  TrajectoryOptions options;
  options.start_at_motion_m = 0.5;
  auto moving = SplineTrajectory::fit(*v101_, options);
  auto plain = SplineTrajectory::fit(*v101_);
  ASSERT_TRUE(moving.ok() && plain.ok()) << moving.status();
  // V1_01 rests for about 4.2 s; 0.5 m of path takes longer.
  EXPECT_GT(moving->t_begin_ns() - plain->t_begin_ns(), 4'000'000'000);
  double length = 0.0;
  Vec3d prev = plain->evaluate(plain->t_begin_ns())->T_w_b.translation();
  for (TimestampNs t = plain->t_begin_ns() + 5'000'000; t <= moving->t_begin_ns(); t += 5'000'000) {
    const Vec3d p = plain->evaluate(t)->T_w_b.translation();
    length += (p - prev).norm();
    prev = p;
  }
  std::printf("[start at motion] start %.3f s later, path length %.4f m\n",
              to_seconds(moving->t_begin_ns() - plain->t_begin_ns()), length);
  EXPECT_GT(length, 0.5);
  EXPECT_LT(length, 0.6);
  EXPECT_GT(moving->evaluate(moving->t_begin_ns())->v_w.norm(), 0.1);

  options.start_at_motion_m = 1e6;
  const auto too_far = SplineTrajectory::fit(*v101_, options);
  EXPECT_FALSE(too_far.ok());
  EXPECT_NE(std::string(too_far.status().message()).find("path length"), std::string::npos);
}

TEST_F(SplineOnEuroc, Windows) {
  auto plain = SplineTrajectory::fit(*v101_);
  ASSERT_TRUE(plain.ok());
  TrajectoryOptions options;
  options.window_start_s = 10.0000005;
  options.window_duration_s = 20.0;
  auto w = SplineTrajectory::fit(*v101_, options);
  ASSERT_TRUE(w.ok()) << w.status();
  EXPECT_EQ(w->t_begin_ns(), plain->t_begin_ns() + 10'000'001'000);  // rounded up to 1 us
  EXPECT_EQ(w->t_end_ns(), w->t_begin_ns() + 20'000'000'000);

  options = {};
  options.window_start_ns = plain->t_begin_ns() + 30'000'000'017;
  options.window_duration_s = 5.0;
  auto abs = SplineTrajectory::fit(*v101_, options);
  ASSERT_TRUE(abs.ok()) << abs.status();
  EXPECT_EQ(abs->t_begin_ns(), plain->t_begin_ns() + 30'000'001'000);

  options = {};
  options.window_start_s = 100.0;
  options.window_duration_s = 100.0;  // V1_01 is 143 s long
  const auto too_long = SplineTrajectory::fit(*v101_, options);
  ASSERT_EQ(too_long.status().code(), absl::StatusCode::kOutOfRange);
  const std::string msg(too_long.status().message());
  EXPECT_NE(msg.find("valid range"), std::string::npos) << msg;
  EXPECT_NE(msg.find(std::to_string(plain->t_begin_ns())), std::string::npos) << msg;
  EXPECT_NE(msg.find(std::to_string(plain->t_end_ns())), std::string::npos) << msg;

  options = {};
  options.window_start_ns = plain->t_begin_ns() - 1'000'000;
  EXPECT_EQ(SplineTrajectory::fit(*v101_, options).status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_FALSE(w->set_window(w->t_begin_ns(), plain->t_end_ns() + 1).ok());
}

TEST(SplineTrajectory, RejectsBadInput) {
  auto message = [](const io::Trajectory& in) {
    const auto r = SplineTrajectory::fit(in);
    EXPECT_FALSE(r.ok());
    return std::string(r.status().message());
  };
  io::Trajectory line;
  for (int k = 0; k < 100; ++k)
    line.push_back({k * 5'000'000LL, SE3d(Quatd::Identity(), Vec3d(0.01 * k, 0, 0))});
  ASSERT_TRUE(SplineTrajectory::fit(line).ok());

  EXPECT_NE(message({line[0]}).find("at least 2 poses"), std::string::npos);
  io::Trajectory bad = line;
  bad[50].t_ns = bad[49].t_ns;
  EXPECT_NE(message(bad).find("strictly increase"), std::string::npos);
  bad = line;
  bad[7].T_w_b.translation().y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(message(bad).find("non-finite"), std::string::npos);
  bad = line;
  bad[9].T_w_b = SE3d(Quatd(0, 0, 0, 0), Vec3d::Zero());
  EXPECT_NE(message(bad).find("degenerate rotation"), std::string::npos);
  bad = io::Trajectory(line.begin(), line.begin() + 30);  // 0.145 s < 4 knots
  EXPECT_NE(message(bad).find("too short"), std::string::npos);
  bad = line;
  for (std::size_t k = 60; k < bad.size(); ++k) bad[k].t_ns += 3'000'000'000;
  EXPECT_NE(message(bad).find("gap"), std::string::npos);
  EXPECT_FALSE(SplineTrajectory::from_control_points(0, kKnot, std::vector<SE3d>(4)).ok());
  EXPECT_FALSE(SplineTrajectory::from_control_points(0, 0, std::vector<SE3d>(8)).ok());
}

TEST_F(SplineOnEuroc, FitAndEvaluateThirtySecondsIsFast) {
  const io::Trajectory clip(v101_->begin(), v101_->begin() + 6400);  // 32 s at 200 Hz
  const auto start = std::chrono::steady_clock::now();
  auto spline = SplineTrajectory::fit(clip);
  ASSERT_TRUE(spline.ok()) << spline.status();
  const auto fitted = std::chrono::steady_clock::now();
  int n = 0;
  Vec3d sum = Vec3d::Zero();
  for (TimestampNs t = spline->t_begin_ns(); t <= spline->t_begin_ns() + 30'000'000'000; t += kImuDt, ++n) {
    sum += spline->evaluate(t)->v_w;
  }
  const auto done = std::chrono::steady_clock::now();
  const double fit_ms = std::chrono::duration<double, std::milli>(fitted - start).count();
  const double eval_ms = std::chrono::duration<double, std::milli>(done - fitted).count();
  std::printf("[timing] fit 32 s of GT %.2f ms, evaluate %d stamps (30 s at 200 Hz) %.2f ms\n", fit_ms, n,
              eval_ms);
  EXPECT_EQ(n, 6001);
  EXPECT_TRUE(sum.allFinite());
  EXPECT_LT(fit_ms + eval_ms, 1000.0);
}

}  // namespace
}  // namespace mrvs::sim
