#pragma once
// Pinhole + radial-tangential distortion (OpenCV's 4-coefficient model, Kalibr "radtan",
// EuRoC "radial-tangential"). Parameters [fx, fy, cx, cy, k1, k2, p1, p2].
//
//   r2 = x^2 + y^2,  radial = 1 + k1 r2 + k2 r2^2
//   xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
//   yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
//   u = fx xd + cx,  v = fy yd + cy
#include <memory>

#include "mrvs/camera/camera_model.h"

namespace mrvs::camera {

class PinholeRadtan final : public CameraModel {
 public:
  /// Validated construction (see validate_camera()).
  static StatusOr<std::unique_ptr<PinholeRadtan>> create(int width, int height, const Params& params);

  DistortionModel model() const override { return DistortionModel::kRadTan; }
  std::unique_ptr<CameraModel> clone() const override;

  Vec2d distort(const Vec2d& xn, Mat2d* J_xn = nullptr,
                Eigen::Matrix<double, 2, 8>* J_params = nullptr) const override;

  /// Newton iteration with the analytic 2x2 Jacobian (with step halving when the residual
  /// grows), started at (uv - c) / f. Solutions with |xn| >= max_monotonic_radius() lie on
  /// the folded-over branch of the model and are rejected.
  StatusOr<Vec2d> undistort(const Vec2d& uv) const override;

  /// Normalised radius where the radial part r (1 + k1 r^2 + k2 r^4) stops increasing (the
  /// image folds over beyond it); +infinity when it increases everywhere (e.g. EuRoC).
  double max_monotonic_radius() const { return max_radius_; }

  /// Distortion in normalised coordinates only: xn -> (xd, yd) above, with the optional
  /// 2x2 Jacobian d xd / d xn (dimensionless). `dist` = [k1, k2, p1, p2].
  static Vec2d distort_normalized(const Vec2d& xn, const Eigen::Vector4d& dist, Mat2d* J_xn = nullptr);

 private:
  PinholeRadtan(int width, int height, const Params& params);

  double max_radius_;
};

}  // namespace mrvs::camera
