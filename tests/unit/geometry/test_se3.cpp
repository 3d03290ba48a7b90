#include <random>

#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include "mrvs/geometry/se3.h"
#include "mrvs/test/numeric_jacobian.h"
#include "random.h"

namespace mrvs {
namespace {

using test::numeric_jacobian;

// 4x4 twist matrix of xi = [rho; phi]; its matrix exponential is an independent reference.
template <typename S>
Mat4<S> hat(const Vec6<S>& xi) {
  Mat4<S> m = Mat4<S>::Zero();
  m.template topLeftCorner<3, 3>() = skew<S>(xi.template tail<3>());
  m.template topRightCorner<3, 1>() = xi.template head<3>();
  return m;
}

template <typename S>
Vec6<S> random_twist(std::mt19937& rng, double angle) {
  Vec6<S> xi;
  xi.template head<3>() = test::random_vector<S>(rng, 2.0);
  xi.template tail<3>() = test::random_rotation_vector<S>(rng, angle, angle);
  return xi;
}

template <typename S>
class Se3Test : public ::testing::Test {
 protected:
  using VecX = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  static constexpr double kTol = sizeof(S) == sizeof(float) ? 5e-3 : 1e-6;
  static constexpr double kExactTol = sizeof(S) == sizeof(float) ? 5e-5 : 1e-11;
  std::mt19937 rng{7};
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(Se3Test, Scalars);

TYPED_TEST(Se3Test, ExpMatchesMatrixExponential) {
  using S = TypeParam;
  for (double angle : test::kTestAngles) {
    const Vec6<S> xi = random_twist<S>(this->rng, angle);
    const Mat4d reference = hat<double>(xi.template cast<double>()).exp();
    EXPECT_MATRIX_NEAR(SE3<S>::exp(xi).matrix(), reference, this->kExactTol * 10) << "angle " << angle;
  }
}

TYPED_TEST(Se3Test, LogInvertsExp) {
  using S = TypeParam;
  for (double angle : test::kTestAngles) {
    const Vec6<S> xi = random_twist<S>(this->rng, angle);
    EXPECT_MATRIX_NEAR(SE3<S>::exp(xi).log(), xi, this->kExactTol * 10) << "angle " << angle;
  }
}

TYPED_TEST(Se3Test, FrameConventionComposesAndInverts) {
  using S = TypeParam;
  for (int i = 0; i < 50; ++i) {
    const SE3<S> T_a_b = test::random_pose<S>(this->rng);
    const SE3<S> T_b_c = test::random_pose<S>(this->rng);
    const Vec3<S> p_c = test::random_vector<S>(this->rng, 10.0);
    // p_a = T_a_b * (T_b_c * p_c) = (T_a_b * T_b_c) * p_c
    EXPECT_MATRIX_NEAR((T_a_b * T_b_c) * p_c, T_a_b * (T_b_c * p_c), this->kExactTol * 100);
    EXPECT_MATRIX_NEAR((T_a_b * T_b_c).matrix(), T_a_b.matrix() * T_b_c.matrix(), this->kExactTol * 100);
    EXPECT_MATRIX_NEAR((T_a_b * T_a_b.inverse()).matrix(), Mat4<S>::Identity(), this->kExactTol * 10);
    EXPECT_MATRIX_NEAR(T_a_b.inverse().matrix(), T_a_b.matrix().inverse(), this->kExactTol * 100);
    // Translation is the origin of b expressed in a.
    EXPECT_MATRIX_NEAR(T_a_b * Vec3<S>::Zero(), T_a_b.translation(), 0.0);
    EXPECT_MATRIX_NEAR(SE3<S>::from_matrix(T_a_b.matrix()).matrix(), T_a_b.matrix(), this->kExactTol);
  }
}

TYPED_TEST(Se3Test, AdjointMovesTwistsAcrossTransforms) {
  using S = TypeParam;
  for (int i = 0; i < 50; ++i) {
    const SE3<S> T = test::random_pose<S>(this->rng);
    const Vec6<S> xi = random_twist<S>(this->rng, 0.7);
    const SE3<S> lhs = T * SE3<S>::exp(xi) * T.inverse();
    const SE3<S> rhs = SE3<S>::exp(T.adjoint() * xi);
    EXPECT_MATRIX_NEAR(lhs.matrix(), rhs.matrix(), this->kExactTol * 100);
  }
}

TYPED_TEST(Se3Test, LeftAndRightJacobiansMatchNumeric) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec6<S> xi = random_twist<S>(this->rng, angle);
    const SE3<S> T0 = SE3<S>::exp(xi);
    auto right = [&](const VecX& d) -> VecX {
      const Vec6<S> xd = xi + d.template head<6>();
      return (T0.inverse() * SE3<S>::exp(xd)).log();
    };
    auto left = [&](const VecX& d) -> VecX {
      const Vec6<S> xd = xi + d.template head<6>();
      return (SE3<S>::exp(xd) * T0.inverse()).log();
    };
    const S h = test::default_step<S>();
    EXPECT_MATRIX_NEAR(se3::right_jacobian(xi), numeric_jacobian<S>(right, 6, h), this->kTol)
        << "angle " << angle;
    EXPECT_MATRIX_NEAR(se3::left_jacobian(xi), numeric_jacobian<S>(left, 6, h), this->kTol)
        << "angle " << angle;
  }
}

TYPED_TEST(Se3Test, JacobianInversesMatchNumericLogDerivative) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec6<S> xi = random_twist<S>(this->rng, angle);
    const SE3<S> T0 = SE3<S>::exp(xi);
    auto right = [&](const VecX& d) -> VecX { return (T0 * SE3<S>::exp(d.template head<6>())).log(); };
    auto left = [&](const VecX& d) -> VecX { return (SE3<S>::exp(d.template head<6>()) * T0).log(); };
    const S h = test::default_step<S>();
    EXPECT_MATRIX_NEAR(se3::right_jacobian_inverse(xi), numeric_jacobian<S>(right, 6, h), this->kTol)
        << "angle " << angle;
    EXPECT_MATRIX_NEAR(se3::left_jacobian_inverse(xi), numeric_jacobian<S>(left, 6, h), this->kTol)
        << "angle " << angle;
    EXPECT_MATRIX_NEAR(se3::left_jacobian(xi) * se3::left_jacobian_inverse(xi), Mat6<S>::Identity(),
                       this->kExactTol * 100);
  }
}

TYPED_TEST(Se3Test, CastPreservesTheTransform) {
  using S = TypeParam;
  const SE3<S> T = test::random_pose<S>(this->rng);
  // Exact up to the re-normalisation of the quaternion in the constructor.
  EXPECT_MATRIX_NEAR(T.template cast<double>().template cast<S>().matrix(), T.matrix(), this->kExactTol);
}

}  // namespace
}  // namespace mrvs
