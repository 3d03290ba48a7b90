#include "mrvs/test/euroc_sensor_yaml.h"

#include <stdexcept>

#include <fmt/format.h>

namespace mrvs::test {
namespace {

constexpr const char* kCameraTemplate = R"(%YAML:1.0
# General sensor definitions.
sensor_type: camera
comment: VI-Sensor cam{cam} (MT9M034)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [{T_BS}]

# Camera specific definitions.
rate_hz: 20
resolution: [{w}, {h}]
camera_model: pinhole
intrinsics: [{fu}, {fv}, {cu}, {cv}] #fu, fv, cu, cv
distortion_model: radial-tangential
distortion_coefficients: [{dist}]
)";

// Row-major T_BS data, laid out over four lines as in the dataset.
constexpr const char* kCam0TBS =
    "0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\n"
    "         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\n"
    "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\n"
    "         0.0, 0.0, 0.0, 1.0";
constexpr const char* kCam1TBS =
    "0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,\n"
    "         0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,\n"
    "        -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,\n"
    "         0.0, 0.0, 0.0, 1.0";
constexpr const char* kCam0Dist = "-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05";
constexpr const char* kCam1Dist = "-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05";

constexpr const char* kImu = R"(#Default imu sensor yaml file
sensor_type: imu
comment: VI-Sensor IMU (ADIS16448)

# Sensor extrinsics wrt. the body-frame.
T_BS:
  cols: 4
  rows: 4
  data: [1.0, 0.0, 0.0, 0.0,
         0.0, 1.0, 0.0, 0.0,
         0.0, 0.0, 1.0, 0.0,
         0.0, 0.0, 0.0, 1.0]
rate_hz: 200

# inertial sensor noise model parameters (static)
gyroscope_noise_density: 1.6968e-04     # [ rad / s / sqrt(Hz) ]   ( gyro "white noise" )
gyroscope_random_walk: 1.9393e-05       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )
accelerometer_noise_density: 2.0000e-3  # [ m / s^2 / sqrt(Hz) ]  ( accel "white noise" )
accelerometer_random_walk: 3.0000e-3    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )
)";

void check_camera(int cam) {
  if (cam != 0 && cam != 1)
    throw std::invalid_argument(fmt::format("EuRoC has cam0 and cam1, not cam{}", cam));
}

}  // namespace

std::array<double, 4> euroc_intrinsics(int cam) {
  check_camera(cam);
  return cam == 0 ? std::array<double, 4>{458.654, 457.296, 367.215, 248.375}
                  : std::array<double, 4>{457.587, 456.134, 379.999, 255.238};
}

std::string euroc_camera_sensor_yaml(int cam) {
  return euroc_camera_sensor_yaml(cam, 752, 480, euroc_intrinsics(cam));
}

std::string euroc_camera_sensor_yaml(int cam, int width, int height,
                                     const std::array<double, 4>& intrinsics) {
  check_camera(cam);
  return fmt::format(fmt::runtime(kCameraTemplate), fmt::arg("cam", cam),
                     fmt::arg("T_BS", cam == 0 ? kCam0TBS : kCam1TBS), fmt::arg("w", width),
                     fmt::arg("h", height), fmt::arg("fu", intrinsics[0]), fmt::arg("fv", intrinsics[1]),
                     fmt::arg("cu", intrinsics[2]), fmt::arg("cv", intrinsics[3]),
                     fmt::arg("dist", cam == 0 ? kCam0Dist : kCam1Dist));
}

std::string euroc_imu_sensor_yaml(bool opencv_header) {
  return opencv_header ? std::string("%YAML:1.0\n") + kImu : std::string(kImu);
}

}  // namespace mrvs::test
