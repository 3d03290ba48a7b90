#pragma once
// Cameras and sample points shared by the camera tests.
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/camera/camera_model.h"
#include "mrvs/geometry/angles.h"

namespace mrvs::camera::test {

struct CameraCase {
  std::string name;
  DistortionModel model;
  int width;
  int height;
  Params params;
};

inline Params make_params(double fx, double fy, double cx, double cy, double d0, double d1, double d2,
                          double d3) {
  Params p;
  p << fx, fy, cx, cy, d0, d1, d2, d3;
  return p;
}

/// EuRoC MAV cam0 (sensor.yaml).
inline CameraCase euroc_cam0() {
  return {
      "EurocCam0", DistortionModel::kRadTan, 752, 480,
      make_params(458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05)};
}

/// TUM-VI-like 512x512 fisheye with a field of view above 180 degrees (corners unusable).
inline CameraCase tumvi_cam0() {
  return {"TumViCam0", DistortionModel::kEquidistant, 512, 512,
          make_params(190.97847715128717, 190.9733070521226, 254.93170605935475, 256.8974428996504,
                      0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
                      0.00020293673591811182)};
}

/// Strong radial and tangential terms, so that every term of the model matters.
inline CameraCase strong_radtan() {
  return {"StrongRadtan", DistortionModel::kRadTan, 640, 480,
          make_params(400.0, 410.0, 322.5, 236.25, -0.3, 0.1, 0.01, -0.008)};
}

/// Strong equidistant coefficients; theta_d stays increasing up to 90 degrees.
inline CameraCase strong_equidistant() {
  return {"StrongEquidistant", DistortionModel::kEquidistant, 640, 480,
          make_params(300.0, 295.0, 318.0, 242.0, 0.1, -0.05, 0.02, -0.002)};
}

inline std::vector<CameraCase> all_cases() {
  return {euroc_cam0(), tumvi_cam0(), strong_radtan(), strong_equidistant()};
}

inline std::string case_name(const ::testing::TestParamInfo<CameraCase>& info) { return info.param.name; }

/// make_camera that must succeed (fails the test otherwise and returns nullptr).
inline std::unique_ptr<CameraModel> build(const CameraCase& c) {
  auto cam = make_camera(c.model, c.width, c.height, c.params);
  EXPECT_TRUE(cam.ok()) << cam.status();
  if (!cam.ok()) return nullptr;
  return std::move(cam).value();
}

/// Normalised point at angle `theta` (radians) off axis, direction `phi`.
inline Vec2d from_angles(double theta, double phi) {
  return std::tan(theta) * Vec2d(std::cos(phi), std::sin(phi));
}

/// Sample normalised points: the optical axis itself, a log sweep of radii 1e-12..1 in
/// random directions (near-axis behaviour), random pixels of the image undistorted, pixels
/// near the four corners undistorted (when possible) and, for equidistant, bearings up to
/// 89 degrees off axis.
inline std::vector<Vec2d> sample_points(const CameraModel& cam, std::mt19937& rng, int n_random) {
  std::uniform_real_distribution<double> angle(0.0, 2.0 * kPi);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec2d> pts = {Vec2d::Zero()};
  for (int i = 0; i <= 240; ++i) {
    const double r = std::pow(10.0, -12.0 + 12.0 * i / 240.0);
    const double phi = angle(rng);
    pts.emplace_back(r * std::cos(phi), r * std::sin(phi));
  }
  auto add_pixel = [&](const Vec2d& uv) {
    auto xn = cam.undistort(uv);
    if (xn.ok()) pts.push_back(*xn);
  };
  for (int i = 0; i < n_random; ++i) {
    add_pixel(Vec2d(unit(rng) * (cam.width() - 1), unit(rng) * (cam.height() - 1)));
  }
  for (const Vec2d& corner : {Vec2d(0, 0), Vec2d(cam.width() - 1, 0), Vec2d(0, cam.height() - 1),
                              Vec2d(cam.width() - 1, cam.height() - 1)}) {
    for (int i = 0; i < 10; ++i) {
      const Vec2d offset(3.0 * unit(rng), 3.0 * unit(rng));
      add_pixel(corner +
                Vec2d(corner.x() > 0 ? -offset.x() : offset.x(), corner.y() > 0 ? -offset.y() : offset.y()));
    }
  }
  if (cam.model() == DistortionModel::kEquidistant) {
    for (int i = 0; i < n_random; ++i) {
      pts.push_back(from_angles(unit(rng) * 89.0 * kPi / 180.0, angle(rng)));
    }
  }
  return pts;
}

}  // namespace mrvs::camera::test
