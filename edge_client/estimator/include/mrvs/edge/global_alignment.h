#pragma once
// Alignment of the odometry frame to the map frame (algorithm.md 6.2, decision 7):
//   map       (the default) no pose at initialisation: the filter runs in its odometry frame
//             until the cloud's localisation service places it in the map (MapLocaliser),
//             then reanchor_state() moves it; again after every restart;
// or, once at initialisation, from a "global localisation pose" (the named ablations):
//   gt        the ground-truth pose at the initialisation time;
//   gt_noisy  the same with a translation error of random direction whose length is drawn
//             from N(mean, sd) (default: the paper's 2 cm mean);
//   constant  a fixed T_w_o applied to the odometry frame;
//   none      the odometry frame stays (gravity aligned, yaw and position from the start).
// The target fixes position and heading (4 degrees of freedom); roll and pitch stay the
// inertial estimate. Ground truth is read only by gt and gt_noisy.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/edge/state.h"
#include "mrvs/io/types.h"

namespace mrvs::edge {

struct AlignmentOptions : config::OptionsEquality<AlignmentOptions> {
  std::string source = "map";                         ///< map | gt | gt_noisy | constant | none
  double translation_noise_mean_m = 0.02;             ///< gt_noisy: mean length of the error
  double translation_noise_sd_m = 0.005;              ///< gt_noisy: its spread
  double rotation_noise_deg = 0.0;                    ///< gt_noisy: rotation error (random axis)
  int seed = 1;                                       ///< of the noise
  std::vector<double> constant = {0, 0, 0, 0, 0, 0};  ///< T_w_o: x y z (m), roll pitch yaw (deg)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("source", source, one_of({"map", "gt", "gt_noisy", "constant", "none"}),
      "map (the cloud's localisation) | gt | gt_noisy (the paper's protocol) | constant | none");
    v("translation_noise_mean_m", translation_noise_mean_m, in_range(0.0, 100.0), "gt_noisy: mean error, m");
    v("translation_noise_sd_m", translation_noise_sd_m, in_range(0.0, 100.0), "gt_noisy: error spread, m");
    v("rotation_noise_deg", rotation_noise_deg, in_range(0.0, 180.0), "gt_noisy: rotation error, deg");
    v("seed", seed, in_range(0, 2147483647), "seed of the noise");
    v("constant", constant, list_size(6, 6), "constant: x y z roll pitch yaw (m, deg)");
  }
};

/// The ground-truth pose at t_ns, interpolated (position linearly, rotation by slerp);
/// OutOfRange when t_ns is outside the trajectory.
StatusOr<SE3d> interpolate_trajectory(const io::Trajectory& trajectory, TimestampNs t_ns);

/// True when `options` reads ground truth (gt, gt_noisy).
inline bool needs_groundtruth(const AlignmentOptions& options) {
  return options.source == "gt" || options.source == "gt_noisy";
}

/// The pose the state should take at its current time (IMU clock), per `options`:
/// `groundtruth` is needed for gt / gt_noisy (FailedPrecondition naming the fix otherwise).
/// nullopt for none and map (which aligns later, from the cloud).
StatusOr<std::optional<SE3d>> alignment_target(const AlignmentOptions& options,
                                               const io::Trajectory& groundtruth, const State& state);

/// Moves the state so that the IMU takes the target's position and heading: the frame
/// turns about gravity (z) by the yaw that best matches the target orientation, so roll and
/// pitch stay the IMU's own (gravity keeps pointing down, and a tilt error of the target does
/// not enter). Velocity and its covariance rotate with the frame; the position and the
/// heading take the source's accuracy: position_sigma^2 I, and yaw_sigma (rad; nullopt: the
/// heading keeps its covariance) for the rotation about gravity, both uncorrelated with the
/// rest. Roll, pitch and the biases keep their estimates and covariance. Only before the
/// first clone.
Status align_state(State& state, const SE3d& T_w_b, double position_sigma, std::optional<double> yaw_sigma);

/// The heading of T's rotation: the angle about +z that best matches it (its roll and pitch
/// left out), rad.
double yaw_of(const SE3d& T);
/// T with its rotation replaced by the rotation about +z of yaw_of(T).
SE3d yaw_only(const SE3d& T);

/// The four directions in which a gravity-aligned VIO state cannot be observed: moving and
/// turning everything together (translation x, y, z, then yaw about +z through `pivot`), as
/// columns over the state's error (dim x 4). `pivot` is a point of the state's frame.
Eigen::MatrixXd gauge_directions(const State& state, const Vec3d& pivot);

/// Moves the whole state (IMU, clones, points and the points' first estimates) from the
/// odometry frame o into the map frame m by T_m_o, keeping gravity: T_m_o's rotation is taken
/// about +z only (its roll and pitch, if any, are dropped). The uncertainty of where the state
/// lies, along gauge_directions() through the current IMU position, is replaced by the
/// alignment's: `covariance` is that of [rho; phi] of a perturbation about `anchor_m` (map
/// frame; mrvs/localisation/types.h), of which rho and phi_z are used. Everything relative
/// (the clones to each other, the points to the clones, velocity in the body frame, biases,
/// calibration) keeps its covariance. InvalidArgument for a non-finite or non-symmetric
/// covariance.
Status reanchor_state(State& state, const SE3d& T_m_o, const Mat6d& covariance, const Vec3d& anchor_m);

/// The covariance of [position; yaw] at the map point x_m (4 x 4) of an answer whose
/// `covariance` is that of [rho; phi] about `anchor_m` (mrvs/localisation/types.h): rho and
/// phi_z, the yaw's lever arm moved from the anchor to x_m.
Eigen::Matrix4d position_yaw_covariance(const Mat6d& covariance, const Vec3d& anchor_m, const Vec3d& x_m);

/// 99 % quantile of chi-square with 4 degrees of freedom (a position and a heading).
constexpr double kChi2Pose4 = 13.277;

/// What apply_pose_fix() did.
struct PoseFix {
  Eigen::Vector4d residual = Eigen::Vector4d::Zero();  ///< the answer's [position (m); yaw (rad)] at the IMU
  Eigen::Vector4d correction = Eigen::Vector4d::Zero();  ///< what the state moved by (applied only)
  double mahalanobis2 = 0.0;  ///< of the residual against the filter's (floored) and the answer's covariance
  bool applied = false;       ///< false: beyond the gate, the state is unchanged
};

/// A localisation answer once the state is already in the map frame (design/localisation.md,
/// "optionally at a low rate as a pose update"): T_fix (its yaw and translation; roll and
/// pitch dropped) takes the state's frame to where the cloud places it, so the IMU's true
/// position is T_fix * p and its heading yaw(T_fix) more than the estimate (the residual).
/// The filter's own [position; heading] covariance at the IMU, each variance raised to at
/// least `floor_sigma`^2 ([m x3; rad]; the raise along the gauge directions, where the whole
/// state may lie off together), and the answer's (`covariance` of [rho; phi] about
/// `anchor_m`, moved to the IMU) weigh the two: the state's mean moves by the Kalman gain of
/// that floored covariance (the IMU's position and heading by own (own + answer)^-1 residual,
/// the clones, points, velocity and gyro bias through their correlations). The covariance is
/// kept: the filter's stage-1 map updates, cast from its own estimate, confirm its heading and
/// its position along a surface whether they are right or wrong, so it is overconfident about
/// where it lies (hence the floor); an EKF update of the covariance with the floor in it left
/// the filter that much looser for the following map updates, which then turned its heading by
/// degrees (edge_client/README.md). Not applied when the residual's squared Mahalanobis
/// distance exceeds `gate_chi2` (the answer disagrees with the filter beyond both
/// covariances). InvalidArgument for a non-finite or non-symmetric covariance (the state
/// unchanged).
StatusOr<PoseFix> apply_pose_fix(State& state, const SE3d& T_fix, const Mat6d& covariance,
                                 const Vec3d& anchor_m,
                                 const Eigen::Vector4d& floor_sigma = Eigen::Vector4d::Zero(),
                                 double gate_chi2 = kChi2Pose4);

}  // namespace mrvs::edge
