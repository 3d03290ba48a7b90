#pragma once
// Pinhole + equidistant distortion (Kannala-Brandt as Kalibr "equidistant", OpenCV fisheye).
// Parameters [fx, fy, cx, cy, k1, k2, k3, k4].
//
//   r = |xn|,  theta = atan(r)  (angle from the optical axis, radians)
//   theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//   xd = (theta_d / r) xn   (-> xn as r -> 0),  u = fx xd_x + cx,  v = fy xd_y + cy
#include <memory>

#include "mrvs/camera/camera_model.h"

namespace mrvs::camera {

class PinholeEquidistant final : public CameraModel {
 public:
  /// Validated construction (see validate_camera()).
  static StatusOr<std::unique_ptr<PinholeEquidistant>> create(int width, int height, const Params& params);

  DistortionModel model() const override { return DistortionModel::kEquidistant; }
  std::unique_ptr<CameraModel> clone() const override;

  /// Smooth through r = 0 (series expansions near the optical axis), Jacobians included.
  Vec2d distort(const Vec2d& xn, Mat2d* J_xn = nullptr,
                Eigen::Matrix<double, 2, 8>* J_params = nullptr) const override;

  /// Solves theta from theta_d = |(uv - c) / f| by 1D Newton (safeguarded by bisection on
  /// [0, max_monotonic_theta()]), then xn = tan(theta) xd / theta_d.
  /// Error when theta >= pi/2 (the pixel sees a direction 90 degrees or more off axis) or
  /// theta >= max_monotonic_theta() (the folded-over part of the model).
  StatusOr<Vec2d> undistort(const Vec2d& uv) const override;

  /// Angle off axis (radians, at most pi/2) up to which theta_d(theta) increases: the first
  /// zero of d theta_d / d theta in (0, pi/2], or pi/2 when there is none.
  double max_monotonic_theta() const { return max_theta_; }

  /// Distortion in normalised coordinates only: xn -> xd, with the optional 2x2 Jacobian
  /// d xd / d xn (dimensionless). `dist` = [k1, k2, k3, k4].
  static Vec2d distort_normalized(const Vec2d& xn, const Eigen::Vector4d& dist, Mat2d* J_xn = nullptr);

  /// theta_d for an angle theta (radians) off the optical axis: the distorted normalised
  /// radius. `dist` = [k1, k2, k3, k4].
  static double theta_d(double theta, const Eigen::Vector4d& dist);

 private:
  PinholeEquidistant(int width, int height, const Params& params);

  double max_theta_;
};

}  // namespace mrvs::camera
