// Saliency: synthetic edges with known answers and a brute-force evaluation of the formula.
#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Eigenvalues>

#include "map_test_util.h"
#include "mrvs/map/saliency.h"

namespace mrvs::map {
namespace {

struct LocalCloud {
  std::vector<Eigen::Vector3f> positions;
  std::vector<float> intensities;
};

LocalCloud to_local(const RawCloud& raw) {
  LocalCloud c;
  for (std::size_t i = 0; i < raw.size(); ++i) {
    c.positions.push_back(raw.positions[i].cast<float>());
    c.intensities.push_back(raw.intensities[i]);
  }
  return c;
}

/// A flat plane z = 0 on a 1 cm grid, nx x ny points, intensity 0 for column i < step, 1 beyond.
LocalCloud intensity_step_plane(int nx, int ny, int step, double y0) {
  LocalCloud c;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      c.positions.emplace_back(0.01f * static_cast<float>(i), static_cast<float>(y0 + 0.01 * j), 0.0f);
      c.intensities.push_back(i < step ? 0.0f : 1.0f);
    }
  }
  return c;
}

TEST(Saliency, IntensityStepOnAPlane) {
  const LocalCloud c = intensity_step_plane(40, 30, 20, 0.0);
  auto s = compute_saliency(c.positions, c.intensities, SaliencyOptions{});
  ASSERT_TRUE(s.ok()) << s.status();
  const float max_s = *std::max_element(s->begin(), s->end());
  // Columns 19 and 20 touch the step: |dI| / d = 1 / 0.01, no normal term on a flat plane.
  EXPECT_NEAR(max_s, 100.0f, 1e-3f);
  for (int i = 0; i < 40; ++i) {
    for (int j = 0; j < 30; ++j) {
      const float v = (*s)[static_cast<std::size_t>(i * 30 + j)];
      if (i == 19 || i == 20) {
        EXPECT_NEAR(v, max_s, 1e-3f) << i << "," << j;
      } else {
        EXPECT_LT(v, 0.6f * max_s) << i << "," << j;  // next column: 1 / 0.02 at most
      }
      if (i < 17 || i > 22) {
        EXPECT_EQ(v, 0.0f) << i << "," << j;  // no contrast within K = 16
      }
    }
  }
}

/// Adds a depth step: plane z = 0 for columns < step, z = h beyond, intensity 0 / contrast.
void add_depth_step(LocalCloud& c, int nx, int ny, int step, double y0, float h, float contrast) {
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      c.positions.emplace_back(0.01f * static_cast<float>(i), static_cast<float>(y0 + 0.01 * j),
                               i < step ? 0.0f : h);
      c.intensities.push_back(i < step ? 0.0f : contrast);
    }
  }
}

TEST(Saliency, DepthEdgeWinsOnlyWithTheNormalTerm) {
  // Region A (y in [0, 0.3)): in-plane intensity step, S = 1 / 0.01 = 100 whatever alpha.
  // Region B (y in [1, 1.3)): a 1 cm depth step whose shortest crossing (1 cm across, 1 cm up)
  // has |dI| / d = 90: weaker photometrically, but along the normal.
  LocalCloud c = intensity_step_plane(40, 30, 20, 0.0);
  const std::size_t region_b = c.positions.size();
  add_depth_step(c, 40, 30, 20, 1.0, 0.01f, static_cast<float>(90.0 * std::sqrt(2.0) * 0.01));
  auto in_region_b = [&](std::size_t i) { return i >= region_b; };
  auto column = [&](std::size_t i) { return static_cast<int>((i % region_b) / 30); };

  SaliencyOptions no_normal;
  no_normal.alpha = 0.0;
  auto s0 = compute_saliency(c.positions, c.intensities, no_normal);
  ASSERT_TRUE(s0.ok()) << s0.status();
  const auto best0 = static_cast<std::size_t>(std::max_element(s0->begin(), s0->end()) - s0->begin());
  EXPECT_FALSE(in_region_b(best0)) << "alpha = 0 must prefer the stronger intensity edge";
  EXPECT_NEAR((*s0)[best0], 100.0f, 1e-3f);

  SaliencyOptions with_normal;  // alpha = 1
  auto s1 = compute_saliency(c.positions, c.intensities, with_normal);
  ASSERT_TRUE(s1.ok()) << s1.status();
  const auto best1 = static_cast<std::size_t>(std::max_element(s1->begin(), s1->end()) - s1->begin());
  EXPECT_TRUE(in_region_b(best1)) << "alpha = 1 must prefer the depth edge";
  EXPECT_TRUE(column(best1) == 19 || column(best1) == 20) << column(best1);
  EXPECT_GT((*s1)[best1], 110.0f);
  // The flat intensity edge is unchanged by alpha.
  EXPECT_NEAR((*s1)[19 * 30 + 15], 100.0f, 1e-3f);
}

/// Brute force: K nearest other points by (distance, index), normal by a double-precision
/// eigen decomposition of the K + 1 points, the formula term by term.
std::vector<double> brute_force(const LocalCloud& c, int k, double alpha) {
  const std::size_t n = c.positions.size();
  std::vector<double> out(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<std::size_t> order(n);
    std::iota(order.begin(), order.end(), 0);
    const Eigen::Vector3d p = c.positions[i].cast<double>();
    auto dist = [&](std::size_t j) { return (c.positions[j].cast<double>() - p).norm(); };
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return dist(a) != dist(b) ? dist(a) < dist(b) : a < b; });
    std::vector<std::size_t> hood(order.begin(), order.begin() + std::min<std::size_t>(k + 1, n));
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::size_t j : hood) mean += c.positions[j].cast<double>();
    mean /= static_cast<double>(hood.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::size_t j : hood) {
      const Eigen::Vector3d d = c.positions[j].cast<double>() - mean;
      cov += d * d.transpose();
    }
    const Eigen::Vector3d normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
    double best = 0.0;
    for (std::size_t j : hood) {
      const double d = dist(j);
      if (d < 1e-6) continue;
      const Eigen::Vector3d u = (c.positions[j].cast<double>() - p) / d;
      const double gradient = std::abs(double(c.intensities[i]) - double(c.intensities[j])) / d;
      best = std::max(best, gradient * (1.0 + alpha * std::abs(normal.dot(u))));
    }
    out[i] = best;
  }
  return out;
}

TEST(Saliency, MatchesBruteForceOnARandomSurface) {
  const LocalCloud c = to_local(test::wavy_cloud(600, 7, 0.3, 0.0005));
  for (const auto& [k, alpha] : std::vector<std::pair<int, double>>{{16, 1.0}, {8, 0.7}, {5, 3.0}}) {
    SaliencyOptions options;
    options.knn = k;
    options.alpha = alpha;
    auto s = compute_saliency(c.positions, c.intensities, options);
    ASSERT_TRUE(s.ok()) << s.status();
    const std::vector<double> expected = brute_force(c, k, alpha);
    int far = 0;
    for (std::size_t i = 0; i < expected.size(); ++i) {
      if (std::abs((*s)[i] - expected[i]) > 1e-4 * std::max(1.0, expected[i])) ++far;
    }
    EXPECT_EQ(far, 0) << "K " << k << ", alpha " << alpha;
  }
}

TEST(Saliency, DuplicatesAndIsolatedPointsAreHarmless) {
  LocalCloud c;
  for (int i = 0; i < 5; ++i) {  // five copies of one point: no usable neighbour
    c.positions.emplace_back(0.5f, 0.5f, 0.5f);
    c.intensities.push_back(static_cast<float>(i));
  }
  c.positions.emplace_back(0.5f, 0.5f, 0.6f);  // 10 cm away, contrast 10
  c.intensities.push_back(10.0f);
  SaliencyOptions options;
  options.knn = 2;
  auto s = compute_saliency(c.positions, c.intensities, options);
  ASSERT_TRUE(s.ok()) << s.status();
  for (float v : *s) EXPECT_TRUE(std::isfinite(v));
  // The lone point's neighbours are duplicates 10 cm away: |10 - I| / 0.1 * (1 + |n.u|).
  EXPECT_GT((*s)[5], 0.0f);
}

TEST(Saliency, ThreadCountDoesNotChangeTheResult) {
  const LocalCloud c = to_local(test::random_cloud(20000, 3, 0.5, Eigen::Vector3d::Zero()));
  SaliencyOptions one;
  one.threads = 1;
  SaliencyOptions two;
  two.threads = 2;
  auto a = compute_saliency(c.positions, c.intensities, one);
  auto b = compute_saliency(c.positions, c.intensities, two);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(*a == *b);
}

TEST(Saliency, InvalidInputs) {
  const std::vector<Eigen::Vector3f> p = {Eigen::Vector3f::Zero(), Eigen::Vector3f::Ones()};
  EXPECT_FALSE(compute_saliency(p, {1.0f}, {}).ok());
  EXPECT_FALSE(compute_saliency({}, {}, {}).ok());
  SaliencyOptions bad_k;
  bad_k.knn = 0;
  EXPECT_FALSE(compute_saliency(p, {1.0f, 2.0f}, bad_k).ok());
  SaliencyOptions bad_alpha;
  bad_alpha.alpha = -1.0;
  EXPECT_FALSE(compute_saliency(p, {1.0f, 2.0f}, bad_alpha).ok());
  std::vector<Eigen::Vector3f> nan_p = p;
  nan_p[1].x() = std::nanf("");
  EXPECT_FALSE(compute_saliency(nan_p, {1.0f, 2.0f}, {}).ok());
  // One point alone: S = 0.
  auto single = compute_saliency({Eigen::Vector3f::Zero()}, {1.0f}, {});
  ASSERT_TRUE(single.ok());
  EXPECT_EQ((*single)[0], 0.0f);
}

}  // namespace
}  // namespace mrvs::map
