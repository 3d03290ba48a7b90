// Motion blur (StereoRenderer::render_exposure, exposure_samples) against its analytic model:
// a camera turning by theta about its y axis during the exposure smears the image along x by
// the streak f * theta, so the blurred image is the sharp one box-filtered over that length.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

/// The camera turned by `angle` about its own y axis.
SE3d turned(const SE3d& T_w_c, double angle) {
  return T_w_c * SE3d(Quatd(Eigen::AngleAxisd(angle, Vec3d::UnitY())), Vec3d::Zero());
}

/// `image` box-filtered along x over `length` px (linear interpolation between pixels).
double box_at(const cv::Mat& image, int u, int v, double length) {
  constexpr int kTaps = 64;
  double sum = 0.0;
  for (int j = 0; j < kTaps; ++j) {
    const double x = u - 0.5 * length + (j + 0.5) * length / kTaps;
    const int x0 = static_cast<int>(std::floor(x));
    const double f = x - x0;
    sum += (1.0 - f) * image.at<std::uint8_t>(v, x0) + f * image.at<std::uint8_t>(v, x0 + 1);
  }
  return sum / kTaps;
}

/// Mean |blurred - sharp box-filtered over `length`| over the image's central 200 x 150 px.
double residual(const cv::Mat& blurred, const cv::Mat& sharp, double length) {
  double sum = 0.0;
  int n = 0;
  for (int v = sharp.rows / 2 - 75; v < sharp.rows / 2 + 75; ++v) {
    for (int u = sharp.cols / 2 - 100; u < sharp.cols / 2 + 100; ++u) {
      sum += std::abs(blurred.at<std::uint8_t>(v, u) - box_at(sharp, u, v, length));
      ++n;
    }
  }
  return sum / n;
}

/// The exposure's poses: the middles of n equal parts of the turn [-angle / 2, angle / 2].
std::vector<SE3d> exposure(const SE3d& T_w_c, double angle, int n) {
  std::vector<SE3d> poses;
  for (int i = 0; i < n; ++i) poses.push_back(turned(T_w_c, angle * ((i + 0.5) / n - 0.5)));
  return poses;
}

TEST(RenderBlur, TheStreakIsTheTurnTimesTheFocalLength) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  const SE3d T_w_c = r.camera_pose(0, w->trajectory[test::pose_index_at(w->trajectory, 20.0)].T_w_b);
  cv::Mat sharp;
  ASSERT_TRUE(r.render(0, T_w_c, FrameInfo{}, &sharp).ok());
  const double f = r.camera(0).fx();
  for (double streak_px : {4.0, 8.0, 12.0}) {
    const double angle = streak_px / f;
    const double step = RenderOptions{}.blur_step_px;  // the shipped spacing
    const int n = r.exposure_samples(0, turned(T_w_c, -0.5 * angle), turned(T_w_c, 0.5 * angle), step, 256);
    // The grid's outer points move up to 1 / cos^2 of the field's half-angle more.
    EXPECT_GE(n, static_cast<int>(std::ceil(streak_px / step))) << streak_px;
    EXPECT_LE(n, static_cast<int>(std::ceil(2.0 * streak_px / step))) << streak_px;
    cv::Mat blurred;
    ASSERT_TRUE(r.render_exposure(0, exposure(T_w_c, angle, n), FrameInfo{}, &blurred).ok());
    const double at_streak = residual(blurred, sharp, streak_px);
    ::testing::Test::RecordProperty("residual_dn_" + test::num(streak_px), test::num(at_streak));
    ::testing::Test::RecordProperty("samples_" + test::num(streak_px), n);
    for (double other : {0.5, 0.75, 1.3, 1.6}) {
      const double r_other = residual(blurred, sharp, other * streak_px);
      ::testing::Test::RecordProperty("residual_dn_" + test::num(streak_px) + "_x" + test::num(other),
                                      test::num(r_other));
      EXPECT_LT(at_streak, r_other) << streak_px << " px vs " << other;
    }
    EXPECT_LT(at_streak, 1.5) << streak_px << " px";  // DN, mean over the centre
    EXPECT_GT(residual(blurred, sharp, 0.0 + 1e-9), 2.0 * at_streak) << "blurred at all: " << streak_px;
  }
}

TEST(RenderBlur, NoMotionNeedsOneSampleAndOnePoseIsTheSharpImage) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  const SE3d T_w_c = r.camera_pose(1, w->trajectory[test::pose_index_at(w->trajectory, 12.0)].T_w_b);
  EXPECT_EQ(r.exposure_samples(1, T_w_c, T_w_c, 0.5, 32), 1);
  cv::Mat sharp, one;
  ASSERT_TRUE(r.render(1, T_w_c, FrameInfo{3, 1.1}, &sharp).ok());
  ASSERT_TRUE(r.render_exposure(1, {T_w_c}, FrameInfo{3, 1.1}, &one).ok());
  EXPECT_EQ(cv::norm(sharp, one, cv::NORM_INF), 0.0);
  // A large turn is capped.
  EXPECT_EQ(r.exposure_samples(1, T_w_c, turned(T_w_c, 0.3), 0.5, 32), 32);
  cv::Mat image;
  EXPECT_FALSE(r.render_exposure(1, {}, FrameInfo{}, &image).ok());
  EXPECT_FALSE(r.render_exposure(2, {T_w_c, T_w_c}, FrameInfo{}, &image).ok());
}

}  // namespace
}  // namespace mrvs::sim
