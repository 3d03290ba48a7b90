// Image pyramid and gradients against brute force, the DSO-style selector's contract (count,
// mask, border, spread, gradient preference) and the stereo two-view geometry against
// projected ground-truth points.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "frontend_test_world.h"
#include "mrvs/edge/image_pyramid.h"
#include "mrvs/edge/pixel_selector.h"
#include "mrvs/edge/stereo_geometry.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

cv::Mat random_image(int w, int h, unsigned seed) {
  cv::Mat img(h, w, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::UNIFORM, 0, 256);
  return img;
}

TEST(ImagePyramid, LevelsAreBlockAveragesAndGradientsAreCentralDifferences) {
  const cv::Mat img = random_image(97, 64, 3);  // odd width: the last column is dropped
  GradientPyramid pyr;
  ASSERT_TRUE(build_gradient_pyramid(img, 3, &pyr).ok());
  ASSERT_EQ(pyr.levels.size(), 3u);
  EXPECT_EQ(pyr.levels[1].image.cols, 48);
  EXPECT_EQ(pyr.levels[1].image.rows, 32);
  EXPECT_EQ(pyr.levels[2].image.cols, 24);
  for (int y = 0; y < 32; ++y) {
    for (int x = 0; x < 48; ++x) {
      const double mean =
          (img.at<std::uint8_t>(2 * y, 2 * x) + img.at<std::uint8_t>(2 * y, 2 * x + 1) +
           img.at<std::uint8_t>(2 * y + 1, 2 * x) + img.at<std::uint8_t>(2 * y + 1, 2 * x + 1)) /
          4.0;
      ASSERT_NEAR(pyr.levels[1].image.at<float>(y, x), mean, 1e-4);
    }
  }
  const GradientLevel& l0 = pyr.levels[0];
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const bool inside = x > 0 && y > 0 && x < img.cols - 1 && y < img.rows - 1;
      const double gx =
          inside ? 0.5 * (img.at<std::uint8_t>(y, x + 1) - img.at<std::uint8_t>(y, x - 1)) : 0.0;
      const double gy =
          inside ? 0.5 * (img.at<std::uint8_t>(y + 1, x) - img.at<std::uint8_t>(y - 1, x)) : 0.0;
      ASSERT_NEAR(l0.gx.at<float>(y, x), gx, 1e-4) << x << "," << y;
      ASSERT_NEAR(l0.gy.at<float>(y, x), gy, 1e-4);
      ASSERT_NEAR(l0.mag2.at<float>(y, x), gx * gx + gy * gy, 1e-2);
    }
  }
}

TEST(ImagePyramid, BadInputIsAnError) {
  GradientPyramid pyr;
  EXPECT_FALSE(build_gradient_pyramid(cv::Mat(), 3, &pyr).ok());
  EXPECT_FALSE(build_gradient_pyramid(cv::Mat(64, 64, CV_8UC3), 3, &pyr).ok());
  const auto small = build_gradient_pyramid(random_image(10, 10, 1), 3, &pyr);
  ASSERT_FALSE(small.ok());
  EXPECT_NE(small.message().find("too small"), std::string::npos);
  EXPECT_FALSE(build_gradient_pyramid(random_image(64, 64, 1), 0, &pyr).ok());
}

class PixelSelectorTest : public testing::Test {
 protected:
  void SetUp() override {
    const test::TestSequence* seq = test::sequence(sim::SceneProfile::kIndoor, "easy", 40);
    ASSERT_NE(seq, nullptr);
    image_ = seq->images[5][0];
    ASSERT_TRUE(build_gradient_pyramid(image_, 3, &pyr_).ok());
  }
  cv::Mat image_;
  GradientPyramid pyr_;
  SelectorOptions options_;
};

TEST_F(PixelSelectorTest, ReturnsAboutTheWantedCountAndNeverMore) {
  for (int want : {50, 200, 800}) {
    const SelectorResult r = select_pixels(pyr_, cv::Mat(), want, options_);
    EXPECT_LE(static_cast<int>(r.pixels.size()), want);
    EXPECT_GE(static_cast<int>(r.pixels.size()), want * 8 / 10) << "want " << want << " pot " << r.pot;
  }
  EXPECT_TRUE(select_pixels(pyr_, cv::Mat(), 0, options_).pixels.empty());
}

TEST_F(PixelSelectorTest, RespectsTheMaskAndTheBorder) {
  cv::Mat mask(image_.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(0, 0, image_.cols / 2, image_.rows)).setTo(255);  // left half excluded
  const SelectorResult r = select_pixels(pyr_, mask, 150, options_);
  ASSERT_GE(r.pixels.size(), 100u);
  for (const SelectedPixel& p : r.pixels) {
    EXPECT_GE(p.uv.x, image_.cols / 2);
    EXPECT_GE(p.uv.x, options_.border_px);
    EXPECT_GE(p.uv.y, options_.border_px);
    EXPECT_LT(p.uv.x, image_.cols - options_.border_px);
    EXPECT_LT(p.uv.y, image_.rows - options_.border_px);
  }
}

TEST_F(PixelSelectorTest, SpreadsEvenlyOverTheImage) {
  const SelectorResult r = select_pixels(pyr_, cv::Mat(), 200, options_);
  // 5 x 4 grid of cells: every cell gets a share of the points (the scene is textured all
  // over), none more than three times the mean.
  std::array<int, 20> counts{};
  for (const SelectedPixel& p : r.pixels) {
    const int cx = std::min(4, static_cast<int>(p.uv.x * 5 / image_.cols));
    const int cy = std::min(3, static_cast<int>(p.uv.y * 4 / image_.rows));
    ++counts[static_cast<std::size_t>(cy * 5 + cx)];
  }
  const double mean = static_cast<double>(r.pixels.size()) / 20.0;
  for (int c : counts) {
    EXPECT_GT(c, 0);
    EXPECT_LT(c, 3.0 * mean);
  }
}

TEST_F(PixelSelectorTest, PrefersHighGradients) {
  const SelectorResult r = select_pixels(pyr_, cv::Mat(), 200, options_);
  ASSERT_FALSE(r.pixels.empty());
  // Level-0 picks pass their block threshold, so their gradient is far above the image's
  // typical one.
  std::vector<float> all;
  const cv::Mat& mag2 = pyr_.levels[0].mag2;
  for (int y = 0; y < mag2.rows; ++y)
    for (int x = 0; x < mag2.cols; ++x) all.push_back(mag2.at<float>(y, x));
  std::nth_element(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(all.size() / 2), all.end());
  const float median_all = all[all.size() / 2];
  std::vector<float> picked;
  for (const SelectedPixel& p : r.pixels) {
    if (p.level == 0) picked.push_back(mag2.at<float>(static_cast<int>(p.uv.y), static_cast<int>(p.uv.x)));
  }
  ASSERT_GE(picked.size(), r.pixels.size() / 2);
  std::nth_element(picked.begin(), picked.begin() + static_cast<std::ptrdiff_t>(picked.size() / 2),
                   picked.end());
  EXPECT_GT(picked[picked.size() / 2], 4.0f * median_all);
}

TEST_F(PixelSelectorTest, IsDeterministic) {
  const SelectorResult a = select_pixels(pyr_, cv::Mat(), 200, options_);
  const SelectorResult b = select_pixels(pyr_, cv::Mat(), 200, options_);
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  for (std::size_t i = 0; i < a.pixels.size(); ++i) EXPECT_EQ(a.pixels[i].uv, b.pixels[i].uv);
}

TEST(StereoGeometry, TrueCorrespondencesLieOnTheEpipolarLineAndTriangulateExactly) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const SE3d T_c1_c0(Quatd(so3::exp_quat<double>(Vec3d(0.01, -0.02, 0.005))), Vec3d(-0.11, 0.001, 0.002));
  for (int i = 0; i < 100; ++i) {
    const Vec3d p0(u(rng) * 3.0, u(rng) * 2.0, 0.5 + 10.0 * (u(rng) + 1.0));
    const Vec3d p1 = T_c1_c0 * p0;
    const Vec2d xn0 = p0.head<2>() / p0.z(), xn1 = p1.head<2>() / p1.z();
    EXPECT_LT(epipolar_distance(T_c1_c0, xn0, xn1), 1e-12);
    const auto d = triangulate_depths(T_c1_c0, xn0, xn1);
    ASSERT_TRUE(d.has_value());
    EXPECT_NEAR(d->x(), p0.z(), 1e-9 * p0.z());
    EXPECT_NEAR(d->y(), p1.z(), 1e-9 * p1.z());
    // A vertical offset of 0.01 (normalised) moves the point off the near-horizontal line
    // by about that much.
    EXPECT_NEAR(epipolar_distance(T_c1_c0, xn0, xn1 + Vec2d(0.0, 0.01)), 0.01, 0.001);
  }
  // Parallel rays (no baseline) do not triangulate.
  EXPECT_FALSE(triangulate_depths(SE3d(), Vec2d(0.1, 0.2), Vec2d(0.1, 0.2)).has_value());
}

}  // namespace
}  // namespace mrvs::edge
