// simulate_imu: strapdown integration back to the spline GT (simulator.md 6.4, 6.5), noise
// and bias-walk statistics (6.6), static start (6.7), sampling modes and determinism.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "mrvs/sim/imu_sim.h"
#include "mrvs/sim/test/strapdown.h"
#include "mrvs/sim/time_grid.h"

namespace mrvs::sim {
namespace {

using test::kRadToDeg;
using test::NavState;

constexpr DurationNs kDt = 5'000'000;
constexpr std::uint64_t kSeed = 42;

struct Sequence {
  SplineTrajectory spline;
  std::vector<TimestampNs> stamps;
};

Sequence make_sequence(const std::string& name, const TrajectoryOptions& options = {}) {
  auto spline = SplineTrajectory::fit(test::load_euroc_gt(name), options);
  EXPECT_TRUE(spline.ok()) << spline.status();
  auto grid = make_time_grid(spline->t_begin_ns(), spline->t_end_ns(), euroc_time_grid());
  EXPECT_TRUE(grid.ok()) << grid.status();
  return {*std::move(spline), grid->imu_ns};
}

struct Errors {
  double pos = 0.0, rot_deg = 0.0, vel = 0.0;
};

/// Integrates 1 s (200 samples) from sample `first` starting at the spline state and
/// compares with the spline at the end. `subtract_bias`: measured - true bias, else noiseless.
Errors integrate_one_second(const Sequence& seq, const std::vector<ImuSimSample>& imu, std::size_t first,
                            bool use_measured) {
  std::vector<Vec3d> gyro(imu.size()), accel(imu.size());
  for (std::size_t k = first; k <= first + 200; ++k) {
    gyro[k] =
        use_measured ? Vec3d(imu[k].measured.gyro_radps - imu[k].bias_gyro) : imu[k].noiseless.gyro_radps;
    accel[k] =
        use_measured ? Vec3d(imu[k].measured.accel_mps2 - imu[k].bias_accel) : imu[k].noiseless.accel_mps2;
  }
  const Kinematics k0 = *seq.spline.evaluate(seq.stamps[first]);
  const Kinematics k1 = *seq.spline.evaluate(seq.stamps[first + 200]);
  NavState s{k0.T_w_b.quaternion(), k0.T_w_b.translation(), k0.v_w};
  s = test::integrate_midpoint(s, gyro, accel, first, first + 200, to_seconds(kDt), 9.81);
  Errors e;
  e.pos = (s.p_w - k1.T_w_b.translation()).norm();
  e.rot_deg = quat::angular_distance(s.q_w_b, k1.T_w_b.quaternion()) * kRadToDeg;
  e.vel = (s.v_w - k1.v_w).norm();
  return e;
}

/// Start index of the 1 s window with the largest sum of |a_w| + |omega| (the most dynamic).
std::size_t most_dynamic_start(const Sequence& seq) {
  std::vector<double> score(seq.stamps.size());
  for (std::size_t k = 0; k < seq.stamps.size(); ++k) {
    const Kinematics kin = *seq.spline.evaluate(seq.stamps[k]);
    score[k] = kin.a_w.norm() + kin.omega_b.norm();
  }
  double window = 0.0, best = -1.0;
  std::size_t best_k = 0;
  for (std::size_t k = 0; k < score.size(); ++k) {
    window += score[k];
    if (k >= 200) window -= score[k - 200];
    if (k >= 200 && window > best) {
      best = window;
      best_k = k - 200;
    }
  }
  return best_k;
}

void check_strapdown(const std::string& name) {
  const Sequence seq = make_sequence(name);
  auto imu = simulate_imu(seq.spline, seq.stamps, ImuSimOptions{}, kSeed);
  ASSERT_TRUE(imu.ok()) << imu.status();
  std::vector<std::size_t> starts = {0, 2000, 5000, 9000, 14000, most_dynamic_start(seq)};
  Errors clean_max, noisy_max;
  for (std::size_t first : starts) {
    ASSERT_LT(first + 200, seq.stamps.size());
    const Errors c = integrate_one_second(seq, *imu, first, false);
    const Errors n = integrate_one_second(seq, *imu, first, true);
    clean_max = {std::max(clean_max.pos, c.pos), std::max(clean_max.rot_deg, c.rot_deg),
                 std::max(clean_max.vel, c.vel)};
    noisy_max = {std::max(noisy_max.pos, n.pos), std::max(noisy_max.rot_deg, n.rot_deg),
                 std::max(noisy_max.vel, n.vel)};
  }
  std::printf(
      "[strapdown %s] most dynamic window at %.2f s; noiseless max %.4f mm, %.5f deg, %.4f mm/s; "
      "noisy-bias max %.3f mm, %.4f deg\n",
      name.c_str(), to_seconds(seq.stamps[starts.back()] - seq.stamps[0]), clean_max.pos * 1e3,
      clean_max.rot_deg, clean_max.vel * 1e3, noisy_max.pos * 1e3, noisy_max.rot_deg);
  EXPECT_LT(clean_max.pos, 1e-3);
  EXPECT_LT(clean_max.rot_deg, 0.01);
  EXPECT_LT(clean_max.vel, 1e-3);
  EXPECT_LT(noisy_max.pos, 1e-2);
  EXPECT_LT(noisy_max.rot_deg, 0.1);
}

TEST(ImuSim, StrapdownReproducesSplineV101) { check_strapdown("V1_01_easy.txt"); }
TEST(ImuSim, StrapdownReproducesSplineV201) { check_strapdown("V2_01_easy.txt"); }

TEST(ImuSim, NoiseAndBiasWalkStatistics) {
  const Sequence full = make_sequence("V1_01_easy.txt");
  const std::vector<TimestampNs> stamps(full.stamps.begin(), full.stamps.begin() + 8001);  // 40 s
  auto imu = simulate_imu(full.spline, stamps, ImuSimOptions{}, kSeed);
  ASSERT_TRUE(imu.ok()) << imu.status();
  const double dt = to_seconds(kDt);
  const ImuSimOptions o;
  const double expected[4] = {
      o.gyroscope_noise_density / std::sqrt(dt), o.accelerometer_noise_density / std::sqrt(dt),
      o.gyroscope_random_walk * std::sqrt(dt), o.accelerometer_random_walk * std::sqrt(dt)};
  const std::size_t n = imu->size() - 1;
  for (int axis = 0; axis < 3; ++axis) {
    double sum[4] = {0, 0, 0, 0}, sum2[4] = {0, 0, 0, 0};
    for (std::size_t k = 0; k < n; ++k) {
      const ImuSimSample& s = (*imu)[k];
      const ImuSimSample& s1 = (*imu)[k + 1];
      const double x[4] = {s.measured.gyro_radps[axis] - s.noiseless.gyro_radps[axis] - s.bias_gyro[axis],
                           s.measured.accel_mps2[axis] - s.noiseless.accel_mps2[axis] - s.bias_accel[axis],
                           s1.bias_gyro[axis] - s.bias_gyro[axis], s1.bias_accel[axis] - s.bias_accel[axis]};
      for (int j = 0; j < 4; ++j) {
        sum[j] += x[j];
        sum2[j] += x[j] * x[j];
      }
    }
    for (int j = 0; j < 4; ++j) {
      const double mean = sum[j] / n;
      const double sd = std::sqrt(sum2[j] / n - mean * mean);
      if (axis == 0) {
        std::printf("[noise] stream %d axis x: std %.5g, expected %.5g (ratio %.4f)\n", j, sd, expected[j],
                    sd / expected[j]);
      }
      EXPECT_NEAR(sd / expected[j], 1.0, 0.05) << "stream " << j << " axis " << axis;
      EXPECT_LT(std::abs(mean), 4.0 * expected[j] / std::sqrt(static_cast<double>(n))) << "stream " << j;
    }
  }
  EXPECT_EQ((*imu)[0].bias_gyro, o.initial_gyro_bias);
  EXPECT_EQ((*imu)[0].bias_accel, o.initial_accel_bias);
}

TEST(ImuSim, StaticStartSeesGravity) {
  const Sequence seq = make_sequence("V1_01_easy.txt");
  auto imu = simulate_imu(seq.spline, seq.stamps, ImuSimOptions{}, kSeed);
  ASSERT_TRUE(imu.ok()) << imu.status();
  Vec3d mean_a = Vec3d::Zero(), mean_clean = Vec3d::Zero();
  double mean_w = 0.0;
  const int n = 400;  // first 2 s
  for (int k = 0; k < n; ++k) {
    mean_a += ((*imu)[k].measured.accel_mps2 - (*imu)[k].bias_accel) / n;
    mean_clean += (*imu)[k].noiseless.accel_mps2 / n;
    mean_w += (*imu)[k].noiseless.gyro_radps.norm() / n;
  }
  std::printf("[static start] |mean(a_m - b_a)| = %.5f m/s^2 (noiseless %.5f), mean |w_true| = %.5f rad/s\n",
              mean_a.norm(), mean_clean.norm(), mean_w);
  EXPECT_NEAR(mean_a.norm(), 9.81, 0.01);
  EXPECT_NEAR(mean_clean.norm(), 9.81, 0.01);
  EXPECT_LT(mean_w, 0.01);
}

TEST(ImuSim, StaticPrefixIsExact) {
  TrajectoryOptions t;
  t.static_prefix_s = 2.0;
  const Sequence seq = make_sequence("V1_01_easy.txt", t);
  ImuSimOptions o;
  o.noise_scale = 0.0;
  auto imu = simulate_imu(seq.spline, std::vector<TimestampNs>(seq.stamps.begin(), seq.stamps.begin() + 600),
                          o, kSeed);
  ASSERT_TRUE(imu.ok()) << imu.status();
  const Quatd q = seq.spline.control_points().front().quaternion();
  const Vec3d f = q.conjugate() * Vec3d(0.0, 0.0, 9.81);
  for (int k = 0; k <= 400; ++k) {
    const ImuSimSample& s = (*imu)[k];
    ASSERT_EQ(s.noiseless.gyro_radps, Vec3d::Zero()) << k;
    ASSERT_LT((s.noiseless.accel_mps2 - f).norm(), 1e-14) << k;
    ASSERT_EQ(s.measured.gyro_radps, s.noiseless.gyro_radps + o.initial_gyro_bias);
    ASSERT_EQ(s.measured.accel_mps2, s.noiseless.accel_mps2 + o.initial_accel_bias);
  }
  // The prefix ends and the real motion blends in.
  EXPECT_GT((*imu)[599].noiseless.gyro_radps.norm(), 0.0);
}

TEST(ImuSim, DeterminismAndIndependentStreams) {
  const Sequence full = make_sequence("V1_01_easy.txt");
  const std::vector<TimestampNs> stamps(full.stamps.begin() + 1000, full.stamps.begin() + 3000);
  const ImuSimOptions o;
  const auto a = *simulate_imu(full.spline, stamps, o, kSeed);
  const auto b = *simulate_imu(full.spline, stamps, o, kSeed);
  const auto c = *simulate_imu(full.spline, stamps, o, kSeed + 1);
  ImuSimOptions rw = o;
  rw.bias_rw_scale = 3.0;
  const auto d = *simulate_imu(full.spline, stamps, rw, kSeed);
  ImuSimOptions off = o;
  off.noise_scale = 0.0;
  const auto e = *simulate_imu(full.spline, stamps, off, kSeed);
  int differs = 0;
  for (std::size_t k = 0; k < stamps.size(); ++k) {
    ASSERT_EQ(a[k].measured.t_ns, stamps[k]);
    ASSERT_EQ(a[k].measured.gyro_radps, b[k].measured.gyro_radps);
    ASSERT_EQ(a[k].measured.accel_mps2, b[k].measured.accel_mps2);
    ASSERT_EQ(a[k].bias_accel, b[k].bias_accel);
    ASSERT_EQ(a[k].noiseless.accel_mps2, c[k].noiseless.accel_mps2);
    differs += a[k].measured.gyro_radps != c[k].measured.gyro_radps ? 1 : 0;
    // The bias walk scale does not touch the white noise.
    const Vec3d na = a[k].measured.accel_mps2 - a[k].noiseless.accel_mps2 - a[k].bias_accel;
    const Vec3d nd = d[k].measured.accel_mps2 - d[k].noiseless.accel_mps2 - d[k].bias_accel;
    ASSERT_LT((na - nd).norm(), 1e-12);
    ASSERT_EQ(e[k].measured.gyro_radps, e[k].noiseless.gyro_radps + o.initial_gyro_bias);
    ASSERT_EQ(e[k].measured.accel_mps2, e[k].noiseless.accel_mps2 + o.initial_accel_bias);
    ASSERT_EQ(e[k].bias_gyro, o.initial_gyro_bias);
  }
  EXPECT_EQ(differs, static_cast<int>(stamps.size()));
  EXPECT_GT((d.back().bias_accel - o.initial_accel_bias).norm(),
            (a.back().bias_accel - o.initial_accel_bias).norm());
  const ImuNoiseDensities eff = effective_noise_densities(rw);
  EXPECT_DOUBLE_EQ(eff.accelerometer_random_walk, 9.0e-3);
  EXPECT_DOUBLE_EQ(eff.gyroscope_noise_density, 1.6968e-4);
}

TEST(ImuSim, AverageSamplingIsTheIntervalMean) {
  const Sequence full = make_sequence("V1_01_easy.txt");
  const std::vector<TimestampNs> stamps(full.stamps.begin(), full.stamps.begin() + 6000);
  ImuSimOptions o;
  o.noise_scale = 0.0;
  o.sampling = ImuSampling::kAverage;
  const auto avg = *simulate_imu(full.spline, stamps, o, kSeed);
  o.sampling = ImuSampling::kInstant;
  const auto inst = *simulate_imu(full.spline, stamps, o, kSeed);
  // The interval mean of omega is the rotation increment over [t_k - dt, t_k] (up to coning).
  double err_avg = 0.0, err_inst = 0.0;
  for (std::size_t k = 1; k < stamps.size(); ++k) {
    const Quatd q0 = full.spline.evaluate(stamps[k - 1])->T_w_b.quaternion();
    const Quatd q1 = full.spline.evaluate(stamps[k])->T_w_b.quaternion();
    const Vec3d inc = so3::log<double>(q0.conjugate() * q1) / to_seconds(kDt);
    err_avg = std::max(err_avg, (avg[k].noiseless.gyro_radps - inc).norm());
    err_inst = std::max(err_inst, (inst[k].noiseless.gyro_radps - inc).norm());
  }
  std::printf("[average sampling] max |mean gyro - dR/dt| %.3g rad/s (instant %.3g)\n", err_avg, err_inst);
  EXPECT_LT(err_avg, 1e-4);
  EXPECT_GT(err_inst, 10.0 * err_avg);
  // The first sample averages over [t0 - dt, t0], inside the spline's support.
  EXPECT_EQ(avg[0].noiseless.t_ns, stamps[0]);
}

TEST(ImuSim, RejectsBadStamps) {
  const Sequence seq = make_sequence("V1_01_easy.txt");
  EXPECT_FALSE(simulate_imu(seq.spline, {seq.stamps[0]}, {}, kSeed).ok());
  EXPECT_FALSE(simulate_imu(seq.spline, {seq.stamps[0], seq.stamps[1], seq.stamps[3]}, {}, kSeed).ok());
  const auto outside =
      simulate_imu(seq.spline, {seq.spline.support_end_ns(), seq.spline.support_end_ns() + kDt}, {}, kSeed);
  EXPECT_EQ(outside.status().code(), absl::StatusCode::kOutOfRange);
  ImuSimOptions bad;
  bad.noise_scale = -1.0;
  EXPECT_FALSE(simulate_imu(seq.spline, {seq.stamps[0], seq.stamps[1]}, bad, kSeed).ok());
}

}  // namespace
}  // namespace mrvs::sim
