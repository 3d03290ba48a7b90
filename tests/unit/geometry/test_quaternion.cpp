#include <random>

#include <gtest/gtest.h>

#include "mrvs/geometry/quaternion.h"
#include "mrvs/test/numeric_jacobian.h"
#include "random.h"

namespace mrvs {
namespace {

TEST(Quaternion, EigenIsHamiltonAndActsAsRotation) {
  // Hamilton: i * j = k.
  const Quatd i(0, 1, 0, 0), j(0, 0, 1, 0);
  const Quatd k = i * j;
  EXPECT_MATRIX_NEAR(k.coeffs(), Vec4d(0, 0, 1, 0), 0.0);
  // q_a_b rotates b vectors into a: 90 deg about z maps x_b to y_a.
  const Quatd q_a_b = so3::exp_quat<double>(Vec3d(0, 0, M_PI / 2));
  EXPECT_MATRIX_NEAR(q_a_b * Vec3d::UnitX(), Vec3d::UnitY(), 1e-15);
  EXPECT_MATRIX_NEAR(q_a_b.toRotationMatrix(), so3::exp<double>(Vec3d(0, 0, M_PI / 2)), 1e-15);
}

TEST(Quaternion, MultiplicationMatricesMatchTheProduct) {
  std::mt19937 rng(3);
  for (int n = 0; n < 100; ++n) {
    const Quatd p = so3::exp_quat(test::random_rotation_vector<double>(rng, 0.0, 3.1));
    const Quatd q = so3::exp_quat(test::random_rotation_vector<double>(rng, 0.0, 3.1));
    const Vec4d pq = (p * q).coeffs();
    EXPECT_MATRIX_NEAR(quat::left_multiplication_matrix(p) * q.coeffs(), pq, 1e-14);
    EXPECT_MATRIX_NEAR(quat::right_multiplication_matrix(q) * p.coeffs(), pq, 1e-14);
  }
}

TEST(Quaternion, CanonicalHasNonNegativeW) {
  Quatd q(-0.5, 0.5, 0.5, 0.5);
  const Quatd c = quat::canonical(q);
  EXPECT_GE(c.w(), 0.0);
  EXPECT_NEAR(quat::angular_distance(q, c), 0.0, 1e-7);
}

TEST(Quaternion, BoxPlusAndMinusAreInverse) {
  std::mt19937 rng(5);
  for (int n = 0; n < 100; ++n) {
    const Quatd a = so3::exp_quat(test::random_rotation_vector<double>(rng, 0.0, 3.1));
    const Vec3d d = test::random_rotation_vector<double>(rng, 0.0, 3.0);
    EXPECT_MATRIX_NEAR(quat::minus_right(quat::plus_right(a, d), a), d, 1e-12);
    EXPECT_NEAR(quat::angular_distance(a, quat::plus_right(a, d)), d.norm(), 1e-12);
  }
}

// d/dq (R(q) v) is what estimators chain; check the local-perturbation form
// d/dtheta [ (q * exp(theta)) v ] = -R [v]x against numeric differentiation.
TEST(Quaternion, RotatedVectorJacobianMatchesNumeric) {
  std::mt19937 rng(9);
  for (int n = 0; n < 20; ++n) {
    const Quatd q = so3::exp_quat(test::random_rotation_vector<double>(rng, 0.0, 3.1));
    const Vec3d v = test::random_vector<double>(rng, 4.0);
    auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return quat::plus_right<double>(q, d.head<3>()) * v;
    };
    const Mat3d analytic = -q.toRotationMatrix() * skew(v);
    EXPECT_MATRIX_NEAR(analytic, test::numeric_jacobian<double>(f, 3, 1e-6), 1e-8);
  }
}

}  // namespace
}  // namespace mrvs
