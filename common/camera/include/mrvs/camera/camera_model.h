#pragma once
// Camera models: pinhole + radial-tangential (EuRoC, Kalibr "pinhole"/"radtan") and
// pinhole + equidistant (Kalibr "pinhole"/"equidistant", OpenCV fisheye / Kannala-Brandt).
//
// Coordinates
// - A point in the camera frame p_c = (x, y, z), z along the optical axis.
// - Normalised (undistorted) coordinates xn = (x / z, y / z).
// - Pixels uv are distorted image coordinates, (0, 0) the centre of the top-left pixel.
//
// Parameter vector (8 values for both models), in Kalibr order:
//   radtan:       [fx, fy, cx, cy, k1, k2, p1, p2]
//   equidistant:  [fx, fy, cx, cy, k1, k2, k3, k4]
// fx, fy, cx, cy are in pixels; the distortion coefficients are dimensionless.
//
// The concrete models live in pinhole_radtan.h and pinhole_equidistant.h; most code only
// needs this header and make_camera().
#include <memory>
#include <optional>
#include <string>

#include <Eigen/Core>

#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"

namespace mrvs::camera {

enum class DistortionModel { kRadTan, kEquidistant };

/// "radtan" / "equidistant" (the Kalibr names).
std::string to_string(DistortionModel model);
/// Accepts the Kalibr names and the EuRoC sensor.yaml spelling "radial-tangential", plus
/// "equi" and "fisheye" (case-insensitive). The error lists the accepted names.
StatusOr<DistortionModel> distortion_model_from_string(const std::string& name);

using Params = Eigen::Matrix<double, 8, 1>;

/// Number of entries of Params.
inline constexpr int kNumParams = 8;

/// Name of parameter `index` (0..7) of `model`: "fx", "fy", "cx", "cy", then "k1", "k2",
/// "p1", "p2" (radtan) or "k1".."k4" (equidistant). "?" for an index out of range.
std::string param_name(DistortionModel model, int index);

class CameraModel {
 public:
  virtual ~CameraModel() = default;

  virtual DistortionModel model() const = 0;
  /// A deep copy with the same model, size and parameters.
  virtual std::unique_ptr<CameraModel> clone() const = 0;
  int width() const { return width_; }
  int height() const { return height_; }
  const Params& params() const { return params_; }
  double fx() const { return params_[0]; }
  double fy() const { return params_[1]; }
  double cx() const { return params_[2]; }
  double cy() const { return params_[3]; }

  /// Normalised point (dimensionless) -> distorted pixel. Optional Jacobians with respect to
  /// xn (2x2, pixels) and to the 8 parameters (2x8, in the order of Params).
  virtual Vec2d distort(const Vec2d& xn, Mat2d* J_xn = nullptr,
                        Eigen::Matrix<double, 2, 8>* J_params = nullptr) const = 0;

  /// Distorted pixel -> normalised point (iterative Newton inversion of distort()). The
  /// result re-distorts to uv within 1e-9 pixels; InvalidArgument naming the pixel when uv
  /// is not finite, when the iteration does not converge (far outside the valid image area)
  /// or, for equidistant, when uv lies 90 degrees or more from the optical axis.
  virtual StatusOr<Vec2d> undistort(const Vec2d& uv) const = 0;

  /// Point in the camera frame (metres, or any length unit) -> pixel; nullopt when
  /// z < min_depth (same unit as p_c) or p_c is not finite. Optional Jacobian
  /// d uv / d p_c (2x3, pixels per unit length), only written when a pixel is returned.
  std::optional<Vec2d> project(const Vec3d& p_c, Eigen::Matrix<double, 2, 3>* J_p = nullptr,
                               double min_depth = 1e-6) const;

  /// Pixel -> unit bearing in the camera frame (z > 0). Errors as undistort().
  StatusOr<Vec3d> unproject(const Vec2d& uv) const;

  /// True when uv lies at least `border` pixels inside the image: pixel centres span
  /// [0, width - 1] x [0, height - 1], so the accepted region is
  /// [border, width - 1 - border] x [border, height - 1 - border] (bilinear interpolation is
  /// safe at border = 0). False for non-finite uv.
  bool in_image(const Vec2d& uv, double border = 0.0) const;

  /// One line, e.g. "radtan 752x480 fx=458.654 fy=457.296 cx=367.215 cy=248.375 d=[...]".
  std::string describe() const;

 protected:
  CameraModel(int width, int height, const Params& params)
      : width_(width), height_(height), params_(params) {}

 private:
  int width_;
  int height_;
  Params params_;
};

/// Checks what make_camera() requires: width, height > 0 (pixels), every parameter finite,
/// fx, fy > 0 (pixels) and the principal point inside the image area
/// cx in [-0.5, width - 0.5], cy in [-0.5, height - 0.5] (pixels). InvalidArgument naming the
/// offending value and its valid range otherwise.
Status validate_camera(DistortionModel model, int width, int height, const Params& params);

/// Builds a camera after validating its parameters (positive size, fx, fy > 0, finite
/// values, principal point inside the image). The error names the offending value.
StatusOr<std::unique_ptr<CameraModel>> make_camera(DistortionModel model, int width, int height,
                                                   const Params& params);

}  // namespace mrvs::camera
