#pragma once
// The camera measurement model of every updater (algorithm.md 3.5): a world point p_w seen
// in camera c of the clone T_w_b,
//   p_b = R_w_b^T (p_w - p_w_b),  p_c = R_b_c^T (p_b - p_b_c),  uv = distort(p_c.xy / p_c.z),
// in raw (distorted) pixels, with Jacobians for the error conventions of state.h.
#include <optional>

#include <Eigen/Core>

#include "mrvs/camera/camera_model.h"
#include "mrvs/geometry/se3.h"

namespace mrvs::edge {

struct ProjectionJacobians {
  Eigen::Matrix<double, 2, 6> clone;      ///< d uv / d [dtheta_b, dp_w_b]
  Eigen::Matrix<double, 2, 3> point;      ///< d uv / d p_w
  Eigen::Matrix<double, 2, 6> extrinsic;  ///< d uv / d [dtheta_b_c, dp_b_c]
  Eigen::Matrix<double, 2, 8> intrinsic;  ///< d uv / d camera parameters
};

/// Pixel of p_w; nullopt when the point is less than `min_depth` (m) in front of the
/// camera. Jacobians (optional) are only written when a pixel is returned.
std::optional<Vec2d> project_point(const SE3d& T_w_b, const SE3d& T_b_c, const camera::CameraModel& cam,
                                   const Vec3d& p_w, ProjectionJacobians* J = nullptr,
                                   double min_depth = 1e-3);

}  // namespace mrvs::edge
