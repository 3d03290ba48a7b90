#include "mrvs/edge/camera_measurement.h"

#include "mrvs/geometry/so3.h"

namespace mrvs::edge {

std::optional<Vec2d> project_point(const SE3d& T_w_b, const SE3d& T_b_c, const camera::CameraModel& cam,
                                   const Vec3d& p_w, ProjectionJacobians* J, double min_depth) {
  const Mat3d R_w_b = T_w_b.rotation_matrix();
  const Mat3d R_b_c = T_b_c.rotation_matrix();
  const Vec3d p_b = R_w_b.transpose() * (p_w - T_w_b.translation());
  const Vec3d p_c = R_b_c.transpose() * (p_b - T_b_c.translation());
  if (!(p_c.z() >= min_depth)) return std::nullopt;
  const Vec2d xn = p_c.head<2>() / p_c.z();
  Mat2d J_xn;
  Eigen::Matrix<double, 2, 8> J_params;
  const Vec2d uv = cam.distort(xn, J ? &J_xn : nullptr, J ? &J_params : nullptr);
  if (J == nullptr) return uv;
  Eigen::Matrix<double, 2, 3> J_proj;  // d xn / d p_c
  J_proj << 1.0 / p_c.z(), 0.0, -p_c.x() / (p_c.z() * p_c.z()), 0.0, 1.0 / p_c.z(),
      -p_c.y() / (p_c.z() * p_c.z());
  const Eigen::Matrix<double, 2, 3> J_pc = J_xn * J_proj;
  const Eigen::Matrix<double, 2, 3> J_pb = J_pc * R_b_c.transpose();
  J->clone.leftCols<3>() = J_pb * skew<double>(p_b);
  J->clone.rightCols<3>() = -J_pb * R_w_b.transpose();
  J->point = J_pb * R_w_b.transpose();
  J->extrinsic.leftCols<3>() = J_pc * skew<double>(p_c);
  J->extrinsic.rightCols<3>() = -J_pc * R_b_c.transpose();
  J->intrinsic = J_params;
  return uv;
}

}  // namespace mrvs::edge
