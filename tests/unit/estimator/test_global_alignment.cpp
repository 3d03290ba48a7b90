// The one-time alignment to the global pose source: the frame turns about gravity only, and
// the covariance takes the source's accuracy for the position and the heading while roll,
// pitch, velocity and biases keep what the initialiser knew.
#include <random>

#include <Eigen/Eigenvalues>

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

// ---- Re-anchoring a running state into the map frame (the localisation answer) ----------

namespace mrvs::edge {
namespace {

/// A state with two clones and two points, and a random full covariance.
State running_state() {
  State s = initialised_state();
  EXPECT_TRUE(augment_clone(s, 1000, Vec3d(0.1, -0.2, 0.3)).ok());
  s.imu.q_w_b = rpy(2.0, 5.0, 40.0);
  s.imu.p_w_b = Vec3d(0.8, 0.1, 0.3);
  EXPECT_TRUE(augment_clone(s, 2000, Vec3d(0.0, 0.1, -0.2)).ok());
  for (FeatureId id : {FeatureId{7}, FeatureId{9}}) {
    PointState p;
    p.p_w = p.fej = Vec3d(2.0 + id, -1.0, 1.2);
    p.slot = s.append(3);
    s.points[id] = p;
  }
  std::mt19937 rng(11);
  std::normal_distribution<double> g(0.0, 0.01);
  Eigen::MatrixXd A(s.dim(), s.dim());
  for (int i = 0; i < A.size(); ++i) A(i) = g(rng);
  s.P = A * A.transpose() + 1e-4 * Eigen::MatrixXd::Identity(s.dim(), s.dim());
  return s;
}

Mat6d alignment_covariance() {
  Mat6d c = Mat6d::Zero();
  c.diagonal() << 4e-4, 9e-4, 1e-4, 0.0, 0.0, 3e-5;
  c(0, 5) = c(5, 0) = 2e-5;
  c(0, 1) = c(1, 0) = -1e-4;
  return c;
}

/// Jacobian (3 x dim) of f = R_w_b^T (x - p_w_b) for a point x of the state at `x_offset`
/// (a point, or a clone's position): invariant when everything moves together.
Eigen::MatrixXd relative_jacobian(const State& s, int x_offset, const Vec3d& x) {
  const Mat3d Rt = s.imu.q_w_b.toRotationMatrix().transpose();
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, s.dim());
  J.block<3, 3>(0, 0) = skew<double>(Vec3d(Rt * (x - s.imu.p_w_b)));
  J.block<3, 3>(0, 3) = -Rt;
  J.block<3, 3>(0, x_offset) += Rt;
  return J;
}

TEST(Reanchor, MovesEverythingAndKeepsWhatIsRelative) {
  const State before = running_state();
  State s = before;
  const SE3d T_m_o(Quatd(Eigen::AngleAxisd(70.0 * kDeg, Vec3d::UnitZ())), Vec3d(3.0, -2.0, 1.0));
  const Vec3d anchor_m(2.0, 1.0, 0.5);
  ASSERT_TRUE(reanchor_state(s, T_m_o, alignment_covariance(), anchor_m).ok());
  // Values: everything moved by T_m_o.
  const Vec3d p_moved = T_m_o * before.imu.p_w_b;
  const Vec3d v_moved = T_m_o.rotation_matrix() * before.imu.v_w_b;
  EXPECT_MATRIX_NEAR(s.imu.p_w_b, p_moved, 1e-12);
  EXPECT_MATRIX_NEAR(s.imu.v_w_b, v_moved, 1e-12);
  EXPECT_LT(so3::log<double>(s.imu.q_w_b.conjugate() * (T_m_o.quaternion() * before.imu.q_w_b)).norm(),
            1e-12);
  for (const auto& [t, c] : s.clones) {
    const Vec3d p = T_m_o * before.clones.at(t).T_w_b.translation();
    const Vec3d fej = T_m_o * before.clones.at(t).fej.translation();
    EXPECT_MATRIX_NEAR(c.T_w_b.translation(), p, 1e-12);
    EXPECT_MATRIX_NEAR(c.fej.translation(), fej, 1e-12);
  }
  for (const auto& [id, p] : s.points) {
    const Vec3d moved = T_m_o * before.points.at(id).p_w;
    const Vec3d moved_fej = T_m_o * before.points.at(id).fej;
    EXPECT_MATRIX_NEAR(p.p_w, moved, 1e-12);
    EXPECT_MATRIX_NEAR(p.fej, moved_fej, 1e-12);
  }
  // Relative geometry (points and clones seen from the IMU) keeps its covariance exactly.
  for (const auto& [id, p] : s.points) {
    const Eigen::MatrixXd Jb = relative_jacobian(before, p.slot.offset, before.points.at(id).p_w);
    const Eigen::MatrixXd Ja = relative_jacobian(s, p.slot.offset, p.p_w);
    EXPECT_MATRIX_NEAR(Ja * s.P * Ja.transpose(), Jb * before.P * Jb.transpose(), 1e-12);
  }
  for (const auto& [t, c] : s.clones) {
    const int o = c.slot.offset + 3;
    const Eigen::MatrixXd Jb = relative_jacobian(before, o, before.clones.at(t).T_w_b.translation());
    const Eigen::MatrixXd Ja = relative_jacobian(s, o, c.T_w_b.translation());
    EXPECT_MATRIX_NEAR(Ja * s.P * Ja.transpose(), Jb * before.P * Jb.transpose(), 1e-12);
  }
  // Biases: unchanged.
  const Mat6d biases_after = s.P.block<6, 6>(9, 9);
  const Mat6d biases_before = before.P.block<6, 6>(9, 9);
  EXPECT_MATRIX_NEAR(biases_after, biases_before, 1e-15);
  // Where the IMU is and its heading: the alignment's, moved from the anchor to the IMU.
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4, s.dim());
  C.block<3, 3>(0, 3).setIdentity();
  C.block<1, 3>(3, 0) = (s.imu.q_w_b.conjugate() * Vec3d::UnitZ()).transpose();
  Eigen::Matrix4d G = Eigen::Matrix4d::Identity();
  G.block<3, 1>(0, 3) = Vec3d::UnitZ().cross(s.imu.p_w_b - anchor_m);
  Eigen::Matrix4d S;
  const int idx[4] = {0, 1, 2, 5};
  for (int a = 0; a < 4; ++a)
    for (int b = 0; b < 4; ++b) S(a, b) = alignment_covariance()(idx[a], idx[b]);
  EXPECT_MATRIX_NEAR(C * s.P * C.transpose(), G * S * G.transpose(), 1e-12);
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(s.P).eigenvalues().minCoeff(), -1e-12);
}

TEST(Reanchor, GaugeDirectionsAreTheRigidMotionsOfTheState) {
  const State s = running_state();
  const Vec3d pivot(0.4, -0.3, 0.2);
  const Eigen::MatrixXd N = gauge_directions(s, pivot);
  // Numeric: move every value by a small rigid motion about +z through the pivot, read the
  // error-state difference (orientation: right-perturbation, body frame).
  auto moved_error = [&](const Eigen::Vector4d& d) {
    const Mat3d R = Eigen::AngleAxisd(d(3), Vec3d::UnitZ()).toRotationMatrix();
    auto move = [&](const Vec3d& p) { return Vec3d(R * (p - pivot) + pivot + d.head<3>()); };
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(s.dim());
    auto pose = [&](int o, const Quatd& q, const Vec3d& p) {
      dx.segment<3>(o) = so3::log<double>(q.conjugate() * (Quatd(R) * q));
      dx.segment<3>(o + 3) = move(p) - p;
    };
    pose(0, s.imu.q_w_b, s.imu.p_w_b);
    dx.segment<3>(6) = R * s.imu.v_w_b - s.imu.v_w_b;
    for (const auto& [t, c] : s.clones) pose(c.slot.offset, c.T_w_b.quaternion(), c.T_w_b.translation());
    for (const auto& [id, p] : s.points) dx.segment<3>(p.slot.offset) = move(p.p_w) - p.p_w;
    return dx;
  };
  const double h = 1e-6;
  for (int k = 0; k < 4; ++k) {
    Eigen::Vector4d d = Eigen::Vector4d::Zero();
    d(k) = h;
    const Eigen::VectorXd numeric = (moved_error(d) - moved_error(-d)) / (2 * h);
    EXPECT_MATRIX_NEAR(numeric, N.col(k), 1e-7) << "direction " << k;
  }
}

TEST(Reanchor, RefusesABrokenCovariance) {
  State s = running_state();
  Mat6d c = alignment_covariance();
  c(0, 0) = NAN;
  EXPECT_FALSE(reanchor_state(s, SE3d(), c, Vec3d::Zero()).ok());
  c = alignment_covariance();
  c(0, 1) = 1.0;
  EXPECT_FALSE(reanchor_state(s, SE3d(), c, Vec3d::Zero()).ok());
}

}  // namespace
}  // namespace mrvs::edge

// ---- Pose fixes: a localisation answer once the state is in the map frame ----------------

namespace mrvs::edge {
namespace {

/// A running state whose uncertainty is mostly where it lies (position sigma `sigma_m`,
/// heading `sigma_deg` along the gauge directions through the IMU) plus a little relative one.
State drifting_state(double sigma_m, double sigma_deg) {
  State s = running_state();
  s.P *= 0.01;
  const Eigen::MatrixXd N = gauge_directions(s, s.imu.p_w_b);
  Eigen::Vector4d g;
  g << sigma_m, sigma_m, sigma_m, sigma_deg * kDeg;
  s.P += N * g.array().square().matrix().asDiagonal() * N.transpose();
  return s;
}

/// [position; yaw] of the IMU (the yaw: of R_w_b about +z).
Eigen::Vector4d position_yaw(const State& s) {
  Eigen::Vector4d x;
  x.head<3>() = s.imu.p_w_b;
  x(3) = yaw_of(SE3d(s.imu.q_w_b, Vec3d::Zero()));
  return x;
}

/// C P C^T: the [position; heading] covariance of the IMU (gauge rows through it).
Eigen::Matrix4d own_covariance(const State& s) {
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4, s.dim());
  C.block<3, 3>(0, 3).setIdentity();
  C.block<1, 3>(3, 0) = (s.imu.q_w_b.conjugate() * Vec3d::UnitZ()).transpose();
  return C * s.P * C.transpose();
}

TEST(PoseFix, TheStateMovesByTheBayesCombinationAndKeepsItsCovariance) {
  const State before = drifting_state(0.05, 1.0);
  State s = before;
  const SE3d T_fix(Quatd(Eigen::AngleAxisd(0.6 * kDeg, Vec3d::UnitZ())), Vec3d(0.03, -0.02, 0.01));
  const Vec3d anchor_m = before.imu.p_w_b + Vec3d(0.5, -0.3, 0.0);
  const auto fix = apply_pose_fix(s, T_fix, alignment_covariance(), anchor_m);
  ASSERT_TRUE(fix.ok()) << fix.status();
  ASSERT_TRUE(fix->applied);
  // The measured error at the IMU: where T_fix puts it, and T_fix's yaw.
  const Vec3d measured = T_fix * before.imu.p_w_b - before.imu.p_w_b;
  EXPECT_MATRIX_NEAR(fix->residual.head<3>(), measured, 1e-12);
  EXPECT_NEAR(fix->residual(3), 0.6 * kDeg, 1e-12);
  // Brute force: the linear-Gaussian combination of the filter's [p; yaw] (prior Sigma) and the
  // answer's (R, moved to the IMU): the IMU moves by Sigma (Sigma + R)^-1 r.
  const Eigen::Matrix4d Sigma = own_covariance(before);
  const Eigen::Matrix4d R = position_yaw_covariance(alignment_covariance(), anchor_m, before.imu.p_w_b);
  const Eigen::Vector4d expected = Sigma * (Sigma + R).ldlt().solve(fix->residual);
  EXPECT_MATRIX_NEAR(fix->correction, expected, 1e-12);
  Eigen::Vector4d moved = position_yaw(s) - position_yaw(before);
  moved(3) = std::remainder(moved(3), 2.0 * M_PI);
  EXPECT_MATRIX_NEAR(moved, expected, 2e-5);  // the heading to first order (a body-frame rotation)
  EXPECT_NEAR(fix->mahalanobis2, fix->residual.dot((Sigma + R).ldlt().solve(fix->residual)), 1e-9);
  // The window follows through its correlations: a clone moves about as the IMU does.
  for (const auto& [t, c] : s.clones) {
    const Vec3d d_clone = c.T_w_b.translation() - before.clones.at(t).T_w_b.translation();
    EXPECT_LT((d_clone - expected.head<3>()).norm(), 0.2 * expected.head<3>().norm() + 2e-3) << t;
  }
  // What it knows stays.
  EXPECT_EQ(s.P, before.P);
}

TEST(PoseFix, ATightAnswerTakesTheStateThereAndABroadOneBarelyMovesIt) {
  const SE3d T_fix(Quatd(Eigen::AngleAxisd(-0.4 * kDeg, Vec3d::UnitZ())), Vec3d(-0.02, 0.04, 0.0));
  State tight = drifting_state(0.05, 1.0);
  const Eigen::Vector4d start = position_yaw(tight);
  const Vec3d p0 = tight.imu.p_w_b;
  Mat6d small = Mat6d::Zero();
  small.diagonal() << 1e-8, 1e-8, 1e-8, 0.0, 0.0, 1e-10;
  ASSERT_TRUE(apply_pose_fix(tight, T_fix, small, p0)->applied);
  EXPECT_MATRIX_NEAR(tight.imu.p_w_b, T_fix * p0, 2e-4);
  EXPECT_NEAR(position_yaw(tight)(3) - start(3), -0.4 * kDeg, 2e-4);
  State broad = drifting_state(0.05, 1.0);
  Mat6d large = Mat6d::Zero();
  large.diagonal() << 1.0, 1.0, 1.0, 0.0, 0.0, 1.0;
  ASSERT_TRUE(apply_pose_fix(broad, T_fix, large, p0)->applied);
  EXPECT_LT((broad.imu.p_w_b - p0).norm(), 0.01 * 0.045);
}

TEST(PoseFix, TheFloorLetsAnOverconfidentFilterBeCorrected) {
  // The filter claims 2 mm and 0.02 deg; the answer, 1 cm and 0.2 deg, says 6 cm and 1 deg.
  const SE3d T_fix(Quatd(Eigen::AngleAxisd(1.0 * kDeg, Vec3d::UnitZ())), Vec3d(0.06, 0.0, 0.0));
  Mat6d c = Mat6d::Zero();
  c.diagonal() << 1e-4, 1e-4, 1e-4, 0.0, 0.0, std::pow(0.2 * kDeg, 2);
  State stiff = drifting_state(0.002, 0.02);
  const Vec3d p0 = stiff.imu.p_w_b;
  const auto refused = apply_pose_fix(stiff, T_fix, c, p0);
  ASSERT_TRUE(refused.ok());
  EXPECT_FALSE(refused->applied);
  // Trusted no better than 5 cm and 1 deg, it takes most of the correction.
  const Eigen::Vector4d floor(0.05, 0.05, 0.05, 1.0 * kDeg);
  const auto fix = apply_pose_fix(stiff, T_fix, c, p0, floor);
  ASSERT_TRUE(fix.ok());
  ASSERT_TRUE(fix->applied);
  EXPECT_GT(fix->correction.head<3>().norm(), 0.8 * 0.06);
  EXPECT_GT(fix->correction(3), 0.8 * kDeg);
  EXPECT_LT(fix->correction(3), 1.0 * kDeg);
}

TEST(PoseFix, AnAnswerTheFilterCannotBelieveIsNotApplied) {
  const State before = drifting_state(0.02, 0.5);
  State s = before;
  // 30 cm off, answered to 1 cm, while the filter knows its place to 2 cm.
  Mat6d c = Mat6d::Zero();
  c.diagonal() << 1e-4, 1e-4, 1e-4, 0.0, 0.0, 1e-5;
  const auto fix = apply_pose_fix(s, SE3d(Quatd::Identity(), Vec3d(0.3, 0.0, 0.0)), c, s.imu.p_w_b);
  ASSERT_TRUE(fix.ok());
  EXPECT_FALSE(fix->applied);
  EXPECT_GT(fix->mahalanobis2, kChi2Pose4);
  EXPECT_EQ(s.imu.p_w_b, before.imu.p_w_b);
  EXPECT_EQ(s.P, before.P);
  // A broken covariance is an error, the state unchanged.
  c(0, 0) = NAN;
  EXPECT_EQ(apply_pose_fix(s, SE3d(), c, s.imu.p_w_b).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(s.P, before.P);
}

}  // namespace
}  // namespace mrvs::edge
