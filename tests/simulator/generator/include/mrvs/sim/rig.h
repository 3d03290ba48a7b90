#pragma once
// The two built-in sensor rigs the simulator renders and writes: the real EuRoC MAV
// VI-Sensor (indoor profile) and a KAIST-Urban-like car rig (outdoor profile), plus the
// writers of their EuRoC-ASL sensor.yaml files.
#include <array>
#include <string>

#include "mrvs/camera/camera_model.h"
#include "mrvs/config/calibration.h"
#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"
#include "mrvs/sim/gnss_sim.h"

namespace mrvs::sim {

struct RigCamera {
  std::string name;                ///< "cam0" / "cam1"
  std::string comment;             ///< sensor.yaml comment, e.g. "VI-Sensor cam0 (MT9M034)"
  Mat4d T_BS = Mat4d::Identity();  ///< T_b_c exactly as written (orthonormal rotation)
  int width = 0;
  int height = 0;
  double rate_hz = 0.0;
  camera::DistortionModel model = camera::DistortionModel::kRadTan;
  camera::Params params = camera::Params::Zero();  ///< fx fy cx cy k1 k2 p1 p2
};

struct RigImu {
  std::string comment;
  double rate_hz = 0.0;
  double gyroscope_noise_density = 0.0;      ///< rad / s / sqrt(Hz)
  double gyroscope_random_walk = 0.0;        ///< rad / s^2 / sqrt(Hz)
  double accelerometer_noise_density = 0.0;  ///< m / s^2 / sqrt(Hz)
  double accelerometer_random_walk = 0.0;    ///< m / s^3 / sqrt(Hz)
  double gravity_mps2 = 9.81;                ///< magnitude used by the simulation
};

struct Rig {
  std::string name;  ///< "euroc" / "kaist_like"
  std::array<RigCamera, 2> cameras;
  RigImu imu;
  /// Camera frames per IMU sample: cameras tick on every N-th IMU stamp.
  int imu_samples_per_frame() const;
  /// The rig as the project's calibration type (camera models built and validated).
  StatusOr<config::StereoRigCalibration> calibration() const;
};

/// The real EuRoC MAV calibration (752x480 radtan, 20 Hz, IMU 200 Hz, baseline 0.110 m).
Rig euroc_rig();
/// KAIST Urban-like: 1280x560 radtan, 10 Hz, baseline 0.475 m, IMU 100 Hz (simulator.md
/// 1.11). The published 5-decimal rotations are re-orthonormalised (SVD) before use.
Rig kaist_like_rig();

/// Nearest rotation matrix (SVD, det +1) of the top-left 3x3 block; keeps the translation.
Mat4d orthonormalized(const Mat4d& T);

/// mav0/camN/sensor.yaml in the real EuRoC layout (no "%YAML:1.0" line).
std::string camera_sensor_yaml(const RigCamera& camera);
/// mav0/imu0/sensor.yaml with the densities actually simulated.
std::string imu_sensor_yaml(const RigImu& imu);
/// mav0/state_groundtruth_estimate0/sensor.yaml.
std::string groundtruth_sensor_yaml(const std::string& comment);
/// mav0/pointcloud0/sensor.yaml.
std::string pointcloud_sensor_yaml(const std::string& comment);
/// mav0/gnss0/sensor.yaml (format in mrvs/io/gnss.h): T_BS = the antenna at
/// gnss.lever_arm_m, the rate and the stationary sigmas of the error actually simulated.
std::string gnss_sensor_yaml(const GnssSimOptions& gnss, const std::string& comment);

}  // namespace mrvs::sim
