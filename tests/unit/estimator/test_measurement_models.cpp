// Camera measurement Jacobians against numeric derivatives, and triangulation of known
// points.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/camera_measurement.h"
#include "mrvs/edge/triangulation.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

std::unique_ptr<camera::CameraModel> euroc_cam() {
  camera::Params p;
  p << 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  return std::move(*camera::make_camera(camera::DistortionModel::kRadTan, 752, 480, p));
}

SE3d plus(const SE3d& T, const Eigen::VectorXd& d) {  // [dtheta (right), dp]
  return SE3d(quat::plus_right(T.quaternion(), Vec3d(d.head<3>())), T.translation() + d.tail<3>());
}

TEST(CameraMeasurement, JacobiansMatchNumericDerivatives) {
  const auto cam = euroc_cam();
  const SE3d T_w_b(so3::exp_quat<double>(Vec3d(0.2, -0.1, 0.7)), Vec3d(1.0, -0.5, 1.2));
  const SE3d T_b_c(so3::exp_quat<double>(Vec3d(-1.5, 0.02, -1.55)), Vec3d(-0.02, -0.06, 0.01));
  const Vec3d p_w = T_w_b * (T_b_c * Vec3d(0.4, -0.3, 3.0));
  ProjectionJacobians J;
  const auto uv = project_point(T_w_b, T_b_c, *cam, p_w, &J);
  ASSERT_TRUE(uv.has_value());
  const double h = 1e-6;
  const auto clone = test::numeric_jacobian<double>(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        return *project_point(plus(T_w_b, d), T_b_c, *cam, p_w);
      },
      6, h);
  EXPECT_TRUE(test::matrices_near(J.clone, clone, 1e-4));
  const auto point = test::numeric_jacobian<double>(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        return *project_point(T_w_b, T_b_c, *cam, p_w + d);
      },
      3, h);
  EXPECT_TRUE(test::matrices_near(J.point, point, 1e-4));
  const auto extr = test::numeric_jacobian<double>(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        return *project_point(T_w_b, plus(T_b_c, d), *cam, p_w);
      },
      6, h);
  EXPECT_TRUE(test::matrices_near(J.extrinsic, extr, 1e-4));
  const auto intr = test::numeric_jacobian<double>(
      [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
        auto moved = camera::make_camera(cam->model(), 752, 480, cam->params() + d);
        return *project_point(T_w_b, T_b_c, **moved, p_w);
      },
      8, h);
  EXPECT_TRUE(test::matrices_near(J.intrinsic, intr, 1e-4));
  EXPECT_FALSE(project_point(T_w_b, T_b_c, *cam, T_w_b * (T_b_c * Vec3d(0.0, 0.0, -1.0))).has_value());
}

TEST(Triangulation, RecoversKnownPointsFromNoiselessAndNoisyViews) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> px(0.0, 1.0 / 458.0);  // 1 px
  TriangulationOptions options;
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3d p_w(u(rng) * 2.0, 4.0 + 2.0 * u(rng), u(rng));
    std::vector<BearingObservation> clean, noisy;
    for (int k = 0; k < 8; ++k) {  // a camera moving sideways 5 cm per view, looking along +y
      const SE3d T_w_c(
          so3::exp_quat<double>(Vec3d(-M_PI / 2, 0.0, 0.0) + 0.02 * Vec3d(u(rng), u(rng), u(rng))),
          Vec3d(0.05 * k, 0.0, 0.02 * u(rng)));
      const Vec3d p_c = T_w_c.inverse() * p_w;
      const Vec2d xn = p_c.head<2>() / p_c.z();
      clean.push_back({T_w_c, xn});
      noisy.push_back({T_w_c, xn + Vec2d(px(rng), px(rng))});
    }
    const auto a = triangulate(clean, options);
    ASSERT_TRUE(a.ok()) << a.status();
    EXPECT_LT((*a - p_w).norm(), 1e-7);
    const auto b = triangulate(noisy, options);
    ASSERT_TRUE(b.ok()) << b.status();
    // 1 px at 4 m depth with a 35 cm baseline: a few cm.
    EXPECT_LT((*b - p_w).norm(), 0.3);
  }
}

TEST(Triangulation, RefusesDegenerateGeometry) {
  const SE3d T(so3::exp_quat<double>(Vec3d(-M_PI / 2, 0.0, 0.0)), Vec3d::Zero());
  const Vec3d p_w(0.0, 5.0, 0.0);
  const Vec3d p_c = T.inverse() * p_w;
  const Vec2d xn = p_c.head<2>() / p_c.z();
  TriangulationOptions options;
  EXPECT_FALSE(triangulate({{T, xn}}, options).ok());           // one view
  EXPECT_FALSE(triangulate({{T, xn}, {T, xn}}, options).ok());  // no baseline
  SE3d T2 = T;
  T2.translation() = Vec3d(0.001, 0.0, 0.0);  // 1 mm for 5 m: too short
  EXPECT_FALSE(
      triangulate({{T, xn}, {T2, (T2.inverse() * p_w).head<2>() / (T2.inverse() * p_w).z()}}, options).ok());
}

}  // namespace
}  // namespace mrvs::edge
