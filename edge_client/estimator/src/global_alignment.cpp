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
  if (o.source == "none") return std::optional<SE3d>();
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
  const Mat3d R_full = T_w_b.rotation_matrix() * state.imu.q_w_b.toRotationMatrix().transpose();
  const double yaw = std::atan2(R_full(1, 0) - R_full(0, 1), R_full(0, 0) + R_full(1, 1));
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

}  // namespace mrvs::edge
