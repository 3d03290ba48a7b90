#pragma once
// The filter state (algorithm.md 3.1): the IMU, optional camera calibration, stochastic
// clones of the IMU pose at image times, and point features in the state ("registered map
// points" / SLAM points), with one covariance over all of them. A plain container: the EKF
// operations live in state_helper.h.
//
// Error state and its order in the covariance (every variable records its Slot):
//   IMU 15 [dtheta, dp, dv, dbg, dba] (imu_propagator.h), then, when calibrated, the time
//   offset (1), per camera the extrinsics T_b_c (6: [dtheta, dp], R_b_c = R^ Exp(dtheta))
//   and intrinsics (8, additive, camera::Params order), then clones and points in the order
//   they were added. A clone is a pose T_w_b with error [dtheta (body), dp]; a point is
//   p_w (3, additive).
// First-estimate Jacobians: clones and points keep the value they had when added (`fej`);
// measurement Jacobians are evaluated there when StateOptions::use_fej is on.
#include <array>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include <Eigen/Core>

#include "mrvs/camera/camera_model.h"
#include "mrvs/config/calibration.h"
#include "mrvs/config/options.h"
#include "mrvs/edge/feature_observation.h"
#include "mrvs/edge/imu_propagator.h"
#include "mrvs/geometry/se3.h"

namespace mrvs::edge {

struct StateOptions : config::OptionsEquality<StateOptions> {
  int max_clones = 11;                      ///< sliding-window size
  int max_slam = 100;                       ///< point features in the state at most
  bool calib_extrinsics = false;            ///< estimate T_b_c of both cameras
  bool calib_intrinsics = false;            ///< estimate the 8 camera parameters of both cameras
  bool calib_time_offset = false;           ///< estimate t_d (t_imu = t_cam + t_d)
  bool use_fej = true;                      ///< first-estimate Jacobians for clones and points
  double init_extrinsic_rot_sigma = 0.005;  ///< rad, when calibrating
  double init_extrinsic_pos_sigma = 0.015;  ///< m
  double init_focal_sigma = 1.0;            ///< px (fx fy cx cy)
  double init_distortion_sigma = 0.005;     ///< distortion coefficients
  double init_time_offset_sigma = 0.01;     ///< s

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("max_clones", max_clones, in_range(3, 64), "clones in the sliding window");
    v("max_slam", max_slam, in_range(0, 1000), "point features kept in the state");
    v("calib_extrinsics", calib_extrinsics, any(), "estimate the camera-IMU extrinsics online");
    v("calib_intrinsics", calib_intrinsics, any(), "estimate the camera intrinsics online");
    v("calib_time_offset", calib_time_offset, any(), "estimate the camera-IMU time offset online");
    v("use_fej", use_fej, any(), "first-estimate Jacobians");
    v("init_extrinsic_rot_sigma", init_extrinsic_rot_sigma, in_range(1e-6, 1.0), "prior sd, rad");
    v("init_extrinsic_pos_sigma", init_extrinsic_pos_sigma, in_range(1e-6, 1.0), "prior sd, m");
    v("init_focal_sigma", init_focal_sigma, in_range(1e-6, 100.0), "prior sd of fx fy cx cy, px");
    v("init_distortion_sigma", init_distortion_sigma, in_range(1e-9, 1.0), "prior sd of distortion");
    v("init_time_offset_sigma", init_time_offset_sigma, in_range(1e-6, 1.0), "prior sd of t_d, s");
  }
};

/// Where a variable's error lives in the covariance.
struct Slot {
  int offset = -1;  ///< first row / column; -1 when not in the state
  int size = 0;
  bool active() const { return offset >= 0; }
};

struct CloneState {
  SE3d T_w_b;  ///< IMU pose at the image time
  SE3d fej;
  Slot slot;
};

struct PointState {
  Vec3d p_w = Vec3d::Zero();
  Vec3d fej = Vec3d::Zero();
  Slot slot;
  TimestampNs added_ns = 0;  ///< image time it entered the state
  int update_failures = 0;   ///< chi-square rejections since it was added
  bool from_map = false;     ///< registered from a map point (issue 8), else triangulated
};

struct CameraState {
  SE3d T_b_c;                                        ///< current extrinsics
  std::shared_ptr<const camera::CameraModel> model;  ///< current intrinsics
  Slot extrinsic_slot;
  Slot intrinsic_slot;
};

class State {
 public:
  State(const StateOptions& options, const config::StereoRigCalibration& rig);

  const StateOptions& options() const { return options_; }
  int dim() const { return static_cast<int>(P.rows()); }

  ImuState imu;
  Slot imu_slot{0, 15};
  std::array<CameraState, 2> cams;
  double time_offset_s = 0.0;  ///< t_d: t_imu = t_cam + t_d
  Slot time_offset_slot;
  std::map<TimestampNs, CloneState> clones;  ///< keyed by the camera time of the image
  std::map<FeatureId, PointState> points;
  Eigen::MatrixXd P;  ///< covariance of the error state

  /// Appends a variable of `size` with zero covariance; returns its slot.
  Slot append(int size);
  /// Removes the rows and columns of `slot` and moves every later variable up.
  void remove(const Slot& slot);
  /// Every active slot, in covariance order.
  std::vector<Slot> slots() const;
  /// Applies the error `dx` (size dim()) to every variable.
  void apply_correction(const Eigen::VectorXd& dx);

  /// T_w_c of camera `cam` at clone `t_ns` (current estimates); the clone must exist.
  SE3d T_w_c(TimestampNs t_ns, int cam) const;
  /// Camera time of the newest clone (0 without clones).
  TimestampNs newest_clone_ns() const { return clones.empty() ? 0 : clones.rbegin()->first; }

 private:
  std::vector<Slot*> all_slots();
  StateOptions options_;
};

}  // namespace mrvs::edge
