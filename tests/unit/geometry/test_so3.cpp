#include <random>

#include <gtest/gtest.h>

#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"
#include "random.h"

namespace mrvs {
namespace {

using test::numeric_jacobian;

template <typename S>
class So3Test : public ::testing::Test {
 protected:
  using VecX = Eigen::Matrix<S, Eigen::Dynamic, 1>;
  // Tolerances: float keeps ~7 digits, and numeric differentiation loses about half.
  static constexpr double kTol = sizeof(S) == sizeof(float) ? 2e-3 : 1e-7;
  static constexpr double kExactTol = sizeof(S) == sizeof(float) ? 1e-5 : 1e-12;
  std::mt19937 rng{42};
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(So3Test, Scalars);

TYPED_TEST(So3Test, SkewIsCrossProductAndVeeInvertsIt) {
  using S = TypeParam;
  for (int i = 0; i < 100; ++i) {
    const Vec3<S> a = test::random_vector<S>(this->rng, 3.0);
    const Vec3<S> b = test::random_vector<S>(this->rng, 3.0);
    EXPECT_MATRIX_NEAR(skew(a) * b, a.cross(b), this->kExactTol * 10);
    EXPECT_MATRIX_NEAR(vee(skew(a)), a, this->kExactTol);
    EXPECT_MATRIX_NEAR(skew(a).transpose(), -skew(a), 0.0);
  }
}

TYPED_TEST(So3Test, ExpMatchesEigenAngleAxis) {
  using S = TypeParam;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    const Mat3<S> expected = angle == 0.0
                                 ? Mat3<S>::Identity()
                                 : Eigen::AngleAxis<S>(phi.norm(), phi.normalized()).toRotationMatrix();
    EXPECT_MATRIX_NEAR(so3::exp(phi), expected, this->kExactTol) << "angle " << angle;
    EXPECT_TRUE(so3::is_rotation_matrix<S>(so3::exp(phi), S(this->kExactTol)));
  }
}

TYPED_TEST(So3Test, LogInvertsExpIncludingNearPi) {
  using S = TypeParam;
  for (double angle : test::kTestAngles) {
    for (int i = 0; i < 20; ++i) {
      const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
      EXPECT_MATRIX_NEAR(so3::log(so3::exp(phi)), phi, this->kExactTol * 10) << "angle " << angle;
      EXPECT_MATRIX_NEAR(so3::log(so3::exp_quat(phi)), phi, this->kExactTol * 10);
    }
  }
  // Exactly pi: log returns a vector of norm pi whose exp is the same rotation.
  const Vec3<S> half_turn(S(0), S(M_PI), S(0));
  const Vec3<S> back = so3::log(so3::exp(half_turn));
  EXPECT_NEAR(back.norm(), M_PI, this->kExactTol * 10);
  EXPECT_MATRIX_NEAR(so3::exp(back), so3::exp(half_turn), this->kExactTol * 10);
}

TYPED_TEST(So3Test, LogIsTheSameForQAndMinusQ) {
  using S = TypeParam;
  for (int i = 0; i < 50; ++i) {
    const Quat<S> q = so3::exp_quat(test::random_rotation_vector<S>(this->rng, 0.0, 3.1));
    Quat<S> minus_q = q;
    minus_q.coeffs() = -q.coeffs();
    EXPECT_MATRIX_NEAR(so3::log(q), so3::log(minus_q), this->kExactTol * 10);
  }
}

// exp(phi + d) == exp(phi) * exp(Jr(phi) d)  <=>  Jr = d/dd log(exp(phi)^-1 exp(phi + d)).
TYPED_TEST(So3Test, RightJacobianMatchesNumeric) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    const Quat<S> q0 = so3::exp_quat(phi);
    auto f = [&](const VecX& d) -> VecX {
      return so3::log<S>(q0.conjugate() * so3::exp_quat<S>(phi + d.template head<3>()));
    };
    EXPECT_MATRIX_NEAR(so3::right_jacobian(phi), numeric_jacobian<S>(f, 3, test::default_step<S>()),
                       this->kTol)
        << "angle " << angle;
  }
}

TYPED_TEST(So3Test, LeftJacobianMatchesNumeric) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    const Quat<S> q0 = so3::exp_quat(phi);
    auto f = [&](const VecX& d) -> VecX {
      return so3::log<S>(so3::exp_quat<S>(phi + d.template head<3>()) * q0.conjugate());
    };
    EXPECT_MATRIX_NEAR(so3::left_jacobian(phi), numeric_jacobian<S>(f, 3, test::default_step<S>()),
                       this->kTol)
        << "angle " << angle;
  }
}

// log(exp(phi) exp(d)) ~= phi + Jr^-1(phi) d.
TYPED_TEST(So3Test, RightJacobianInverseMatchesNumericLogDerivative) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    const Quat<S> q0 = so3::exp_quat(phi);
    auto f = [&](const VecX& d) -> VecX { return so3::log<S>(q0 * so3::exp_quat<S>(d.template head<3>())); };
    EXPECT_MATRIX_NEAR(so3::right_jacobian_inverse(phi), numeric_jacobian<S>(f, 3, test::default_step<S>()),
                       this->kTol)
        << "angle " << angle;
  }
}

TYPED_TEST(So3Test, LeftJacobianInverseMatchesNumericLogDerivative) {
  using S = TypeParam;
  using VecX = typename TestFixture::VecX;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    const Quat<S> q0 = so3::exp_quat(phi);
    auto f = [&](const VecX& d) -> VecX { return so3::log<S>(so3::exp_quat<S>(d.template head<3>()) * q0); };
    EXPECT_MATRIX_NEAR(so3::left_jacobian_inverse(phi), numeric_jacobian<S>(f, 3, test::default_step<S>()),
                       this->kTol)
        << "angle " << angle;
  }
}

TYPED_TEST(So3Test, JacobianInversesAreInverses) {
  using S = TypeParam;
  for (double angle : test::kTestAngles) {
    const Vec3<S> phi = test::random_rotation_vector<S>(this->rng, angle, angle);
    EXPECT_MATRIX_NEAR(so3::right_jacobian(phi) * so3::right_jacobian_inverse(phi), Mat3<S>::Identity(),
                       this->kExactTol * 10)
        << "angle " << angle;
    EXPECT_MATRIX_NEAR(so3::left_jacobian(phi) * so3::left_jacobian_inverse(phi), Mat3<S>::Identity(),
                       this->kExactTol * 10)
        << "angle " << angle;
    // Jl = R Jr
    EXPECT_MATRIX_NEAR(so3::left_jacobian(phi), so3::exp(phi) * so3::right_jacobian(phi),
                       this->kExactTol * 10);
  }
}

// The series branch and the closed form agree where they switch (continuity).
TYPED_TEST(So3Test, JacobiansAreContinuousAtTheSeriesSwitch) {
  using S = TypeParam;
  const double t = jacobian_series_threshold<S>();
  const Vec3<S> axis = Vec3<S>(S(1), S(2), S(-0.5)).normalized();
  // A step small enough that the true change (~|dJ/dphi| * step) is below the tolerance.
  const double step = sizeof(S) == sizeof(float) ? 1e-5 : 1e-9;
  const double tol = sizeof(S) == sizeof(float) ? 1e-4 : 1e-9;
  const Vec3<S> below = axis * S(t * (1 - step));
  const Vec3<S> above = axis * S(t * (1 + step));
  ASSERT_LT(below.norm(), S(t));
  ASSERT_GT(above.norm(), S(t));
  EXPECT_MATRIX_NEAR(so3::right_jacobian(below), so3::right_jacobian(above), tol);
  EXPECT_MATRIX_NEAR(so3::right_jacobian_inverse(below), so3::right_jacobian_inverse(above), tol);
}

TEST(So3, IsRotationMatrixRejectsReflectionsAndScaledMatrices) {
  EXPECT_TRUE(so3::is_rotation_matrix<double>(Mat3d::Identity(), 1e-9));
  EXPECT_FALSE(so3::is_rotation_matrix<double>(-Mat3d::Identity(), 1e-9));
  EXPECT_FALSE(so3::is_rotation_matrix<double>(1.01 * Mat3d::Identity(), 1e-3));
  Mat3d reflection = Mat3d::Identity();
  reflection(2, 2) = -1;
  EXPECT_FALSE(so3::is_rotation_matrix<double>(reflection, 1e-9));
}

}  // namespace
}  // namespace mrvs
