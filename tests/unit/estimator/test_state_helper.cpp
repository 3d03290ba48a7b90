// EKF operations against brute force: an update on a few variables equals the textbook
// update over the full state, delayed initialisation equals a joint update from a flat
// prior, compression keeps the information, cloning and marginalisation move the right
// covariance blocks.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/state_helper.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

config::StereoRigCalibration rig() {
  camera::Params p;
  p << 458.0, 457.0, 367.0, 248.0, 0.0, 0.0, 0.0, 0.0;
  config::StereoRigCalibration r;
  for (int c = 0; c < 2; ++c) {
    r.cameras[c].model = std::shared_ptr<const camera::CameraModel>(
        std::move(*camera::make_camera(camera::DistortionModel::kRadTan, 752, 480, p)));
    r.cameras[c].T_b_c = SE3d(Quatd::Identity(), Vec3d(0.11 * c, 0.0, 0.0));
  }
  return r;
}

Eigen::MatrixXd random_spd(int n, std::mt19937* rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd A(n, n);
  for (int i = 0; i < n * n; ++i) A(i) = g(*rng);
  return A * A.transpose() / n + 0.1 * Eigen::MatrixXd::Identity(n, n);
}

/// A state with IMU, 3 clones and 2 points, and a random covariance.
State make_state(std::mt19937* rng) {
  State s(StateOptions{}, rig());
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(augment_clone(s, 1000 + k, Vec3d::Zero()).ok());
  }
  for (FeatureId id : {7u, 9u}) {
    PointState p;
    p.slot = s.append(3);
    p.p_w = Vec3d(1.0, 2.0, 3.0 + id);
    s.points.emplace(id, p);
  }
  s.P = random_spd(s.dim(), rng);
  return s;
}

/// The full-state H of a measurement.
Eigen::MatrixXd full_H(const State& s, const Measurement& m) {
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m.rows(), s.dim());
  int c = 0;
  for (const Slot& v : m.vars) H.middleCols(v.offset, v.size) = m.H.middleCols(c, v.size), c += v.size;
  return H;
}

/// The error between two states of the same layout.
Eigen::VectorXd difference(const State& a, const State& b) {
  Eigen::VectorXd d(a.dim());
  d.head<15>() = a.imu.boxminus(b.imu);
  for (const auto& [t, c] : a.clones) {
    const SE3d& o = b.clones.at(t).T_w_b;
    d.segment<3>(c.slot.offset) = so3::log<double>(o.quaternion().conjugate() * c.T_w_b.quaternion());
    d.segment<3>(c.slot.offset + 3) = c.T_w_b.translation() - o.translation();
  }
  for (const auto& [id, p] : a.points) d.segment<3>(p.slot.offset) = p.p_w - b.points.at(id).p_w;
  return d;
}

TEST(StateHelper, UpdateOnSomeVariablesEqualsTheFullUpdate) {
  std::mt19937 rng(1);
  std::normal_distribution<double> g(0.0, 1.0);
  State s = make_state(&rng);
  Measurement m;
  m.vars = {s.clones.at(1001).slot, s.points.at(9).slot, s.imu_slot};
  m.H = Eigen::MatrixXd(7, 6 + 3 + 15);
  for (int i = 0; i < m.H.size(); ++i) m.H(i) = g(rng);
  m.r = Eigen::VectorXd(7);
  for (int i = 0; i < 7; ++i) m.r[i] = 0.1 * g(rng);
  m.sigma = 0.5;
  const Eigen::MatrixXd H = full_H(s, m);
  const Eigen::MatrixXd S = H * s.P * H.transpose() + 0.25 * Eigen::MatrixXd::Identity(7, 7);
  const Eigen::MatrixXd K = s.P * H.transpose() * S.inverse();
  const Eigen::MatrixXd P_expected = (Eigen::MatrixXd::Identity(s.dim(), s.dim()) - K * H) * s.P;
  const Eigen::VectorXd dx_expected = K * m.r;
  EXPECT_NEAR(mahalanobis(s, m), m.r.dot(S.inverse() * m.r), 1e-9);
  const State before = s;
  ASSERT_TRUE(ekf_update(s, m).ok());
  EXPECT_TRUE(test::matrices_near(s.P, P_expected, 1e-9));
  EXPECT_TRUE(test::matrices_near(difference(s, before), dx_expected, 1e-9));
}

TEST(StateHelper, DelayedInitialisationEqualsAJointUpdateFromAFlatPrior) {
  std::mt19937 rng(2);
  std::normal_distribution<double> g(0.0, 1.0);
  State s = make_state(&rng);
  // 8 rows seeing two clones and a new 3-value variable.
  Measurement m;
  m.vars = {s.clones.at(1000).slot, s.clones.at(1002).slot};
  m.H = Eigen::MatrixXd(8, 12);
  Eigen::MatrixXd H_f(8, 3);
  for (int i = 0; i < m.H.size(); ++i) m.H(i) = g(rng);
  for (int i = 0; i < H_f.size(); ++i) H_f(i) = g(rng);
  m.r = Eigen::VectorXd(8);
  for (int i = 0; i < 8; ++i) m.r[i] = g(rng);
  m.sigma = 0.3;
  // Brute force in information form: no prior on the new variable.
  const int n = s.dim();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(8, n + 3);
  H.leftCols(n) = full_H(s, m);
  H.rightCols(3) = H_f;
  Eigen::MatrixXd info = H.transpose() * H / 0.09;
  info.topLeftCorner(n, n) += s.P.inverse();
  const Eigen::MatrixXd P_expected = info.inverse();
  const Eigen::VectorXd dx_expected = P_expected * H.transpose() * m.r / 0.09;

  auto split = split_by_new_variable(m, H_f);
  ASSERT_TRUE(split.ok()) << split.status();
  const State before = s;
  const auto [slot, df] = add_variable(s, split->first, split->R_f);
  PointState p;
  p.slot = slot;
  s.points.emplace(42, p);
  ASSERT_TRUE(ekf_update(s, split->rest).ok());
  // Mean: the state moved like the joint update, the new variable by df plus the update.
  State moved = before;
  moved.points.emplace(42, p);
  const Eigen::VectorXd d = difference(s, moved);  // rows of the old variables
  EXPECT_TRUE(test::matrices_near(d.head(before.dim()), dx_expected.head(before.dim()), 1e-6));
  EXPECT_TRUE(test::matrices_near(Eigen::VectorXd(s.points.at(42).p_w + df), dx_expected.tail(3), 1e-5));
  EXPECT_TRUE(test::matrices_near(s.P, P_expected, 1e-5));
}

TEST(StateHelper, CompressionKeepsTheInformation) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  Measurement m;
  m.vars = {Slot{0, 6}};
  m.H = Eigen::MatrixXd(20, 6);
  m.r = Eigen::VectorXd(20);
  for (int i = 0; i < m.H.size(); ++i) m.H(i) = g(rng);
  for (int i = 0; i < 20; ++i) m.r[i] = g(rng);
  const Eigen::MatrixXd info = m.H.transpose() * m.H;
  const Eigen::VectorXd grad = m.H.transpose() * m.r;
  const double rest = m.r.squaredNorm() - grad.dot(info.ldlt().solve(grad));
  compress(&m);
  EXPECT_EQ(m.rows(), 6);
  EXPECT_TRUE(test::matrices_near(Eigen::MatrixXd(m.H.transpose() * m.H), info, 1e-9));
  EXPECT_TRUE(test::matrices_near(Eigen::VectorXd(m.H.transpose() * m.r), grad, 1e-9));
  EXPECT_GT(rest, 0.0);
}

TEST(StateHelper, CloningCopiesTheImuPoseAndMarginalisingRemovesOnlyItsBlock) {
  std::mt19937 rng(4);
  State s = make_state(&rng);
  const Eigen::MatrixXd P0 = s.P;
  s.imu.p_w_b = Vec3d(1, 2, 3);
  ASSERT_TRUE(augment_clone(s, 2000, Vec3d(0.1, 0.2, 0.3)).ok());
  const Slot c = s.clones.at(2000).slot;
  EXPECT_EQ(c.offset, P0.rows());
  EXPECT_TRUE(test::matrices_near(s.P.block(c.offset, c.offset, 6, 6), P0.topLeftCorner(6, 6), 1e-12));
  EXPECT_TRUE(test::matrices_near(s.P.block(c.offset, 0, 6, P0.rows()), P0.topRows(6), 1e-12));
  EXPECT_EQ(s.clones.at(2000).T_w_b.translation(), Vec3d(1, 2, 3));
  EXPECT_FALSE(augment_clone(s, 2000, Vec3d::Zero()).ok());  // twice the same time
  // Marginalise the middle clone: everything else keeps its covariance, later slots move up.
  const Slot mid = s.clones.at(1001).slot;
  const Slot point9 = s.points.at(9).slot;
  const double p9 = s.P(point9.offset, point9.offset);
  marginalize_clone(s, 1001);
  EXPECT_EQ(s.clones.count(1001), 0u);
  EXPECT_EQ(s.points.at(9).slot.offset, point9.offset - 6);
  EXPECT_EQ(s.P(s.points.at(9).slot.offset, s.points.at(9).slot.offset), p9);
  EXPECT_EQ(s.dim(), P0.rows());
  (void)mid;
  int total = 0;
  for (const Slot& slot : s.slots()) total += slot.size;
  EXPECT_EQ(total, s.dim());
}

TEST(StateHelper, Chi2QuantilesAreTheTabulatedValues) {
  const Chi2Table t(100);
  EXPECT_NEAR(t.q95(1), 3.841, 1e-3);
  EXPECT_NEAR(t.q95(10), 18.307, 1e-3);
  EXPECT_NEAR(t.q95(100), 124.342, 1e-3);
  EXPECT_NEAR(t.q95(200), 233.994, 1e-3);  // beyond the table
}

TEST(StateHelper, TimeOffsetEntersTheCloneCovariance) {
  StateOptions o;
  o.calib_time_offset = true;
  State s(o, rig());
  s.imu.v_w_b = Vec3d(1.0, 0.0, 0.0);
  const double var_td = s.P(s.time_offset_slot.offset, s.time_offset_slot.offset);
  ASSERT_TRUE(augment_clone(s, 5, Vec3d(0.0, 0.0, 2.0)).ok());
  const Slot c = s.clones.at(5).slot;
  EXPECT_NEAR(s.P(c.offset + 2, c.offset + 2), 4.0 * var_td, 1e-12);  // yaw rate 2 rad/s
  EXPECT_NEAR(s.P(c.offset + 3, c.offset + 3), var_td, 1e-12);        // 1 m/s along x
  EXPECT_NEAR(s.P(c.offset + 3, s.time_offset_slot.offset), var_td, 1e-12);
}

}  // namespace
}  // namespace mrvs::edge
