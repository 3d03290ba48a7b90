// IMU propagation: the RK4 mean against a dense reference integration of a known motion,
// the discrete transition against numeric derivatives of the mean, the noise against a
// Monte Carlo of noisy measurements, and a static IMU that does not drift.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/imu_propagator.h"
#include "mrvs/geometry/quaternion.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

const Vec3d kGravity(0.0, 0.0, -9.81);

/// A smooth motion: body rates and world acceleration as functions of time.
struct Motion {
  Vec3d w(double t) const {
    return Vec3d(0.3 * std::sin(1.3 * t), 0.5 * std::cos(0.7 * t), 0.8 * std::sin(0.9 * t + 1));
  }
  Vec3d a_w(double t) const {
    return Vec3d(1.5 * std::cos(1.1 * t), -0.8 * std::sin(0.6 * t), 0.4 * std::cos(2.0 * t));
  }
};

/// Reference: tiny RK4 steps of the true continuous motion from a known start.
ImuState reference(const Motion& m, ImuState x, double t0, double t1) {
  const int n = 20000;
  const double h = (t1 - t0) / n;
  for (int i = 0; i < n; ++i) {
    const double t = t0 + i * h;
    // Rotation: midpoint rate; position/velocity: exact world acceleration.
    x.q_w_b = quat::plus_right(x.q_w_b, Vec3d(m.w(t + 0.5 * h) * h));
    x.p_w_b += x.v_w_b * h + 0.5 * h * h * (m.a_w(t) + (m.a_w(t + h) - m.a_w(t)) / 3.0);
    x.v_w_b += 0.5 * h * (m.a_w(t) + m.a_w(t + h));
  }
  return x;
}

std::vector<io::ImuSample> samples_of(const Motion& m, const ImuState& x0, double t0, double t1, double rate,
                                      const Vec3d& bg, const Vec3d& ba) {
  // Orientation along the way from the reference integration.
  std::vector<io::ImuSample> out;
  ImuState x = x0;
  const int n = static_cast<int>((t1 - t0) * rate + 0.5);
  for (int k = 0; k <= n; ++k) {
    const double t = t0 + k / rate;
    if (k > 0) x = reference(m, x, t0 + (k - 1) / rate, t);
    io::ImuSample s;
    s.t_ns = from_seconds(t);
    s.gyro_radps = m.w(t) + bg;
    s.accel_mps2 = x.q_w_b.conjugate() * (m.a_w(t) - kGravity) + ba;
    out.push_back(s);
  }
  return out;
}

ImuState start_state() {
  ImuState x;
  x.t_ns = from_seconds(1.0);
  x.q_w_b = so3::exp_quat<double>(Vec3d(0.1, -0.2, 0.3));
  x.p_w_b = Vec3d(1.0, 2.0, 1.5);
  x.v_w_b = Vec3d(0.5, -0.3, 0.1);
  x.bg = Vec3d(0.01, -0.02, 0.015);
  x.ba = Vec3d(0.05, 0.1, -0.08);
  return x;
}

TEST(Propagator, MeanMatchesAReferenceIntegrationOverOneSecond) {
  const Motion m;
  ImuState x0 = start_state();
  const auto samples = samples_of(m, x0, 1.0, 2.05, 200.0, x0.bg, x0.ba);
  const auto prop = propagate(x0, samples, from_seconds(2.0), kGravity, ImuNoise{});
  ASSERT_TRUE(prop.ok()) << prop.status();
  const ImuState ref = reference(m, x0, 1.0, 2.0);
  EXPECT_LT((prop->state.p_w_b - ref.p_w_b).norm(), 2e-4);  // m after 1 s
  EXPECT_LT((prop->state.v_w_b - ref.v_w_b).norm(), 2e-4);  // m/s
  EXPECT_LT(quat::angular_distance(prop->state.q_w_b, ref.q_w_b), 2e-5);
  EXPECT_EQ(prop->state.t_ns, from_seconds(2.0));
}

TEST(Propagator, TransitionMatchesNumericDerivativesOfTheMean) {
  const Motion m;
  const ImuState x0 = start_state();
  const auto samples = samples_of(m, x0, 1.0, 1.2, 200.0, x0.bg, x0.ba);
  const TimestampNs t1 = from_seconds(1.0 + 0.05);
  const auto prop = propagate(x0, samples, t1, kGravity, ImuNoise{});
  ASSERT_TRUE(prop.ok());
  const auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    const ImuState xp = x0.boxplus(d);
    const auto p = propagate(xp, samples, t1, kGravity, ImuNoise{});
    return p->state.boxminus(prop->state);
  };
  const Eigen::MatrixXd num = test::numeric_jacobian<double>(f, 15, 1e-6);
  // The transition is first order per 5 ms step: agreement to O(dt * |w|, dt * |a|).
  EXPECT_TRUE(test::matrices_near(prop->Phi, num, 2e-3));
}

TEST(Propagator, FirstEstimateBlocksAreExactAtTheStartAndKeepTheYawDirection) {
  const Motion m;
  const ImuState x0 = start_state();
  const auto samples = samples_of(m, x0, 1.0, 1.2, 200.0, x0.bg, x0.ba);
  const auto prop = propagate(x0, samples, from_seconds(1.05), kGravity, ImuNoise{});
  ASSERT_TRUE(prop.ok());
  Mat15d fej = prop->Phi;
  apply_first_estimates(x0, prop->state, kGravity, &fej);
  EXPECT_TRUE(test::matrices_near(fej, prop->Phi, 2e-3));  // the closed forms equal the product
  // From a different first estimate, the global-yaw direction of that estimate maps onto
  // the yaw direction of the propagated end.
  ImuState x0_fej = x0.boxplus(
      (Vec15d() << 0.01, -0.02, 0.015, 0.03, 0.02, -0.01, 0.02, 0.01, 0.0, Vec3d::Zero(), Vec3d::Zero())
          .finished());
  apply_first_estimates(x0_fej, prop->state, kGravity, &fej);
  const auto yaw = [&](const ImuState& x) {
    Vec15d n = Vec15d::Zero();
    const Vec3d z = Vec3d::UnitZ();
    n.segment<3>(0) = x.q_w_b.conjugate() * z;
    n.segment<3>(3) = z.cross(x.p_w_b);
    n.segment<3>(6) = z.cross(x.v_w_b);
    return n;
  };
  EXPECT_TRUE(test::matrices_near(Vec15d(fej * yaw(x0_fej)), yaw(prop->state), 1e-9));
}

TEST(Propagator, NoiseCovarianceMatchesMonteCarlo) {
  const Motion m;
  const ImuState x0 = start_state();
  const auto clean = samples_of(m, x0, 1.0, 1.2, 200.0, x0.bg, x0.ba);
  const ImuNoise noise{2e-3, 2e-2, 0.0, 0.0};  // white noise only (the walk is not simulated)
  const TimestampNs t1 = from_seconds(1.1);
  const auto prop = propagate(x0, clean, t1, kGravity, noise);
  ASSERT_TRUE(prop.ok());
  std::mt19937 rng(11);
  std::normal_distribution<double> n01(0.0, 1.0);
  const int runs = 3000;
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(9, 9);
  const double dt = 1.0 / 200.0;
  for (int k = 0; k < runs; ++k) {
    auto noisy = clean;
    for (auto& s : noisy) {
      for (int i = 0; i < 3; ++i) {
        s.gyro_radps[i] += noise.gyro_noise / std::sqrt(dt) * n01(rng);
        s.accel_mps2[i] += noise.accel_noise / std::sqrt(dt) * n01(rng);
      }
    }
    const auto p = propagate(x0, noisy, t1, kGravity, ImuNoise{});
    const Eigen::VectorXd e = p->state.boxminus(prop->state).head<9>();
    cov += e * e.transpose() / runs;
  }
  const Eigen::MatrixXd predicted = prop->Qd.topLeftCorner<9, 9>();
  // Per-sample noise entering a linear-in-time interpolation is slightly correlated with its
  // neighbours; the diagonal agrees within the Monte Carlo spread (~5 % at 3000 runs) + 15 %.
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(cov(i, i) / predicted(i, i), 1.0, 0.25) << "component " << i;
}

TEST(Propagator, StaticImuDoesNotDrift) {
  ImuState x0;
  x0.t_ns = 0;
  x0.q_w_b = so3::exp_quat<double>(Vec3d(0.05, -0.02, 1.0));
  x0.bg = Vec3d(0.002, -0.001, 0.003);
  x0.ba = Vec3d(0.02, -0.03, 0.01);
  std::vector<io::ImuSample> samples;
  for (int k = 0; k <= 2000; ++k) {  // 10 s at 200 Hz, exact readings of a body at rest
    samples.push_back({k * 5'000'000LL, x0.bg, x0.q_w_b.conjugate() * (-kGravity) + x0.ba});
  }
  const auto prop = propagate(x0, samples, 10'000'000'000LL, kGravity, ImuNoise{});
  ASSERT_TRUE(prop.ok());
  EXPECT_LT(prop->state.p_w_b.norm(), 1e-9);
  EXPECT_LT(prop->state.v_w_b.norm(), 1e-9);
  EXPECT_LT(quat::angular_distance(prop->state.q_w_b, x0.q_w_b), 1e-12);
}

TEST(Propagator, MissingImuCoverageIsAnErrorNamingTheInterval) {
  ImuState x0;
  x0.t_ns = 1000;
  const std::vector<io::ImuSample> samples = {{0, Vec3d::Zero(), Vec3d(0, 0, 9.81)},
                                              {5000, Vec3d::Zero(), Vec3d(0, 0, 9.81)}};
  const auto prop = propagate(x0, samples, 9000, kGravity, ImuNoise{});
  ASSERT_FALSE(prop.ok());
  EXPECT_EQ(prop.status().code(), absl::StatusCode::kOutOfRange);
  EXPECT_NE(prop.status().message().find("1000 .. 9000"), std::string::npos) << prop.status();
  EXPECT_FALSE(propagate(x0, samples, 500, kGravity, ImuNoise{}).ok());  // backwards
  const auto same = propagate(x0, samples, 1000, kGravity, ImuNoise{});
  ASSERT_TRUE(same.ok());
  EXPECT_TRUE(same->Phi.isIdentity());
}

}  // namespace
}  // namespace mrvs::edge
