// The GNSS error model as a pure function on long streams (stationary sd and lag-1
// autocorrelation of the Gauss-Markov error against the analytic values, outlier rate within
// binomial bounds, outlier size and direction), and the fixes along a trajectory: grid, lever
// arm, map frame, determinism, options and the truth file.
#include <cmath>
#include <cstdio>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/config/options.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/gnss_sim.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

using ::testing::HasSubstr;

constexpr std::size_t kFixes = 20000;
constexpr std::uint64_t kSeed = 7;

/// Sample statistics of one axis of the Gauss-Markov error (known mean 0).
struct AxisStats {
  double sd = 0.0;    ///< sqrt(mean e^2)
  double lag1 = 0.0;  ///< sum e[k] e[k+1] / sum e[k]^2
};

AxisStats axis_stats(const std::vector<GnssErrorSample>& errors, int axis) {
  double s2 = 0.0, s11 = 0.0;
  for (std::size_t k = 0; k < errors.size(); ++k) {
    const double e = errors[k].gauss_markov_m[axis];
    s2 += e * e;
    if (k + 1 < errors.size()) s11 += e * errors[k + 1].gauss_markov_m[axis];
  }
  return {std::sqrt(s2 / static_cast<double>(errors.size())), s11 / s2};
}

GnssSimOptions no_outliers(double tau_s) {
  GnssSimOptions o;
  o.correlation_time_s = tau_s;
  o.outlier_probability = 0.0;
  return o;
}

// With phi = exp(-dt / tau), the sample variance of N AR(1) values has a relative sd of about
// sqrt(2 (1 + phi^2) / ((1 - phi^2) N)), the lag-1 estimate an sd of sqrt((1 - phi^2) / N).
// The bounds below are about 5 of those sds (sd: also within the 30 % asked of the model).
TEST(GnssErrorModel, GaussMarkovHasTheStationarySigmaAndLag1Correlation) {
  struct Case {
    std::size_t fixes;
    double dt_s, tau_s, sd_tolerance, lag1_tolerance;
  };
  for (const Case& c : {Case{kFixes, 1.0, 30.0, 0.15, 0.010}, Case{10 * kFixes, 0.1, 30.0, 0.15, 0.001},
                        Case{kFixes, 1.0, 5.0, 0.06, 0.025}, Case{kFixes, 1.0, 0.0, 0.03, 0.035}}) {
    const GnssSimOptions o = no_outliers(c.tau_s);
    const auto errors = simulate_gnss_errors(c.fixes, c.dt_s, o, kSeed);
    ASSERT_EQ(errors.size(), c.fixes);
    const double phi = c.tau_s > 0.0 ? std::exp(-c.dt_s / c.tau_s) : 0.0;
    for (int axis = 0; axis < 3; ++axis) {
      const double sigma = axis < 2 ? o.sigma_horizontal_m : o.sigma_vertical_m;
      const AxisStats s = axis_stats(errors, axis);
      std::printf("dt %.1f s, tau %.0f s, axis %d: sd %.4f m (sigma %.2f), lag-1 %.5f (phi %.5f)\n", c.dt_s,
                  c.tau_s, axis, s.sd, sigma, s.lag1, phi);
      EXPECT_NEAR(s.sd / sigma, 1.0, c.sd_tolerance)
          << "dt " << c.dt_s << " tau " << c.tau_s << " axis " << axis;
      EXPECT_NEAR(s.lag1, phi, c.lag1_tolerance) << "dt " << c.dt_s << " tau " << c.tau_s << " axis " << axis;
    }
    for (const GnssErrorSample& e : errors) ASSERT_FALSE(e.outlier);
  }
}

TEST(GnssErrorModel, TheFirstFixIsAlreadyStationary) {
  // e[0] over many seeds has sd sigma (no start-up transient): 4000 seeds, sd of the estimate
  // about 1.1 %.
  const GnssSimOptions o = no_outliers(30.0);
  double s2_h = 0.0, s2_v = 0.0;
  constexpr int kSeeds = 4000;
  for (int seed = 0; seed < kSeeds; ++seed) {
    const Vec3d e = simulate_gnss_errors(1, 1.0, o, static_cast<std::uint64_t>(seed))[0].gauss_markov_m;
    s2_h += 0.5 * (e.x() * e.x() + e.y() * e.y());
    s2_v += e.z() * e.z();
  }
  EXPECT_NEAR(std::sqrt(s2_h / kSeeds) / o.sigma_horizontal_m, 1.0, 0.05);
  EXPECT_NEAR(std::sqrt(s2_v / kSeeds) / o.sigma_vertical_m, 1.0, 0.06);
}

TEST(GnssErrorModel, OutliersHaveTheRateSizeAndAHorizontalRandomDirection) {
  GnssSimOptions o;  // defaults: 2 % per fix, 15 m
  const auto errors = simulate_gnss_errors(kFixes, 1.0, o, kSeed);
  int outliers = 0;
  int quadrant[4] = {0, 0, 0, 0};
  for (const GnssErrorSample& e : errors) {
    if (!e.outlier) {
      ASSERT_EQ(e.outlier_m, Vec3d::Zero());
      continue;
    }
    ++outliers;
    ASSERT_NEAR(e.outlier_m.head<2>().norm(), o.outlier_m, 1e-9);
    ASSERT_EQ(e.outlier_m.z(), 0.0);
    ++quadrant[(e.outlier_m.x() >= 0 ? 0 : 1) + (e.outlier_m.y() >= 0 ? 0 : 2)];
  }
  // Binomial(20000, 0.02): mean 400, sd 19.8; 5 sd bounds.
  const double n = static_cast<double>(kFixes);
  const double mean = n * o.outlier_probability;
  const double sd = std::sqrt(n * o.outlier_probability * (1.0 - o.outlier_probability));
  std::printf("outliers: %d of %zu (expected %.0f +- %.1f), quadrants %d %d %d %d\n", outliers, kFixes, mean,
              sd, quadrant[0], quadrant[1], quadrant[2], quadrant[3]);
  EXPECT_GE(outliers, mean - 5.0 * sd);
  EXPECT_LE(outliers, mean + 5.0 * sd);
  // Each quadrant: Binomial(outliers, 1/4), 5 sd bounds.
  for (int q = 0; q < 4; ++q) {
    const double m = outliers / 4.0;
    EXPECT_NEAR(quadrant[q], m, 5.0 * std::sqrt(outliers * 0.25 * 0.75)) << q;
  }
  // Outliers do not enter the Gauss-Markov error: the same stream without them has the same e.
  const auto clean = simulate_gnss_errors(kFixes, 1.0, no_outliers(o.correlation_time_s), kSeed);
  for (std::size_t k = 0; k < kFixes; ++k) ASSERT_EQ(clean[k].gauss_markov_m, errors[k].gauss_markov_m) << k;
  o.outlier_probability = 1.0;
  for (const GnssErrorSample& e : simulate_gnss_errors(100, 1.0, o, kSeed)) ASSERT_TRUE(e.outlier);
}

TEST(GnssErrorModel, SameSeedSameErrorsSeedOffsetRedrawsThem) {
  GnssSimOptions o;
  const auto a = simulate_gnss_errors(50, 1.0, o, kSeed);
  const auto b = simulate_gnss_errors(50, 1.0, o, kSeed);
  const auto other_seed = simulate_gnss_errors(50, 1.0, o, kSeed + 1);
  o.seed_offset = 3;
  const auto offset = simulate_gnss_errors(50, 1.0, o, kSeed);
  for (std::size_t k = 0; k < 50; ++k) {
    ASSERT_EQ(a[k].total(), b[k].total());
    ASSERT_NE(a[k].gauss_markov_m, other_seed[k].gauss_markov_m);
    ASSERT_NE(a[k].gauss_markov_m, offset[k].gauss_markov_m);
  }
}

/// IMU-rate states of a body turning about z while moving: T_w_b(k).
std::vector<io::GroundTruthState> turning_states(std::size_t n, DurationNs period_ns) {
  std::vector<io::GroundTruthState> states(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * to_seconds(period_ns);
    states[k].t_ns = 1'544'590'800'000'000'000 + static_cast<TimestampNs>(k) * period_ns;
    states[k].T_w_b =
        SE3d(Quatd(Eigen::AngleAxisd(0.3 * t, Vec3d::UnitZ()) * Eigen::AngleAxisd(0.05, Vec3d::UnitX())),
             Vec3d(10.0 * t, 2.0 * std::sin(t), 1.7));
  }
  return states;
}

TEST(SimulateGnss, FixesAreOnTheImuGridAtTheAntennaInTheMapFrame) {
  const std::vector<io::GroundTruthState> states = turning_states(1001, 10'000'000);  // 10 s at 100 Hz
  const SE3d T_map_world(Quatd(Eigen::AngleAxisd(0.02, Vec3d(1, 2, 3).normalized())), Vec3d(0.5, -0.2, 0.1));
  GnssSimOptions o;
  o.enabled = true;
  for (const double rate_hz : {1.0, 10.0, 2.0}) {
    o.rate_hz = rate_hz;
    auto fixes = simulate_gnss(states, T_map_world, o, kSeed);
    ASSERT_TRUE(fixes.ok()) << fixes.status();
    const std::size_t stride = static_cast<std::size_t>(std::lround(100.0 / rate_hz));
    ASSERT_EQ(fixes->size(), 1000 / stride + 1) << rate_hz;
    const auto errors = simulate_gnss_errors(fixes->size(), 1.0 / rate_hz, o, kSeed);
    for (std::size_t k = 0; k < fixes->size(); ++k) {
      const GnssSimFix& f = (*fixes)[k];
      const io::GroundTruthState& s = states[k * stride];
      ASSERT_EQ(f.t_ns, s.t_ns);
      const Vec3d antenna_w = s.T_w_b.translation() + s.T_w_b.quaternion() * Vec3d(o.lever_arm_m);
      ASSERT_LT((f.p_true_map - T_map_world * antenna_w).norm(), 1e-9) << k;
      ASSERT_LT((f.p_measured_map - f.p_true_map - errors[k].total()).norm(), 1e-9) << k;
      ASSERT_EQ(f.outlier, errors[k].outlier);
    }
  }
  // The first fix is the first IMU stamp; the last one is within the window.
  o.rate_hz = 1.0;
  auto short_window = simulate_gnss(turning_states(250, 10'000'000), T_map_world, o, kSeed);
  ASSERT_TRUE(short_window.ok());
  ASSERT_EQ(short_window->size(), 3u);  // 0, 1, 2 s of 2.49 s
  EXPECT_EQ(short_window->back().t_ns - short_window->front().t_ns, 2'000'000'000);
}

TEST(SimulateGnss, RatesOffTheImuGridAndBadOptionsAreErrors) {
  const auto states = turning_states(300, 10'000'000);
  GnssSimOptions o;
  o.rate_hz = 3.0;
  auto off_grid = simulate_gnss(states, SE3d(), o, kSeed);
  ASSERT_FALSE(off_grid.ok());
  EXPECT_THAT(std::string(off_grid.status().message()), HasSubstr("gnss.rate_hz = 3 Hz"));
  EXPECT_THAT(std::string(off_grid.status().message()),
              HasSubstr("whole number of IMU periods (10000000 ns)"));
  o.rate_hz = 200.0;  // faster than the IMU
  EXPECT_FALSE(simulate_gnss(states, SE3d(), o, kSeed).ok());
  o.rate_hz = 0.5;  // one fix per 2 s is fine
  EXPECT_TRUE(simulate_gnss(states, SE3d(), o, kSeed).ok());
  o.sigma_vertical_m = -1.0;
  auto bad = simulate_gnss(states, SE3d(), o, kSeed);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr("gnss.sigma_vertical_m"));
  EXPECT_FALSE(simulate_gnss({}, SE3d(), GnssSimOptions{}, kSeed).ok());
  EXPECT_EQ(*gnss_period_ns(10.0, 10'000'000), 100'000'000);
  EXPECT_EQ(*gnss_period_ns(1.0, 5'000'000), 1'000'000'000);
}

TEST(SimulateGnss, OptionsRoundTripThroughYaml) {
  GnssSimOptions o;
  o.enabled = true;
  o.rate_hz = 10.0;
  o.lever_arm_m = Vec3d(0.1, -0.2, 1.5);
  o.seed_offset = 9;
  EXPECT_TRUE(config::validate_options(o).ok());
  const std::string text = config::options_to_yaml(o, "gnss");
  auto doc = config::parse_yaml_string(text);
  ASSERT_TRUE(doc.ok()) << doc.status();
  auto loaded = config::load_options<GnssSimOptions>(*doc, "gnss");
  ASSERT_TRUE(loaded.ok()) << loaded.status() << "\n" << text;
  EXPECT_TRUE(*loaded == o) << text;
  auto bad = config::parse_yaml_string("gnss:\n  outlier_probability: 1.5\n");
  ASSERT_TRUE(bad.ok());
  EXPECT_FALSE(config::load_options<GnssSimOptions>(*bad, "gnss").ok());
}

TEST(GnssTruthCsv, RoundTripsAndNamesBadLines) {
  const test::TempDir dir;
  GnssSimOptions o;
  o.rate_hz = 10.0;
  o.outlier_probability = 0.3;
  auto fixes = simulate_gnss(turning_states(1001, 10'000'000), SE3d(), o, kSeed);
  ASSERT_TRUE(fixes.ok());
  ASSERT_TRUE(write_gnss_truth_csv(dir / "sim0/gnss_truth.csv", *fixes).ok());
  auto back = read_gnss_truth_csv(dir / "sim0/gnss_truth.csv");
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), fixes->size());
  int outliers = 0;
  for (std::size_t k = 0; k < fixes->size(); ++k) {
    EXPECT_EQ((*back)[k].t_ns, (*fixes)[k].t_ns);
    EXPECT_EQ((*back)[k].p_true_map, (*fixes)[k].p_true_map);
    EXPECT_EQ((*back)[k].outlier, (*fixes)[k].outlier);
    outliers += (*fixes)[k].outlier;
  }
  EXPECT_GT(outliers, 0);
  const auto bad =
      dir.write("bad.csv", "#timestamp [ns],p_x [m],p_y [m],p_z [m],outlier\n1,2,3,4,0\n2,2,3,4,yes\n");
  auto error = read_gnss_truth_csv(bad);
  ASSERT_FALSE(error.ok());
  EXPECT_THAT(std::string(error.status().message()), HasSubstr(bad.string() + ":3: field 5 ('outlier')"));
}

}  // namespace
}  // namespace mrvs::sim
