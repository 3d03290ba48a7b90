// The one-time alignment to the global pose source: the frame turns about gravity only, and
// the covariance takes the source's accuracy for the position and the heading while roll,
// pitch, velocity and biases keep what the initialiser knew.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/global_alignment.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

constexpr double kDeg = M_PI / 180.0;

Quatd rpy(double roll, double pitch, double yaw) {
  return Quatd(Eigen::AngleAxisd(yaw * kDeg, Vec3d::UnitZ()) *
               Eigen::AngleAxisd(pitch * kDeg, Vec3d::UnitY()) *
               Eigen::AngleAxisd(roll * kDeg, Vec3d::UnitX()));
}

/// An initialised state (no clone yet): tilted IMU, velocity, and a random full covariance.
State initialised_state() {
  State s(StateOptions{}, config::StereoRigCalibration{});
  s.imu.q_w_b = rpy(4.0, -3.0, 25.0);
  s.imu.p_w_b = Vec3d(0.3, -0.2, 0.1);
  s.imu.v_w_b = Vec3d(0.5, 0.1, -0.05);
  std::mt19937 rng(7);
  std::normal_distribution<double> g(0.0, 0.01);
  Eigen::MatrixXd A(s.dim(), s.dim());
  for (int i = 0; i < A.size(); ++i) A(i) = g(rng);
  s.P = A * A.transpose() + 1e-4 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  return s;
}

TEST(GlobalAlignment, HeadingAndPositionTakeTheSourceAndItsAccuracy) {
  const State before = initialised_state();
  State s = before;
  const SE3d target(rpy(4.0, -3.0, 110.0), Vec3d(5.0, 6.0, 1.5));  // the same tilt, another heading
  ASSERT_TRUE(align_state(s, target, 0.02, 0.5 * kDeg).ok());
  // Pose: the target's (the tilts agree, so the best yaw is exact); gravity in the body unchanged.
  EXPECT_LT(so3::log<double>(s.imu.q_w_b.conjugate() * target.quaternion()).norm(), 1e-12);
  EXPECT_MATRIX_NEAR(s.imu.p_w_b, target.translation(), 1e-12);
  EXPECT_MATRIX_NEAR(s.imu.q_w_b.conjugate() * Vec3d::UnitZ(), before.imu.q_w_b.conjugate() * Vec3d::UnitZ(),
                     1e-12);
  EXPECT_NEAR(s.imu.v_w_b.norm(), before.imu.v_w_b.norm(), 1e-12);
  // Heading error (about gravity, in the body: u^T dtheta_b): the source's variance, and no
  // correlation with any other error.
  const Vec3d u = s.imu.q_w_b.conjugate() * Vec3d::UnitZ();
  Eigen::VectorXd a(s.dim());
  a << u, Eigen::VectorXd::Zero(s.dim() - 3);
  EXPECT_NEAR(a.dot(s.P * a), std::pow(0.5 * kDeg, 2), 1e-15);
  EXPECT_MATRIX_NEAR(s.P * a, std::pow(0.5 * kDeg, 2) * a, 1e-15);
  // Position: the source's accuracy, uncorrelated.
  EXPECT_MATRIX_NEAR(s.P.block(3, 3, 3, 3), Mat3d::Identity() * 0.02 * 0.02, 1e-15);
  EXPECT_NEAR(s.P.middleRows(3, 3).norm(), std::sqrt(3.0) * 0.02 * 0.02, 1e-12);
  // Roll and pitch (the horizontal part of the orientation error) and the biases: unchanged.
  const Mat3d H = Mat3d::Identity() - u * u.transpose();
  EXPECT_MATRIX_NEAR(H * s.P.block(0, 0, 3, 3) * H, H * before.P.block(0, 0, 3, 3) * H, 1e-15);
  EXPECT_MATRIX_NEAR(s.P.block(9, 9, 6, 6), before.P.block(9, 9, 6, 6), 1e-15);
  EXPECT_MATRIX_NEAR(H * s.P.block(0, 9, 3, 6), H * before.P.block(0, 9, 3, 6), 1e-15);
}

TEST(GlobalAlignment, WithoutAHeadingAccuracyTheOrientationCovarianceStays) {
  const State before = initialised_state();
  State s = before;
  ASSERT_TRUE(align_state(s, SE3d(rpy(0.0, 0.0, -60.0), Vec3d(1.0, 2.0, 3.0)), 0.05, std::nullopt).ok());
  EXPECT_MATRIX_NEAR(s.P.block(0, 0, 3, 3), before.P.block(0, 0, 3, 3), 1e-15);
  EXPECT_MATRIX_NEAR(s.P.block(0, 9, 3, 6), before.P.block(0, 9, 3, 6), 1e-15);
  EXPECT_MATRIX_NEAR(s.P.block(3, 3, 3, 3), Mat3d::Identity() * 0.05 * 0.05, 1e-15);
}

TEST(GlobalAlignment, OnlyBeforeTheFirstClone) {
  State s = initialised_state();
  ASSERT_TRUE(augment_clone(s, 1000, Vec3d::Zero()).ok());
  EXPECT_EQ(align_state(s, SE3d(), 0.02, 0.01).code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace mrvs::edge
