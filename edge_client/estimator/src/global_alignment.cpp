#include "mrvs/edge/global_alignment.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <fmt/format.h>

#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

SE3d constant_pose(const std::vector<double>& c) {
  const double d = M_PI / 180.0;
  const Quatd q = Eigen::AngleAxisd(c[5] * d, Vec3d::UnitZ()) * Eigen::AngleAxisd(c[4] * d, Vec3d::UnitY()) *
                  Eigen::AngleAxisd(c[3] * d, Vec3d::UnitX());
  return SE3d(q, Vec3d(c[0], c[1], c[2]));
}

SE3d with_noise(const SE3d& T, const AlignmentOptions& o) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(o.seed));
  std::normal_distribution<double> n01(0.0, 1.0);
  const Vec3d dir = Vec3d(n01(rng), n01(rng), n01(rng)).normalized();
  const double length = std::max(0.0, o.translation_noise_mean_m + o.translation_noise_sd_m * n01(rng));
  const Vec3d axis = Vec3d(n01(rng), n01(rng), n01(rng)).normalized();
  const Quatd dq = so3::exp_quat<double>(Vec3d(axis * (o.rotation_noise_deg * M_PI / 180.0)));
  return SE3d(T.quaternion() * dq, T.translation() + length * dir);
}

}  // namespace

StatusOr<SE3d> interpolate_trajectory(const io::Trajectory& traj, TimestampNs t_ns) {
  if (traj.empty() || t_ns < traj.front().t_ns || t_ns > traj.back().t_ns) {
    return absl::OutOfRangeError(fmt::format("time {} ns is outside the ground truth ({} .. {} ns)", t_ns,
                                             traj.empty() ? 0 : traj.front().t_ns,
                                             traj.empty() ? 0 : traj.back().t_ns));
  }
  const auto it = std::lower_bound(traj.begin(), traj.end(), t_ns,
                                   [](const io::StampedPose& p, TimestampNs t) { return p.t_ns < t; });
  if (it->t_ns == t_ns || it == traj.begin()) return it->T_w_b;
  const io::StampedPose& a = *(it - 1);
  const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(it->t_ns - a.t_ns);
  return SE3d(a.T_w_b.quaternion().slerp(s, it->T_w_b.quaternion()),
              (1.0 - s) * a.T_w_b.translation() + s * it->T_w_b.translation());
}

StatusOr<std::optional<SE3d>> alignment_target(const AlignmentOptions& o, const io::Trajectory& gt,
                                               const State& state) {
  const SE3d T_o_b(state.imu.q_w_b, state.imu.p_w_b);
  if (o.source == "none" || o.source == "map") return std::optional<SE3d>();
  if (o.source == "constant") return std::optional<SE3d>(constant_pose(o.constant) * T_o_b);
  if (gt.empty()) {
    return absl::FailedPreconditionError(
        fmt::format("alignment source '{}' needs ground truth: the dataset has no "
                    "state_groundtruth_estimate0, pass a file "
                    "with --groundtruth, or set estimator.alignment.source to none",
                    o.source));
  }
  MRVS_ASSIGN_OR_RETURN(const SE3d T, interpolate_trajectory(gt, state.imu.t_ns));
  return std::optional<SE3d>(o.source == "gt" ? T : with_noise(T, o));
}

Status align_state(State& state, const SE3d& T_w_b, double position_sigma, std::optional<double> yaw_sigma) {
  if (!state.clones.empty()) return absl::FailedPreconditionError("align_state: only before the first clone");
  // The rotation about gravity (z) that best takes the estimated orientation to the target
  // one (2-D Procrustes on the horizontal block).
  const double yaw = yaw_of(SE3d(T_w_b.quaternion() * state.imu.q_w_b.conjugate(), Vec3d::Zero()));
  const Mat3d R = Eigen::AngleAxisd(yaw, Vec3d::UnitZ()).toRotationMatrix();  // R_w_o
  state.imu.q_w_b = Quatd(R * state.imu.q_w_b.toRotationMatrix()).normalized();
  state.imu.p_w_b = T_w_b.translation();
  state.imu.v_w_b = R * state.imu.v_w_b;
  // World-frame error blocks (position 3..5, velocity 6..8) rotate with the frame; the
  // orientation error is in the body frame and does not change.
  Eigen::MatrixXd J = Eigen::MatrixXd::Identity(state.dim(), state.dim());
  J.block<3, 3>(3, 3) = R;
  J.block<3, 3>(6, 6) = R;
  state.P = J * state.P * J.transpose();
  // The position comes from the pose source now: its accuracy, uncorrelated.
  state.P.middleRows(3, 3).setZero();
  state.P.middleCols(3, 3).setZero();
  state.P.block<3, 3>(3, 3) = Mat3d::Identity() * position_sigma * position_sigma;
  // So does the heading: the error about gravity, u^T dtheta_b with u = R_w_b^T z, is replaced
  // by the source's (independent, yaw_sigma); roll and pitch keep the initialiser's.
  if (!yaw_sigma) return absl::OkStatus();
  const Vec3d u = state.imu.q_w_b.conjugate() * Vec3d::UnitZ();
  Eigen::MatrixXd K = Eigen::MatrixXd::Identity(state.dim(), state.dim());
  K.block<3, 3>(0, 0) -= u * u.transpose();
  state.P = K * state.P * K.transpose();
  state.P.block<3, 3>(0, 0) += *yaw_sigma * *yaw_sigma * u * u.transpose();
  return absl::OkStatus();
}

double yaw_of(const SE3d& T) {
  const Mat3d R = T.rotation_matrix();
  return std::atan2(R(1, 0) - R(0, 1), R(0, 0) + R(1, 1));
}

SE3d yaw_only(const SE3d& T) {
  return SE3d(Quatd(Eigen::AngleAxisd(yaw_of(T), Vec3d::UnitZ())), T.translation());
}

Eigen::MatrixXd gauge_directions(const State& state, const Vec3d& pivot) {
  const Vec3d z = Vec3d::UnitZ();
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(state.dim(), 4);
  auto pose = [&](int o, const Quatd& q_w_b, const Vec3d& p_w) {  // [dtheta (body); dp] at offset o
    N.block<3, 3>(o + 3, 0).setIdentity();
    N.block<3, 1>(o, 3) = q_w_b.conjugate() * z;
    N.block<3, 1>(o + 3, 3) = z.cross(p_w - pivot);
  };
  const int i = state.imu_slot.offset;
  pose(i, state.imu.q_w_b, state.imu.p_w_b);
  N.block<3, 1>(i + 6, 3) = z.cross(state.imu.v_w_b);
  for (const auto& [t, c] : state.clones) pose(c.slot.offset, c.T_w_b.quaternion(), c.T_w_b.translation());
  for (const auto& [id, p] : state.points) {
    N.block<3, 3>(p.slot.offset, 0).setIdentity();
    N.block<3, 1>(p.slot.offset, 3) = z.cross(p.p_w - pivot);
  }
  return N;
}

namespace {

/// Rows extracting the current IMU's position and heading errors (4 x dim): C N = I for the
/// gauge directions through the IMU position.
Eigen::MatrixXd imu_gauge_rows(const State& state) {
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(4, state.dim());
  const int i = state.imu_slot.offset;
  C.block<3, 3>(0, i + 3).setIdentity();
  C.block<1, 3>(3, i) = (state.imu.q_w_b.conjugate() * Vec3d::UnitZ()).transpose();  // z^T R_w_b dtheta
  return C;
}

Status check_covariance(const Mat6d& covariance, const char* what) {
  if (!covariance.allFinite() || !covariance.isApprox(covariance.transpose(), 1e-9)) {
    return absl::InvalidArgumentError(
        fmt::format("{}: the alignment covariance is not finite and symmetric", what));
  }
  return absl::OkStatus();
}

}  // namespace

Eigen::Matrix4d position_yaw_covariance(const Mat6d& covariance, const Vec3d& anchor_m, const Vec3d& x_m) {
  Eigen::Matrix4d S;
  const int idx[4] = {0, 1, 2, 5};
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) S(a, b) = covariance(idx[a], idx[b]);
  }
  Eigen::Matrix4d G = Eigen::Matrix4d::Identity();  // [rho; phi_z] about the anchor -> [p; yaw] at x_m
  G.block<3, 1>(0, 3) = Vec3d::UnitZ().cross(x_m - anchor_m);
  return G * S * G.transpose();
}

namespace {

/// Moves the whole state (IMU, clones, points and their first estimates) by T (its rotation
/// about +z); world-frame error blocks of the covariance turn with it.
void move_state(State& state, const SE3d& T) {
  const Mat3d R = T.rotation_matrix();
  // Error-state Jacobian of the frame change: world-frame blocks rotate, body-frame ones stay.
  Eigen::MatrixXd F = Eigen::MatrixXd::Identity(state.dim(), state.dim());
  const int i = state.imu_slot.offset;
  F.block<3, 3>(i + 3, i + 3) = R;
  F.block<3, 3>(i + 6, i + 6) = R;
  state.imu.q_w_b = (T.quaternion() * state.imu.q_w_b).normalized();
  state.imu.p_w_b = T * state.imu.p_w_b;
  state.imu.v_w_b = R * state.imu.v_w_b;
  for (auto& [t, c] : state.clones) {
    F.block<3, 3>(c.slot.offset + 3, c.slot.offset + 3) = R;
    c.T_w_b = T * c.T_w_b;
    c.fej = T * c.fej;
  }
  for (auto& [id, p] : state.points) {
    F.block<3, 3>(p.slot.offset, p.slot.offset) = R;
    p.p_w = T * p.p_w;
    p.fej = T * p.fej;
  }
  state.P = F * state.P * F.transpose();
}

}  // namespace

Status reanchor_state(State& state, const SE3d& T_m_o_in, const Mat6d& covariance, const Vec3d& anchor_m) {
  MRVS_RETURN_IF_ERROR(check_covariance(covariance, "reanchor_state"));
  move_state(state, yaw_only(T_m_o_in));
  // Drop the position and heading uncertainty (along the gauge directions), put the map's in.
  const Vec3d pivot = state.imu.p_w_b;
  const Eigen::MatrixXd N = gauge_directions(state, pivot);
  const Eigen::MatrixXd K = Eigen::MatrixXd::Identity(state.dim(), state.dim()) - N * imu_gauge_rows(state);
  state.P =
      K * state.P * K.transpose() + N * position_yaw_covariance(covariance, anchor_m, pivot) * N.transpose();
  state.P = 0.5 * (state.P + state.P.transpose()).eval();
  return absl::OkStatus();
}

StatusOr<PoseFix> apply_pose_fix(State& state, const SE3d& T_fix_in, const Mat6d& covariance,
                                 const Vec3d& anchor_m, const Eigen::Vector4d& floor_sigma,
                                 double gate_chi2) {
  MRVS_RETURN_IF_ERROR(check_covariance(covariance, "apply_pose_fix"));
  const SE3d T = yaw_only(T_fix_in);
  const Vec3d p = state.imu.p_w_b;
  PoseFix fix;
  fix.residual.head<3>() = T * p - p;
  fix.residual(3) = yaw_of(T);
  // The filter's own [position; heading] covariance at the IMU, each at least floor_sigma.
  const Eigen::MatrixXd C = imu_gauge_rows(state);
  Eigen::Matrix4d own = C * state.P * C.transpose();
  own.diagonal() = own.diagonal().cwiseMax(floor_sigma.array().square().matrix());
  const Eigen::LDLT<Eigen::Matrix4d> S(own + position_yaw_covariance(covariance, anchor_m, p));
  if (S.info() != Eigen::Success || !S.isPositive() || (S.vectorD().array() <= 0.0).any()) {
    return absl::InvalidArgumentError("apply_pose_fix: the position and heading covariance is singular");
  }
  fix.mahalanobis2 = fix.residual.dot(S.solve(fix.residual));
  if (!(fix.mahalanobis2 <= gate_chi2)) return fix;
  // The Kalman gain from the floored covariance (the floor added along the gauge directions
  // through the IMU, so C P' C^T = own): the mean moves by P' C^T S^-1 r, the IMU's
  // [position; heading] by own S^-1 r, the rest (clones, points, velocity, gyro bias) with
  // their correlations. The covariance is kept (see the header).
  Eigen::MatrixXd PCt = state.P * C.transpose();
  const Eigen::Vector4d raise = own.diagonal() - (C * PCt).diagonal();
  PCt += gauge_directions(state, p) * raise.asDiagonal();
  const Eigen::VectorXd dx = PCt * S.solve(fix.residual);
  if (!dx.allFinite()) return absl::InvalidArgumentError("apply_pose_fix: the correction is not finite");
  fix.correction = C * dx;
  state.apply_correction(dx);
  fix.applied = true;
  return fix;
}

}  // namespace mrvs::edge
