#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr int kN = 200000;

TEST(CounterRng, UniformHasTheMomentsOfU01) {
  const CounterRng rng(1, Stream::kImuNoise);
  double sum = 0, sum2 = 0, lo = 1, hi = 0;
  for (int i = 0; i < kN; ++i) {
    const double u = rng.uniform(i);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum2 += u * u;
    lo = std::min(lo, u);
    hi = std::max(hi, u);
  }
  const double mean = sum / kN;
  const double var = sum2 / kN - mean * mean;
  EXPECT_NEAR(mean, 0.5, 4 * std::sqrt(1.0 / 12 / kN));
  EXPECT_NEAR(var, 1.0 / 12, 0.002);
  EXPECT_LT(lo, 1e-4);
  EXPECT_GT(hi, 1 - 1e-4);
}

TEST(CounterRng, NormalHasZeroMeanUnitVarianceAndGaussianTails) {
  const CounterRng rng(7, Stream::kImageNoise);
  double sum = 0, sum2 = 0, sum4 = 0;
  int beyond2 = 0;
  for (int i = 0; i < kN; ++i) {
    const double x = rng.normal(i, 3, 5);
    ASSERT_TRUE(std::isfinite(x));
    sum += x;
    sum2 += x * x;
    sum4 += x * x * x * x;
    beyond2 += std::abs(x) > 2.0;
  }
  EXPECT_NEAR(sum / kN, 0.0, 4 / std::sqrt(kN));
  EXPECT_NEAR(sum2 / kN, 1.0, 0.01);
  EXPECT_NEAR(sum4 / kN, 3.0, 0.06);                 // kurtosis of a Gaussian
  EXPECT_NEAR(beyond2 / double(kN), 0.0455, 0.003);  // P(|x| > 2)
}

TEST(CounterRng, NormalPairsAreTwoIndependentStandardNormals) {
  const CounterRng rng(11, Stream::kImageNoise);
  double s1 = 0, s2 = 0, q1 = 0, q2 = 0, x12 = 0, x12sq = 0;
  for (int i = 0; i < kN; ++i) {
    const auto [a, b] = rng.normal_pair(i, 2);
    ASSERT_EQ(a, rng.normal(i, 2));  // the first is normal()
    s1 += a, s2 += b, q1 += a * a, q2 += b * b, x12 += a * b, x12sq += a * a * b * b;
  }
  EXPECT_NEAR(s2 / kN, 0.0, 4 / std::sqrt(kN));
  EXPECT_NEAR(q1 / kN, 1.0, 0.01);
  EXPECT_NEAR(q2 / kN, 1.0, 0.01);
  EXPECT_LT(std::abs(x12 / kN), 4 / std::sqrt(kN));
  // Independent, not merely uncorrelated: E[a^2 b^2] = E[a^2] E[b^2] = 1.
  EXPECT_NEAR(x12sq / kN, 1.0, 0.03);
}

TEST(CounterRng, IsAPureFunctionOfSeedStreamAndIndex) {
  const CounterRng a(42, Stream::kMapNoise);
  const CounterRng b(42, Stream::kMapNoise);
  for (int i = 0; i < 1000; ++i) ASSERT_EQ(a.bits(i, 2, 9), b.bits(i, 2, 9));
  // Order of evaluation does not matter (no state).
  EXPECT_EQ(a.bits(5), a.bits(5));
}

TEST(CounterRng, SeedsStreamsAndIndicesAreIndependent) {
  const CounterRng base(1, Stream::kImuNoise);
  const CounterRng other_seed(2, Stream::kImuNoise);
  const CounterRng other_stream(1, Stream::kBiasWalk);
  int same_seed = 0, same_stream = 0;
  std::set<std::uint64_t> seen;
  for (int i = 0; i < 10000; ++i) {
    same_seed += base.bits(i) == other_seed.bits(i);
    same_stream += base.bits(i) == other_stream.bits(i);
    seen.insert(base.bits(i));
    seen.insert(base.bits(0, i));
    seen.insert(base.bits(0, 0, i));
  }
  EXPECT_EQ(same_seed, 0);
  EXPECT_EQ(same_stream, 0);
  EXPECT_EQ(seen.size(), 3u * 10000u - 2u);  // (0,0,0) appears in all three families
}

TEST(CounterRng, NeighbouringIndicesAreUncorrelated) {
  const CounterRng rng(3, Stream::kScene);
  double sxy = 0, sx = 0, sy = 0, sxx = 0, syy = 0;
  for (int i = 0; i < kN; ++i) {
    const double x = rng.normal(i), y = rng.normal(i + 1);
    sx += x, sy += y, sxy += x * y, sxx += x * x, syy += y * y;
  }
  const double cov = sxy / kN - (sx / kN) * (sy / kN);
  const double corr = cov / std::sqrt((sxx / kN - sx * sx / kN / kN) * (syy / kN - sy * sy / kN / kN));
  EXPECT_LT(std::abs(corr), 4 / std::sqrt(kN));
}

TEST(SequenceRng, ReplaysTheCounterSequence) {
  SequenceRng seq(9, Stream::kRoute);
  const CounterRng rng(9, Stream::kRoute);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(seq.uniform(), rng.uniform(i));
  SequenceRng ints(9, Stream::kRoute);
  std::vector<int> counts(6, 0);
  for (int i = 0; i < 60000; ++i) {
    const int k = ints.integer(2, 7);
    ASSERT_GE(k, 2);
    ASSERT_LE(k, 7);
    ++counts[k - 2];
  }
  for (int c : counts) EXPECT_NEAR(c, 10000, 400);
}

}  // namespace
}  // namespace mrvs::sim
