#pragma once
// Dynamic initialisation (algorithm.md 6.1, the moving case): from a window of stereo
// feature frames and the IMU samples over it, the IMU state at the newest frame in a
// gravity-aligned frame, without assuming the platform is still.
//
//   1. Gyroscope bias and rotations: IMU pre-integration between the window's frames
//      against the rotations the features imply.
//   2. Linear solve: velocities, gravity (with its magnitude enforced) and the feature
//      geometry from pre-integration and the feature bearings (stereo gives the metric
//      scale).
//   3. Ceres refinement (maximum likelihood) of poses, velocities, biases and features with
//      pre-integration and reprojection factors; covariance from ceres::Covariance.
#include <string>
#include <vector>

#include "mrvs/config/calibration.h"
#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/edge/feature_observation.h"
#include "mrvs/edge/imu_propagator.h"
#include "mrvs/edge/triangulation.h"
#include "mrvs/io/types.h"

namespace mrvs::edge {

struct DynamicInitOptions : config::OptionsEquality<DynamicInitOptions> {
  int num_poses = 6;                ///< frames of the window used (spread over it)
  double min_rotation_deg = 10.0;   ///< rotation from the oldest frame needed (EuRoC 10, KAIST 5)
  int min_features = 25;            ///< features seen in most of the used frames
  double max_gravity_error = 1e-3;  ///< relative | |g| - g | left by the constrained linear solve
  int max_iterations = 50;          ///< Ceres iterations
  double max_solver_time_s = 0.05;
  double sigma_px = 1.0;                ///< reprojection noise, px
  int max_features = 150;               ///< features in the refinement (the longest tracks)
  double outlier_px = 3.0;              ///< reprojection residual that drops an observation, px
  double max_free_gravity_error = 0.1;  ///< relative | |g| - g | of the unconstrained linear solve
  double prior_gyro_bias = 0.1;         ///< sigma of the zero-mean gyro bias prior, rad/s
  double prior_accel_bias = 0.2;        ///< sigma of the zero-mean accelerometer bias prior, m/s^2
  double inflate_orientation = 10.0;    ///< covariance inflation of the result (reference code)
  double inflate_velocity = 100.0;
  double inflate_gyro_bias = 10.0;
  double inflate_accel_bias = 100.0;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("num_poses", num_poses, in_range(3, 50), "frames of the window used");
    v("min_rotation_deg", min_rotation_deg, in_range(0.0, 180.0), "rotation over the window needed, deg");
    v("min_features", min_features, in_range(5, 1000), "features needed across the window");
    v("max_gravity_error", max_gravity_error, in_range(1e-9, 1.0),
      "relative gravity residual of the linear solve");
    v("max_iterations", max_iterations, in_range(0, 1000), "Ceres iterations");
    v("max_solver_time_s", max_solver_time_s, in_range(0.001, 60.0), "Ceres time budget, s");
    v("sigma_px", sigma_px, in_range(0.01, 100.0), "reprojection noise, px");
    v("max_features", max_features, in_range(5, 5000), "features in the refinement (longest tracks)");
    v("outlier_px", outlier_px, in_range(0.1, 1000.0), "reprojection residual that drops an observation, px");
    v("max_free_gravity_error", max_free_gravity_error, in_range(1e-6, 10.0),
      "relative |g| error of the unconstrained linear solve");
    v("prior_gyro_bias", prior_gyro_bias, in_range(1e-6, 100.0), "sigma of the gyro bias prior, rad/s");
    v("prior_accel_bias", prior_accel_bias, in_range(1e-6, 100.0),
      "sigma of the accelerometer bias prior, m/s^2");
    v("inflate_orientation", inflate_orientation, in_range(1.0, 1e6), "covariance inflation");
    v("inflate_velocity", inflate_velocity, in_range(1.0, 1e6), "covariance inflation");
    v("inflate_gyro_bias", inflate_gyro_bias, in_range(1.0, 1e6), "covariance inflation");
    v("inflate_accel_bias", inflate_accel_bias, in_range(1.0, 1e6), "covariance inflation");
  }
};

/// What an initialiser produces: the IMU state at the newest frame of its window, in a
/// frame whose z axis is up (gravity (0, 0, -g)), position 0, yaw as found, and its
/// covariance (15 x 15, the order of imu_propagator.h).
struct InitializationResult {
  ImuState imu;
  Mat15d P = Mat15d::Identity();
  std::string method;  ///< "static" or "dynamic"
  std::string detail;  ///< one line for the log (e.g. iterations, residuals)
};

/// Attempts a dynamic initialisation from `frames` (time-ordered, camera clock) and `imu`
/// (covering them). `g` is the gravity magnitude (m/s^2). FailedPrecondition saying why
/// when the window does not allow it yet (too little rotation, too few features, the solve
/// is ill-conditioned): the caller waits for more data. `triangulation` bounds the stereo and
/// window points (the estimator's: a street's far points need a larger baseline ratio).
StatusOr<InitializationResult> dynamic_initialize(const std::vector<FeatureFrame>& frames,
                                                  const std::vector<io::ImuSample>& imu,
                                                  const config::StereoRigCalibration& rig,
                                                  const ImuNoise& noise, double g,
                                                  const DynamicInitOptions& options,
                                                  const TriangulationOptions& triangulation = {});

}  // namespace mrvs::edge
