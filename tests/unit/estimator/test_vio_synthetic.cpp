// The filter on generated IMU and exact feature projections plus pixel noise (no tracking
// errors): accuracy against ground truth with and without points in the state,
// initialisation, no drift while still, and determinism.
#include <gtest/gtest.h>

#include "mrvs/edge/global_alignment.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"
#include "vio_test_world.h"

namespace mrvs::edge {
namespace {

std::string num(double x) { return std::to_string(x); }

test::SyntheticOptions twenty_seconds() {
  test::SyntheticOptions so;
  so.duration_s = 20.0;
  return so;
}

TEST(VioSynthetic, TracksTheTrajectoryWithAndWithoutPoints) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(twenty_seconds());
  ASSERT_NE(seq, nullptr);
  EstimatorOptions o = test::euroc_estimator_options();
  const auto with_points = test::run_estimator(*seq, o);
  o.state.max_slam = 0;
  const auto msckf_only = test::run_estimator(*seq, o);
  // The static start (about 4 s) initialises within a second and a half of data.
  EXPECT_GT(with_points.size(), seq->frames.size() - 40);
  EXPECT_GT(msckf_only.size(), seq->frames.size() - 40);
  const double a = test::ate_rmse(*seq, with_points, true), b = test::ate_rmse(*seq, msckf_only, true);
  const double a_raw = test::ate_rmse(*seq, with_points, false),
               b_raw = test::ate_rmse(*seq, msckf_only, false);
  testing::Test::RecordProperty("ate_se3_points_m", num(a));
  testing::Test::RecordProperty("ate_se3_msckf_m", num(b));
  testing::Test::RecordProperty("ate_raw_points_m", num(a_raw));
  testing::Test::RecordProperty("ate_raw_msckf_m", num(b_raw));
  EXPECT_LT(a, 0.01);
  EXPECT_LT(b, 0.03);
  EXPECT_LT(a_raw, 0.05);  // aligned once at initialisation (2 cm noise), never again
  EXPECT_LT(b_raw, 0.06);
  EXPECT_LT(a, b);  // points in the state help when tracks are exact
}

TEST(VioSynthetic, SameInputGivesTheSameTrajectory) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(twenty_seconds());
  ASSERT_NE(seq, nullptr);
  const EstimatorOptions o = test::euroc_estimator_options();
  const auto a = test::run_estimator(*seq, o);
  const auto b = test::run_estimator(*seq, o);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].t_ns, b[i].t_ns);
    ASSERT_EQ(a[i].T_w_b.translation(), b[i].T_w_b.translation()) << "pose " << i;
    ASSERT_EQ(a[i].T_w_b.quaternion().coeffs(), b[i].T_w_b.quaternion().coeffs());
  }
}

TEST(VioSynthetic, StaticInitialisationRecoversGravityAndGyroBiasAndDoesNotDrift) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(twenty_seconds());
  ASSERT_NE(seq, nullptr);
  EstimatorOptions o = test::euroc_estimator_options();
  o.alignment.source = "gt";
  auto vio = VioEstimator::create(o, seq->world.calibration, seq->groundtruth);
  ASSERT_TRUE(vio.ok()) << vio.status();
  std::size_t next = 0;
  std::optional<SE3d> first;
  TimestampNs first_ns = 0;
  for (const FeatureFrame& f : seq->frames) {
    while (next < seq->imu.size()) {
      ASSERT_TRUE(vio->feed_imu(seq->imu[next]).ok());
      if (seq->imu[next++].t_ns >= f.t_ns) break;
    }
    auto r = vio->feed_frame(f);
    ASSERT_TRUE(r.ok()) << r.status();
    if (!r->T_w_b) continue;
    if (!first) {
      first = r->T_w_b, first_ns = f.t_ns;
      EXPECT_NE(vio->initialization_summary().find("static"), std::string::npos)
          << vio->initialization_summary();
      // Gyro bias and gravity (the body's up direction) against the truth at that time.
      const auto& truth = *std::find_if(seq->world.states.begin(), seq->world.states.end(),
                                        [&](const io::GroundTruthState& s) { return s.t_ns >= r->t_imu_ns; });
      // The "still" start of the spline fit to V1_01 still turns at 3-6 mrad/s.
      EXPECT_LT((vio->state()->imu.bg - truth.bias_gyro).norm(), 5e-3);
      const Vec3d up_est = vio->state()->imu.q_w_b.conjugate() * Vec3d::UnitZ();
      const Vec3d up_true = truth.T_w_b.quaternion().conjugate() * Vec3d::UnitZ();
      EXPECT_LT(std::acos(std::min(1.0, up_est.dot(up_true))) * 180.0 / M_PI, 0.5);
    }
    // Still for the first 4 s of V1_01: the position stays put.
    if (to_seconds(f.t_ns - first_ns) < 2.0) {
      EXPECT_LT((r->T_w_b->translation() - first->translation()).norm(), 0.01);
    }
  }
  ASSERT_TRUE(first.has_value()) << vio->waiting_reason();
}

TEST(VioSynthetic, OnlineCalibrationMovesTowardsTheTruth) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(twenty_seconds());
  ASSERT_NE(seq, nullptr);
  const config::StereoRigCalibration& truth = seq->world.calibration;
  config::StereoRigCalibration wrong = truth;
  auto& cam0 = wrong.cameras[0];
  cam0.T_b_c = SE3d(cam0.T_b_c.quaternion() * so3::exp_quat<double>(Vec3d(0.5, -0.3, 0.4) * M_PI / 180.0),
                    cam0.T_b_c.translation() + Vec3d(0.01, -0.005, 0.005));
  camera::Params p = cam0.model->params();
  p[0] += 3.0, p[2] -= 2.0;  // fx, cx
  cam0.model = std::shared_ptr<const camera::CameraModel>(
      std::move(*camera::make_camera(cam0.model->model(), cam0.model->width(), cam0.model->height(), p)));
  for (auto& c : wrong.cameras) c.time_offset_ns = 4'000'000;  // the truth is 0
  EstimatorOptions o = test::euroc_estimator_options();
  o.state.calib_extrinsics = o.state.calib_intrinsics = o.state.calib_time_offset = true;
  auto vio = VioEstimator::create(o, wrong, seq->groundtruth);
  ASSERT_TRUE(vio.ok()) << vio.status();
  std::size_t next = 0;
  for (const FeatureFrame& f : seq->frames) {
    while (next < seq->imu.size()) {
      ASSERT_TRUE(vio->feed_imu(seq->imu[next]).ok());
      if (seq->imu[next++].t_ns >= f.t_ns + 4'000'000) break;
    }
    ASSERT_TRUE(vio->feed_frame(f).ok());
  }
  ASSERT_TRUE(vio->initialized());
  const State& s = *vio->state();
  const auto rot_err = [&](const SE3d& a) {
    return so3::log<double>(a.quaternion().conjugate() * truth.cameras[0].T_b_c.quaternion()).norm() * 180.0 /
           M_PI;
  };
  const auto pos_err = [&](const SE3d& a) {
    return (a.translation() - truth.cameras[0].T_b_c.translation()).norm();
  };
  testing::Test::RecordProperty("extrinsic_rot_err_deg", num(rot_err(s.cams[0].T_b_c)));
  testing::Test::RecordProperty("extrinsic_pos_err_m", num(pos_err(s.cams[0].T_b_c)));
  testing::Test::RecordProperty("fx_err_px", num(s.cams[0].model->fx() - truth.cameras[0].model->fx()));
  testing::Test::RecordProperty("time_offset_s", num(s.time_offset_s));
  EXPECT_LT(rot_err(s.cams[0].T_b_c), 0.5 * rot_err(cam0.T_b_c));
  EXPECT_LT(pos_err(s.cams[0].T_b_c), 0.8 * pos_err(cam0.T_b_c));  // weakly observable in 20 s
  EXPECT_LT(std::abs(s.cams[0].model->fx() - truth.cameras[0].model->fx()), 1.5);
  EXPECT_LT(std::abs(s.cams[0].model->cx() - truth.cameras[0].model->cx()), 1.0);
  EXPECT_LT(std::abs(s.time_offset_s), 0.001);
}

/// Largest |yaw error| (rotation about gravity, deg) of `estimate` against the ground truth.
double worst_yaw_error_deg(const test::SyntheticSequence& seq, const io::Trajectory& estimate) {
  double worst = 0.0;
  for (const io::StampedPose& p : estimate) {
    const auto T = interpolate_trajectory(seq.groundtruth, p.t_ns);
    if (!T.ok()) continue;
    const Vec3d e_w = so3::log<double>(p.T_w_b.quaternion() * T->quaternion().conjugate());
    worst = std::max(worst, std::abs(e_w.z()));
  }
  return worst * 180.0 / M_PI;
}

// Global yaw is unobservable: points in the state must not turn it. A point's first estimate
// has to be where its initialisation was linearised; with the position the initialisation
// then corrected, these runs turned 1.0-2.3 deg within 40 s (now 0.07-0.16 deg).
TEST(VioSynthetic, PointsInTheStateDoNotTurnTheUnobservableYaw) {
  for (int seed : {3, 5}) {
    test::SyntheticOptions so;
    so.duration_s = 40.0;
    so.seed = seed;
    so.drift_px = 0.1;  // KLT-like
    const test::SyntheticSequence* seq = test::synthetic_sequence(so);
    ASSERT_NE(seq, nullptr);
    const EstimatorOptions o = test::euroc_estimator_options();
    ASSERT_GT(o.state.max_slam, 0);
    const io::Trajectory traj = test::run_estimator(*seq, o);
    ASSERT_GT(traj.size(), seq->frames.size() / 2);
    const double yaw = worst_yaw_error_deg(*seq, traj);
    testing::Test::RecordProperty("worst_yaw_deg_seed" + std::to_string(seed), num(yaw));
    EXPECT_LT(yaw, 0.4) << "seed " << seed;
  }
}

TEST(VioSynthetic, KeyframeMarginalisationRuns) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(twenty_seconds());
  ASSERT_NE(seq, nullptr);
  EstimatorOptions o = test::euroc_estimator_options();
  o.keyframe.use_keyframes = true;
  const auto traj = test::run_estimator(*seq, o);
  const double ate = test::ate_rmse(*seq, traj, true);
  testing::Test::RecordProperty("ate_se3_keyframes_m", num(ate));
  EXPECT_GT(traj.size(), seq->frames.size() - 40);
  EXPECT_LT(ate, 0.10);  // the reference code's policy: it works, but costs accuracy here
}

TEST(VioSynthetic, DynamicInitialisationStartsAFilterInFlight) {
  test::SyntheticOptions so;
  so.start_s = 20.0;  // V1_01 is moving
  so.duration_s = 12.0;
  const test::SyntheticSequence* seq = test::synthetic_sequence(so);
  ASSERT_NE(seq, nullptr);
  const EstimatorOptions o = test::euroc_estimator_options();
  const auto traj = test::run_estimator(*seq, o);
  ASSERT_GT(traj.size(), seq->frames.size() / 2);  // initialised within a few seconds
  const double ate = test::ate_rmse(*seq, traj, true);
  testing::Test::RecordProperty("ate_se3_dynamic_m", num(ate));
  EXPECT_LT(ate, 0.03);
}

}  // namespace
}  // namespace mrvs::edge
