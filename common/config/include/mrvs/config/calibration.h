#pragma once
// Sensor calibration of a stereo camera + IMU rig, kept apart from tuning files.
//
// Frames: b = IMU body frame, c = camera frame. T_b_c maps camera points into the body
// frame (EuRoC's sensor.yaml T_BS for a camera; Kalibr stores T_cam_imu = T_c_b).
#include <array>
#include <filesystem>
#include <memory>
#include <string>

#include "mrvs/camera/camera_model.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"

namespace mrvs::config {

struct YamlDocument;

struct CameraCalibration {
  std::string name;                                  ///< "cam0", "cam1"
  std::shared_ptr<const camera::CameraModel> model;  ///< intrinsics, distortion and size
  SE3d T_b_c;                                        ///< camera -> IMU body
  double rate_hz = 0.0;                              ///< 0 when the file does not say
  DurationNs time_offset_ns = 0;                     ///< t_imu = t_cam + offset (Kalibr timeshift_cam_imu)
};

/// Continuous-time IMU noise densities (EuRoC / Kalibr imu.yaml naming and units).
struct ImuCalibration {
  double gyroscope_noise_density = 0.0;      ///< rad / s / sqrt(Hz)
  double gyroscope_random_walk = 0.0;        ///< rad / s^2 / sqrt(Hz)
  double accelerometer_noise_density = 0.0;  ///< m / s^2 / sqrt(Hz)
  double accelerometer_random_walk = 0.0;    ///< m / s^3 / sqrt(Hz)
  double rate_hz = 0.0;                      ///< nominal sample rate
};

struct StereoRigCalibration {
  std::array<CameraCalibration, 2> cameras;
  ImuCalibration imu;

  /// Transform from right camera to left camera frame: T_c0_c1 = T_b_c0^-1 * T_b_c1.
  SE3d T_c0_c1() const { return cameras[0].T_b_c.inverse() * cameras[1].T_b_c; }
  /// Multi-line human-readable summary (printed at start-up).
  std::string describe() const;
};

/// EuRoC `mav0/camN/sensor.yaml` (with or without the OpenCV `%YAML:1.0` line).
StatusOr<CameraCalibration> load_euroc_camera_yaml(const std::filesystem::path& path);
/// EuRoC `mav0/imu0/sensor.yaml`.
StatusOr<ImuCalibration> load_euroc_imu_yaml(const std::filesystem::path& path);
/// T_BS of any EuRoC `mav0/<sensor>/sensor.yaml` document (e.g. gnss0): the sensor frame s in
/// the IMU body frame, T_b_s ({rows: 4, cols: 4, data: [16 numbers, row-major]}, checked to be
/// a rigid transform). Errors name the file, line and key.
StatusOr<SE3d> read_euroc_T_BS(const YamlDocument& doc);
/// Kalibr camchain (`camchain-imucam.yaml`: cam0/cam1 with T_cam_imu, intrinsics, ...).
StatusOr<std::array<CameraCalibration, 2>> load_kalibr_camchain(const std::filesystem::path& path);
/// Kalibr IMU file (`imu.yaml`: imu0 with noise densities and update_rate).
StatusOr<ImuCalibration> load_kalibr_imu(const std::filesystem::path& path);

}  // namespace mrvs::config
