// Every analytic Jacobian against central differences (mrvs::test::numeric_jacobian).
#include <algorithm>
#include <cmath>
#include <complex>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "camera_test_cases.h"
#include "mrvs/camera/camera_model.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::camera {
namespace {

using test::CameraCase;
using VecX = Eigen::VectorXd;

// Central differences with h = 1e-6 on values of a few hundred pixels: round-off
// ~1e-7, truncation negligible. Scaled with the size of the Jacobian entries.
double tolerance(const Eigen::MatrixXd& J) { return 1e-5 * std::max(1.0, J.cwiseAbs().maxCoeff() / 100.0); }

// Reference distortion in normalised coordinates, written straight from the model equations
// and templated so that it can run on complex numbers (complex-step differentiation).
template <typename T>
Eigen::Matrix<T, 2, 1> reference_distort(DistortionModel model, const Params& p,
                                         const Eigen::Matrix<T, 2, 1>& xn) {
  const T x = xn.x(), y = xn.y();
  const T r2 = x * x + y * y;
  if (model == DistortionModel::kRadTan) {
    const T radial = 1.0 + p[4] * r2 + p[5] * r2 * r2;
    return {x * radial + 2.0 * p[6] * x * y + p[7] * (r2 + 2.0 * x * x),
            y * radial + p[6] * (r2 + 2.0 * y * y) + 2.0 * p[7] * x * y};
  }
  const T r = std::sqrt(r2);
  const T theta = std::atan(r);
  const T t2 = theta * theta;
  const T theta_d =
      theta * (1.0 + p[4] * t2 + p[5] * t2 * t2 + p[6] * t2 * t2 * t2 + p[7] * t2 * t2 * t2 * t2);
  return {theta_d / r * x, theta_d / r * y};
}

// d xd / d xn by complex steps: exact to rounding (no subtractive cancellation), so it
// checks the Jacobian far more tightly than central differences. Needs xn != 0.
Mat2d complex_step_jacobian(DistortionModel model, const Params& p, const Vec2d& xn) {
  using C = std::complex<double>;
  const double h = 1e-20 * std::max(xn.norm(), 1e-100);
  Mat2d J;
  for (int i = 0; i < 2; ++i) {
    Eigen::Matrix<C, 2, 1> z(C(xn.x(), 0.0), C(xn.y(), 0.0));
    z[i] += C(0.0, h);
    const Eigen::Matrix<C, 2, 1> d = reference_distort<C>(model, p, z);
    J.col(i) << d.x().imag() / h, d.y().imag() / h;
  }
  return J;
}

class CameraJacobianTest : public ::testing::TestWithParam<CameraCase> {
 protected:
  void SetUp() override {
    cam_ = test::build(GetParam());
    ASSERT_NE(cam_, nullptr);
    std::mt19937 rng(1234);
    points_ = test::sample_points(*cam_, rng, 300);
    ASSERT_GT(points_.size(), 500u);
  }
  std::unique_ptr<CameraModel> cam_;
  std::vector<Vec2d> points_;
};

TEST_P(CameraJacobianTest, DistortWrtNormalisedPoint) {
  for (const Vec2d& xn : points_) {
    Mat2d J;
    const Vec2d uv = cam_->distort(xn, &J);
    ASSERT_TRUE(uv.allFinite()) << xn.transpose();
    const Eigen::MatrixXd J_num = mrvs::test::numeric_jacobian<double>(
        [&](const VecX& d) -> VecX { return cam_->distort(xn + d); }, 2, mrvs::test::default_step<double>());
    EXPECT_MATRIX_NEAR(J, J_num, tolerance(J_num)) << "xn = " << xn.transpose() << " |xn| = " << xn.norm();
  }
}

TEST_P(CameraJacobianTest, DistortWrtNormalisedPointMatchesComplexStep) {
  const CameraCase& c = GetParam();
  const Vec2d f(cam_->fx(), cam_->fy());
  for (const Vec2d& xn : points_) {
    if (xn.norm() == 0.0) continue;
    Mat2d J;
    const Vec2d uv = cam_->distort(xn, &J);
    const Vec2d xd_ref = reference_distort<double>(c.model, c.params, xn);
    EXPECT_MATRIX_NEAR(uv, (f.cwiseProduct(xd_ref) + Vec2d(cam_->cx(), cam_->cy())).eval(), 1e-9);
    const Mat2d J_ref = f.asDiagonal() * complex_step_jacobian(c.model, c.params, xn);
    // Relative to the focal length: about 1e-13 pixels per normalised unit.
    EXPECT_MATRIX_NEAR(J, J_ref, 1e-13 * f.maxCoeff())
        << "xn = " << xn.transpose() << " |xn| = " << xn.norm();
  }
}

TEST_P(CameraJacobianTest, DistortWrtParameters) {
  const CameraCase& c = GetParam();
  for (const Vec2d& xn : points_) {
    Eigen::Matrix<double, 2, 8> J;
    const Vec2d uv = cam_->distort(xn, nullptr, &J);
    const Eigen::MatrixXd J_num = mrvs::test::numeric_jacobian<double>(
        [&](const VecX& d) -> VecX {
          auto perturbed = make_camera(c.model, c.width, c.height, c.params + d);
          EXPECT_TRUE(perturbed.ok()) << perturbed.status();
          return perturbed.ok() ? VecX((*perturbed)->distort(xn)) : VecX::Zero(2);
        },
        kNumParams, mrvs::test::default_step<double>());
    EXPECT_MATRIX_NEAR(J, J_num, tolerance(J_num)) << "xn = " << xn.transpose() << " |xn| = " << xn.norm();
    // Asking for both Jacobians gives the same values as asking for each one.
    Mat2d J_xn_alone, J_xn_both;
    Eigen::Matrix<double, 2, 8> J_both;
    cam_->distort(xn, &J_xn_alone);
    EXPECT_EQ(cam_->distort(xn, &J_xn_both, &J_both), uv);
    EXPECT_EQ(J_xn_both, J_xn_alone);
    EXPECT_EQ(J_both, J);
  }
}

TEST_P(CameraJacobianTest, ProjectWrtPointInCameraFrame) {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> depth(0.1, 50.0);
  for (const Vec2d& xn : points_) {
    // Very oblique fisheye rays make z tiny; keep z away from min_depth.
    const double z = depth(rng);
    const Vec3d p = z * Vec3d(xn.x(), xn.y(), 1.0);
    Eigen::Matrix<double, 2, 3> J;
    const auto uv = cam_->project(p, &J);
    ASSERT_TRUE(uv.has_value()) << p.transpose();
    EXPECT_LT((*uv - cam_->distort(xn)).norm(), 1e-9);
    const double h = 1e-6 * std::max(1.0, p.norm());
    const Eigen::MatrixXd J_num = mrvs::test::numeric_jacobian<double>(
        [&](const VecX& d) -> VecX { return *cam_->project(p + d); }, 3, h);
    EXPECT_MATRIX_NEAR(J, J_num, tolerance(J_num)) << "p = " << p.transpose();
  }
}

TEST_P(CameraJacobianTest, JacobianIsContinuousThroughTheOpticalAxis) {
  // Approaching r = 0 along a line, the analytic Jacobian tends to its value at 0.
  Mat2d J0;
  cam_->distort(Vec2d::Zero(), &J0);
  const Mat2d expected = Vec2d(cam_->fx(), cam_->fy()).asDiagonal();
  EXPECT_MATRIX_NEAR(J0, expected, 1e-12);
  // Radial terms change J by O(r^2), tangential ones (radtan p1, p2) by O(r).
  const CameraCase& c = GetParam();
  const double tangential =
      c.model == DistortionModel::kRadTan ? std::abs(c.params[6]) + std::abs(c.params[7]) : 0.0;
  for (double r = 1e-1; r > 1e-14; r *= 0.7) {
    Mat2d J;
    cam_->distort(Vec2d(0.6, -0.8) * r, &J);
    EXPECT_MATRIX_NEAR(J, J0, 10.0 * cam_->fx() * r * (r + tangential) + 1e-12) << "r = " << r;
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraJacobianTest, ::testing::ValuesIn(test::all_cases()), test::case_name);

}  // namespace
}  // namespace mrvs::camera
