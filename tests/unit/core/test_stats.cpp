#include "mrvs/core/stats.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

namespace mrvs {
namespace {

TEST(Quantile, NearestRankAgainstAFullSort) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-5.0, 5.0);
  for (int n : {1, 2, 7, 100, 1001}) {
    std::vector<double> v(static_cast<std::size_t>(n));
    for (double& x : v) x = u(rng);
    std::vector<double> sorted = v;
    std::sort(sorted.begin(), sorted.end());
    for (double q : {0.0, 0.1, 0.5, 0.9, 0.95, 1.0}) {
      const auto k = static_cast<std::size_t>(std::floor(q * (n - 1) + 0.5));
      EXPECT_EQ(quantile(v, q), sorted[k]) << "n " << n << " q " << q;
    }
  }
  EXPECT_EQ(quantile({3.0, 1.0, 2.0}, 0.5), 2.0);
  EXPECT_EQ(quantile({3.0, 1.0, 2.0}, 7.0), 3.0);  // q clamped to [0, 1]
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
}

}  // namespace
}  // namespace mrvs
