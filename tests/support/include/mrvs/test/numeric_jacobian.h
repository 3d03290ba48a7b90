#pragma once
// Numeric differentiation for checking analytic Jacobians (Basalt's test_jacobian idea).
//
// Usage: given an analytic Jacobian J of g at x with respect to a local perturbation
// delta (x [+] delta), write f(delta) = "local coordinates of g(x [+] delta) relative to
// g(x)" and compare J with numeric_jacobian(f, x.size()).
#include <cmath>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <Eigen/Core>

namespace mrvs::test {

/// Central-difference Jacobian of f : R^n -> R^m at delta = 0, step h.
/// `f` takes an Eigen::Matrix<Scalar, Eigen::Dynamic, 1> and returns any Eigen vector.
template <typename Scalar, typename F>
Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> numeric_jacobian(F&& f, int n, Scalar h) {
  using Vec = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;
  Vec delta = Vec::Zero(n);
  const Vec f0 = f(delta);
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> jac(f0.size(), n);
  for (int i = 0; i < n; ++i) {
    delta.setZero();
    delta[i] = h;
    const Vec fp = f(delta);
    delta[i] = -h;
    const Vec fm = f(delta);
    jac.col(i) = (fp - fm) / (Scalar(2) * h);
  }
  return jac;
}

/// Default step for central differences: about cbrt(machine epsilon).
template <typename Scalar>
constexpr Scalar default_step() {
  if constexpr (sizeof(Scalar) == sizeof(float)) {
    return Scalar(1e-3);
  } else {
    return Scalar(1e-6);
  }
}

/// gtest predicate: max |a - b| <= tol (both the same shape), with a readable report.
template <typename A, typename B>
::testing::AssertionResult matrices_near(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b,
                                         double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure()
           << "shape mismatch: " << a.rows() << "x" << a.cols() << " vs " << b.rows() << "x" << b.cols();
  }
  const double err = (a.template cast<double>() - b.template cast<double>()).cwiseAbs().maxCoeff();
  if (err <= tol || (a.size() == 0)) return ::testing::AssertionSuccess();
  std::ostringstream os;
  os << "max abs difference " << err << " > tolerance " << tol << "\nfirst:\n" << a << "\nsecond:\n" << b;
  return ::testing::AssertionFailure() << os.str();
}

}  // namespace mrvs::test

/// EXPECT_MATRIX_NEAR(a, b, tol): element-wise comparison of two Eigen expressions.
#define EXPECT_MATRIX_NEAR(a, b, tol) EXPECT_TRUE(::mrvs::test::matrices_near((a), (b), (tol)))
#define ASSERT_MATRIX_NEAR(a, b, tol) ASSERT_TRUE(::mrvs::test::matrices_near((a), (b), (tol)))
