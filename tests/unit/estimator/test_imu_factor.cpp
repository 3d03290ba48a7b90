// The analytic pre-integration factor (imu_factor.h): residuals and Jacobians against
// (a) central differences through RightQuaternionManifold and (b) automatic derivatives of
// a templated reference residual (the former AutoDiff factor of dynamic_initializer.cpp),
// on random states with large rotations and biases far from the linearisation point; the
// manifold's Jacobians; partial Jacobian requests; and a small solve against the reference.
#include <array>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include <ceres/autodiff_cost_function.h>
#include <ceres/normal_prior.h>
#include <ceres/problem.h>
#include <ceres/rotation.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include "mrvs/edge/imu_factor.h"
#include "mrvs/edge/preintegration.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

constexpr double kCovFloor = 1e-12;  // the dynamic initializer's floor
constexpr int kBlocks = 8;
constexpr std::array<int, kBlocks> kSizes = {4, 3, 3, 4, 3, 3, 3, 3};
constexpr std::array<bool, kBlocks> kIsQuat = {true, false, false, true, false, false, false, false};
const Vec3d kGravity(0.0, 0.0, -9.81);

// ------------------------------------------------------------------------------------------
// Reference: the residual written once more with templates, differentiated by Ceres.

struct ReferenceImuFactor {
  ReferenceImuFactor(const Preintegration& p, const Vec3d& g, const Mat9d& s)
      : pre(p), g_w(g), sqrt_info(s) {}

  template <typename T>
  bool operator()(const T* qi, const T* pi, const T* vi, const T* qj, const T* pj, const T* vj, const T* bg,
                  const T* ba, T* residual) const {
    const Eigen::Map<const Quat<T>> q_i(qi), q_j(qj);
    const Eigen::Map<const Vec3<T>> p_i(pi), v_i(vi), p_j(pj), v_j(vj), b_g(bg), b_a(ba);
    const Vec3<T> dbg = b_g - pre.bg_lin.cast<T>(), dba = b_a - pre.ba_lin.cast<T>();
    const Vec3<T> phi = pre.dR_dbg.cast<T>() * dbg;
    T e[4];  // w x y z
    ceres::AngleAxisToQuaternion(phi.data(), e);
    const Quat<T> dq = pre.dq.cast<T>() * Quat<T>(e[0], e[1], e[2], e[3]);
    const Vec3<T> dp = pre.dp.cast<T>() + pre.dp_dbg.cast<T>() * dbg + pre.dp_dba.cast<T>() * dba;
    const Vec3<T> dv = pre.dv.cast<T>() + pre.dv_dbg.cast<T>() * dbg + pre.dv_dba.cast<T>() * dba;
    const T dt(pre.dt);
    const Vec3<T> g = g_w.cast<T>();
    const Quat<T> q_i_inv = q_i.conjugate();
    const Quat<T> E = dq.conjugate() * (q_i_inv * q_j);
    const T wxyz[4] = {E.w(), E.x(), E.y(), E.z()};
    Eigen::Matrix<T, 9, 1> r;
    ceres::QuaternionToAngleAxis(wxyz, r.data());
    r.template segment<3>(3) = q_i_inv * Vec3<T>(p_j - p_i - v_i * dt - T(0.5) * g * dt * dt) - dp;
    r.template segment<3>(6) = q_i_inv * Vec3<T>(v_j - v_i - g * dt) - dv;
    Eigen::Map<Eigen::Matrix<T, 9, 1>> out(residual);
    out = sqrt_info.cast<T>() * r;
    return true;
  }

  Preintegration pre;
  Vec3d g_w;
  Mat9d sqrt_info;
};

using ReferenceCost = ceres::AutoDiffCostFunction<ReferenceImuFactor, 9, 4, 3, 3, 4, 3, 3, 3, 3>;

// ------------------------------------------------------------------------------------------
// Random problems

using Blocks = std::array<std::vector<double>, kBlocks>;  ///< q_i p_i v_i q_j p_j v_j bg ba

struct Scenario {
  Preintegration pre;
  Blocks x;
};

Vec3d randn3(std::mt19937_64* rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return Vec3d(n(*rng), n(*rng), n(*rng));
}

Mat3d randn33(std::mt19937_64* rng, double sigma) {
  Mat3d m;
  for (int c = 0; c < 3; ++c) m.col(c) = randn3(rng, sigma);
  return m;
}

Quatd random_rotation(std::mt19937_64* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Quatd(n(*rng), n(*rng), n(*rng), n(*rng)).normalized();
}

std::vector<double> coeffs(const Quatd& q) { return {q.x(), q.y(), q.z(), q.w()}; }
std::vector<double> coeffs(const Vec3d& v) { return {v.x(), v.y(), v.z()}; }

Preintegration random_preintegration(std::mt19937_64* rng) {
  Preintegration pre;
  pre.dt = std::uniform_real_distribution<double>(0.1, 0.5)(*rng);
  pre.t1_ns = std::llround(pre.dt * 1e9);
  pre.bg_lin = randn3(rng, 0.01);
  pre.ba_lin = randn3(rng, 0.1);
  pre.dq = so3::exp_quat<double>(randn3(rng, 0.5));
  pre.dp = randn3(rng, 0.5);
  pre.dv = randn3(rng, 1.0);
  const double dt = pre.dt;
  pre.dR_dbg = -dt * Mat3d::Identity() + randn33(rng, 0.2 * dt);
  pre.dp_dbg = randn33(rng, 0.3 * dt * dt);
  pre.dp_dba = -0.5 * dt * dt * Mat3d::Identity() + randn33(rng, 0.1 * dt * dt);
  pre.dv_dbg = randn33(rng, 0.5 * dt);
  pre.dv_dba = -dt * Mat3d::Identity() + randn33(rng, 0.1 * dt);
  Mat9d A;
  for (int c = 0; c < 9; ++c) A.col(c) << randn3(rng, 1.0), randn3(rng, 1.0), randn3(rng, 1.0);
  pre.cov = 1e-5 * A * A.transpose() + 1e-6 * Mat9d::Identity();
  return pre;
}

/// States near (within `rotation_error` rad and ~0.1 m, m/s) of agreeing with the measurement,
/// biases far (0.05 rad/s, 0.3 m/s^2) from the linearisation point.
Scenario random_scenario(std::mt19937_64* rng, double rotation_error) {
  Scenario s;
  s.pre = random_preintegration(rng);
  const double dt = s.pre.dt;
  const Quatd q_i = random_rotation(rng);
  const Vec3d p_i = randn3(rng, 3.0), v_i = randn3(rng, 1.0);
  const Vec3d bg = s.pre.bg_lin + randn3(rng, 0.05), ba = s.pre.ba_lin + randn3(rng, 0.3);
  const Quatd q_j = q_i * s.pre.dq_at(bg) * so3::exp_quat<double>(randn3(rng, rotation_error));
  const Vec3d p_j = p_i + v_i * dt + 0.5 * kGravity * dt * dt + q_i * s.pre.dp_at(bg, ba) + randn3(rng, 0.1);
  const Vec3d v_j = v_i + kGravity * dt + q_i * s.pre.dv_at(bg, ba) + randn3(rng, 0.1);
  s.x = {coeffs(q_i), coeffs(p_i), coeffs(v_i), coeffs(q_j),
         coeffs(p_j), coeffs(v_j), coeffs(bg),  coeffs(ba)};
  return s;
}

/// Scenarios with residual angles from ~0 (series branches) to ~2 rad.
std::vector<Scenario> scenarios() {
  std::mt19937_64 rng(20240611);
  std::vector<Scenario> out;
  for (const double rotation_error : {0.0, 1e-4, 0.05, 0.3, 0.8, 1.2}) {
    for (int k = 0; k < 4; ++k) out.push_back(random_scenario(&rng, rotation_error));
  }
  return out;
}

// ------------------------------------------------------------------------------------------
// Evaluation helpers

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Evaluation {
  Vec9d r = Vec9d::Zero();
  std::array<RowMatrix, kBlocks> J;  ///< 9 x ambient size
};

Evaluation evaluate(const ceres::CostFunction& f, const Blocks& x) {
  Evaluation e;
  std::array<const double*, kBlocks> params{};
  std::array<double*, kBlocks> jacobians{};
  for (int k = 0; k < kBlocks; ++k) {
    params[k] = x[k].data();
    e.J[k] = RowMatrix::Constant(9, kSizes[k], std::nan(""));
    jacobians[k] = e.J[k].data();
  }
  EXPECT_TRUE(f.Evaluate(params.data(), e.r.data(), jacobians.data()));
  return e;
}

Vec9d residual(const ceres::CostFunction& f, const Blocks& x) {
  std::array<const double*, kBlocks> params{};
  for (int k = 0; k < kBlocks; ++k) params[k] = x[k].data();
  Vec9d r;
  EXPECT_TRUE(f.Evaluate(params.data(), r.data(), nullptr));
  return r;
}

/// The 9 x 3 Jacobian Ceres uses for block k: w.r.t. the manifold's tangent for quaternions.
RowMatrix tangent(const RowMatrix& J_ambient, const Blocks& x, int k) {
  if (!kIsQuat[k]) return J_ambient;
  Eigen::Matrix<double, 4, 3, Eigen::RowMajor> P;
  RightQuaternionManifold().PlusJacobian(x[k].data(), P.data());
  return J_ambient * P;
}

/// Central differences of f's residual w.r.t. block k, through the manifold for quaternions.
RowMatrix numeric_tangent(const ceres::CostFunction& f, const Blocks& x, int k) {
  const RightQuaternionManifold manifold;
  const auto moved = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    Blocks y = x;
    if (kIsQuat[k]) {
      manifold.Plus(x[k].data(), d.data(), y[k].data());
    } else {
      for (int i = 0; i < 3; ++i) y[k][i] += d[i];
    }
    return residual(f, y);
  };
  return mrvs::test::numeric_jacobian<double>(moved, 3, 1e-6);
}

/// max |a - b| <= rel * max(|b|), with the errors reported.
::testing::AssertionResult relatively_near(const RowMatrix& a, const RowMatrix& b, double rel) {
  const double scale = std::max(b.cwiseAbs().maxCoeff(), 1e-300);
  const double err = (a - b).cwiseAbs().maxCoeff();
  if (err <= rel * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "relative error " << err / scale << " > " << rel << "\nfirst:\n"
                                       << a << "\nsecond:\n"
                                       << b;
}

const std::array<const char*, kBlocks> kNames = {"q_i", "p_i", "v_i", "q_j", "p_j", "v_j", "bg", "ba"};

// ------------------------------------------------------------------------------------------
// Tests

TEST(ImuFactor, ResidualMatchesTheReferenceAndPreintegrationResidual) {
  for (const Scenario& s : scenarios()) {
    const ImuCostFunction analytic(s.pre, kGravity, kCovFloor);
    const ReferenceCost reference(new ReferenceImuFactor(s.pre, kGravity, analytic.sqrt_information()));
    const Vec9d r = residual(analytic, s.x);
    EXPECT_TRUE(relatively_near(r, residual(reference, s.x), 1e-10));
    ImuState xi, xj;
    xi.q_w_b = Quatd(s.x[0].data());
    xi.p_w_b = Vec3d(s.x[1].data());
    xi.v_w_b = Vec3d(s.x[2].data());
    xi.bg = Vec3d(s.x[6].data());
    xi.ba = Vec3d(s.x[7].data());
    xj.q_w_b = Quatd(s.x[3].data());
    xj.p_w_b = Vec3d(s.x[4].data());
    xj.v_w_b = Vec3d(s.x[5].data());
    const Vec9d unwhitened = imu_residual(s.pre, xi, xj, kGravity);
    EXPECT_TRUE(relatively_near(unwhitened, preintegration_residual(s.pre, xi, xj, kGravity), 1e-12));
    EXPECT_TRUE(relatively_near(r, analytic.sqrt_information() * unwhitened, 1e-12));
  }
}

TEST(ImuFactor, JacobiansMatchAutomaticDerivatives) {
  double worst = 0.0;
  for (const Scenario& s : scenarios()) {
    const ImuCostFunction analytic(s.pre, kGravity, kCovFloor);
    const ReferenceCost reference(new ReferenceImuFactor(s.pre, kGravity, analytic.sqrt_information()));
    const Evaluation a = evaluate(analytic, s.x), b = evaluate(reference, s.x);
    for (int k = 0; k < kBlocks; ++k) {
      // What Ceres uses: the Jacobian on the tangent space.
      const RowMatrix Ja = tangent(a.J[k], s.x, k), Jb = tangent(b.J[k], s.x, k);
      EXPECT_TRUE(relatively_near(Ja, Jb, 1e-9)) << kNames[k];
      worst = std::max(worst, (Ja - Jb).cwiseAbs().maxCoeff() / Jb.cwiseAbs().maxCoeff());
      if (!kIsQuat[k]) continue;
      // Ambient: the reference's Jacobian projected on the tangent space (the radial
      // direction of a unit quaternion is never seen by Ceres).
      Eigen::Matrix<double, 3, 4, Eigen::RowMajor> M;
      RightQuaternionManifold().MinusJacobian(s.x[k].data(), M.data());
      EXPECT_TRUE(relatively_near(a.J[k], Jb * M, 1e-9)) << kNames[k] << " (ambient)";
    }
  }
  std::cout << "[ result   ] worst relative difference to autodiff " << worst << "\n";
}

TEST(ImuFactor, JacobiansMatchNumericDifferencesThroughTheManifold) {
  double worst = 0.0;
  for (const Scenario& s : scenarios()) {
    const ImuCostFunction analytic(s.pre, kGravity, kCovFloor);
    const Evaluation a = evaluate(analytic, s.x);
    for (int k = 0; k < kBlocks; ++k) {
      const RowMatrix Ja = tangent(a.J[k], s.x, k), Jn = numeric_tangent(analytic, s.x, k);
      EXPECT_TRUE(relatively_near(Ja, Jn, 1e-6)) << kNames[k];
      worst = std::max(worst, (Ja - Jn).cwiseAbs().maxCoeff() / Jn.cwiseAbs().maxCoeff());
    }
  }
  std::cout << "[ result   ] worst relative difference to central differences " << worst << "\n";
}

TEST(ImuFactor, TheChecksDetectAWrongSign) {
  const Scenario s = scenarios()[13];
  const ImuCostFunction analytic(s.pre, kGravity, kCovFloor);
  const Evaluation a = evaluate(analytic, s.x);
  for (int k = 0; k < kBlocks; ++k) {
    RowMatrix wrong = tangent(a.J[k], s.x, k);
    // Flip the largest column of one residual group (rotation, position or velocity).
    Eigen::Index row = 0, col = 0;
    wrong.cwiseAbs().maxCoeff(&row, &col);
    const Eigen::Index group = 3 * (row / 3);
    wrong.block(group, col, 3, 1) *= -1.0;
    EXPECT_FALSE(relatively_near(wrong, numeric_tangent(analytic, s.x, k), 1e-6)) << kNames[k];
  }
}

TEST(ImuFactor, ManifoldMinusJacobianInvertsPlusJacobian) {
  std::mt19937_64 rng(5);
  const RightQuaternionManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const Quatd q = random_rotation(&rng);
    const std::vector<double> x = coeffs(q);
    Eigen::Matrix<double, 4, 3, Eigen::RowMajor> P;
    Eigen::Matrix<double, 3, 4, Eigen::RowMajor> M;
    ASSERT_TRUE(manifold.PlusJacobian(x.data(), P.data()) && manifold.MinusJacobian(x.data(), M.data()));
    EXPECT_MATRIX_NEAR(M * P, Mat3d::Identity(), 1e-14);
    // Both against central differences of Plus and Minus.
    const auto plus = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      Eigen::Vector4d y;
      manifold.Plus(x.data(), d.data(), y.data());
      return y;
    };
    const auto minus = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      const Eigen::Vector4d y = Eigen::Vector4d(x.data()) + d;
      Vec3d out;
      manifold.Minus(y.data(), x.data(), out.data());
      return out;
    };
    EXPECT_MATRIX_NEAR(P, mrvs::test::numeric_jacobian<double>(plus, 3, 1e-6), 1e-9);
    // Minus normalises y: both have a zero radial column (M q = 0).
    EXPECT_MATRIX_NEAR(M, mrvs::test::numeric_jacobian<double>(minus, 4, 1e-6), 1e-9);
  }
}

TEST(ImuFactor, EvaluatesWithoutJacobiansOrWithSomeBlocks) {
  const Scenario s = scenarios()[9];
  const ImuCostFunction analytic(s.pre, kGravity, kCovFloor);
  ASSERT_EQ(analytic.num_residuals(), 9);
  ASSERT_EQ(analytic.parameter_block_sizes(), std::vector<int32_t>(kSizes.begin(), kSizes.end()));
  const Evaluation full = evaluate(analytic, s.x);
  EXPECT_EQ(residual(analytic, s.x), full.r);
  for (const std::array<bool, kBlocks> wanted :
       {std::array<bool, kBlocks>{true, false, false, false, false, false, false, false},
        std::array<bool, kBlocks>{false, true, true, true, false, false, false, true},
        std::array<bool, kBlocks>{false, false, false, false, false, false, false, false}}) {
    std::array<const double*, kBlocks> params{};
    std::array<RowMatrix, kBlocks> J;
    std::array<double*, kBlocks> jacobians{};
    for (int k = 0; k < kBlocks; ++k) {
      params[k] = s.x[k].data();
      J[k] = RowMatrix::Constant(9, kSizes[k], 7.0);
      jacobians[k] = wanted[k] ? J[k].data() : nullptr;
    }
    Vec9d r;
    ASSERT_TRUE(analytic.Evaluate(params.data(), r.data(), jacobians.data()));
    EXPECT_EQ(r, full.r);
    for (int k = 0; k < kBlocks; ++k) {
      if (wanted[k]) {
        EXPECT_EQ(J[k], full.J[k]) << kNames[k];
      } else {
        EXPECT_TRUE((J[k].array() == 7.0).all()) << kNames[k];  // untouched
      }
    }
  }
}

/// Two pre-integration factors on three states, the first held fixed, the biases under a
/// prior: the analytic and the automatic factor lead Ceres to the same solution.
Blocks solve_chain(const std::array<Scenario, 2>& s, bool analytic_factors) {
  std::vector<std::vector<double>> q = {s[0].x[0], s[0].x[3], s[1].x[3]};
  std::vector<std::vector<double>> p = {s[0].x[1], s[0].x[4], s[1].x[4]};
  std::vector<std::vector<double>> v = {s[0].x[2], s[0].x[5], s[1].x[5]};
  std::vector<double> bg = s[0].x[6], ba = s[0].x[7];
  ceres::Problem::Options po;
  po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  RightQuaternionManifold manifold;
  ceres::Problem problem(po);
  for (int k = 0; k < 3; ++k) problem.AddParameterBlock(q[k].data(), 4, &manifold);
  for (int k = 0; k < 2; ++k) {
    ceres::CostFunction* f = nullptr;
    if (analytic_factors) {
      f = new ImuCostFunction(s[k].pre, kGravity, kCovFloor);
    } else {
      const ImuCostFunction whitening(s[k].pre, kGravity, kCovFloor);
      f = new ReferenceCost(new ReferenceImuFactor(s[k].pre, kGravity, whitening.sqrt_information()));
    }
    problem.AddResidualBlock(f, nullptr, q[k].data(), p[k].data(), v[k].data(), q[k + 1].data(),
                             p[k + 1].data(), v[k + 1].data(), bg.data(), ba.data());
  }
  problem.AddResidualBlock(new ceres::NormalPrior(Mat3d::Identity() / 0.01, Vec3d::Zero()), nullptr,
                           bg.data());
  problem.AddResidualBlock(new ceres::NormalPrior(Mat3d::Identity() / 0.1, Vec3d::Zero()), nullptr,
                           ba.data());
  for (double* fixed : {q[0].data(), p[0].data(), v[0].data()}) problem.SetParameterBlockConstant(fixed);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.function_tolerance = so.gradient_tolerance = 1e-16;
  so.parameter_tolerance = 1e-14;
  so.max_num_iterations = 50;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  EXPECT_GT(summary.iterations.size(), 2u);
  EXPECT_LT(summary.final_cost, 1e-3 * summary.initial_cost);
  return {q[1], p[1], v[1], q[2], p[2], v[2], bg, ba};
}

TEST(ImuFactor, SolvesLikeAutomaticDerivatives) {
  std::mt19937_64 rng(11);
  std::array<Scenario, 2> s = {random_scenario(&rng, 0.3), random_scenario(&rng, 0.3)};
  s[1].x[0] = s[0].x[3];  // chain the states: j of the first interval is i of the second
  s[1].x[1] = s[0].x[4];
  s[1].x[2] = s[0].x[5];
  s[1].pre.bg_lin = s[0].pre.bg_lin;
  s[1].pre.ba_lin = s[0].pre.ba_lin;
  const Blocks a = solve_chain(s, true), b = solve_chain(s, false);
  for (int k = 0; k < kBlocks; ++k) {
    const Eigen::Map<const Eigen::VectorXd> xa(a[k].data(), kSizes[k]), xb(b[k].data(), kSizes[k]);
    EXPECT_MATRIX_NEAR(xa, xb, 1e-9) << kNames[k];
  }
}

}  // namespace
}  // namespace mrvs::edge
