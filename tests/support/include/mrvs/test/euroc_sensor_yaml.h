#pragma once
// The real EuRoC MAV `sensor.yaml` files (mav0/cam0, cam1, imu0), in the dataset's own
// layout: OpenCV "%YAML:1.0" first line, T_BS data list over several lines, trailing
// comments. Shared by every test that needs a realistic EuRoC folder.
#include <array>
#include <string>

namespace mrvs::test {

/// Intrinsics [fu, fv, cu, cv] of the real EuRoC camera `cam` (0 or 1).
std::array<double, 4> euroc_intrinsics(int cam);

/// The real mav0/camN/sensor.yaml of EuRoC (752x480, real intrinsics).
std::string euroc_camera_sensor_yaml(int cam);

/// The same file with another image size and intrinsics (for tiny test images); the
/// extrinsics and distortion stay the real ones.
std::string euroc_camera_sensor_yaml(int cam, int width, int height, const std::array<double, 4>& intrinsics);

/// The real mav0/imu0/sensor.yaml of EuRoC (with the "%YAML:1.0" line when `opencv_header`).
std::string euroc_imu_sensor_yaml(bool opencv_header = false);

}  // namespace mrvs::test
