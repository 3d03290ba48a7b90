#pragma once
// Per-camera ray tables (simulator.md section 4.1): the unit bearing of every pixel centre
// and of the 2x2 subsample pattern, computed once from the render-truth camera model, plus
// the angular footprint of each pixel for mip-level selection.
//
// Pixel convention: the centre of pixel (u, v) is at integer (u, v) (as in OpenCV and KLT);
// the subsamples sit at (u -+ 0.25, v -+ 0.25).
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "mrvs/camera/camera_model.h"
#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"

namespace mrvs::sim {

/// Unit bearings in the camera frame c (z along the optical axis), float32.
class RayTable {
 public:
  /// Number of subsamples per pixel (2x2).
  static constexpr int kSubsamples = 4;
  /// Offset (pixels) of subsample k from the pixel centre: k = 0 (-,-), 1 (+,-), 2 (-,+),
  /// 3 (+,+), each component 0.25 px.
  static Vec2d subsample_offset(int k);

  /// Builds the table of `camera` (undistort() of every pixel centre and subsample,
  /// parallel over rows). InvalidArgument naming the pixel when a pixel cannot be
  /// undistorted (e.g. a lens whose distortion folds over inside the image).
  static StatusOr<RayTable> build(const camera::CameraModel& camera);

  RayTable() = default;

  int width() const { return width_; }
  int height() const { return height_; }
  /// Bearing through the centre of pixel (u, v); 0 <= u < width, 0 <= v < height.
  const Eigen::Vector3f& center(int u, int v) const { return centers_[index(u, v)]; }
  /// Bearing through subsample k (0..3) of pixel (u, v).
  const Eigen::Vector3f& subsample(int u, int v, int k) const {
    return subsamples_[kSubsamples * index(u, v) + static_cast<std::size_t>(k)];
  }
  /// Angular size of pixel (u, v), radians: the geometric mean of its angular width and
  /// height (measured between the subsample rays, which are half a pixel apart).
  float pixel_angle(int u, int v) const { return angles_[index(u, v)]; }

  /// Largest |distort(ray) - pixel| over every centre and subsample of the table, pixels
  /// (the float32 round trip through `camera`, which must be the camera it was built from).
  double max_round_trip_error(const camera::CameraModel& camera) const;

 private:
  std::size_t index(int u, int v) const {
    return static_cast<std::size_t>(v) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(u);
  }

  int width_ = 0;
  int height_ = 0;
  std::vector<Eigen::Vector3f> centers_;     ///< width * height
  std::vector<Eigen::Vector3f> subsamples_;  ///< 4 * width * height, pixel-major
  std::vector<float> angles_;                ///< width * height, radians
};

}  // namespace mrvs::sim
