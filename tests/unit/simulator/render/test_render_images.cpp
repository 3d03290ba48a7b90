// Rendered images: DN = round(255 albedo) (simulator.md section 6 item 10, tight form), gains,
// noise statistics, determinism across thread counts, texture richness, errors.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "mrvs/sim/photometry.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

SE3d cam0_pose_at(const RenderTestWorld& w, double seconds) {
  return w.renderer->camera_pose(0, w.trajectory[test::pose_index_at(w.trajectory, seconds)].T_w_b);
}

StereoRenderer with(const StereoRenderer& base, const RenderOptions& options) {
  StatusOr<StereoRenderer> r = base.with_options(options);
  EXPECT_TRUE(r.ok()) << r.status();
  return *std::move(r);
}

// Counts pixels whose DN differs from round(255 albedo(face, u, v, lod)) over pixels whose
// 3x3 neighbourhood has one face; `use_lod` = the adaptive pass-1 level, else level 0.
void expect_dn_equals_albedo(const RenderTestWorld& w, const cv::Mat& image, const TruthImage& truth,
                             bool use_lod) {
  int checked = 0, wrong = 0;
  for (int v = 1; v + 1 < image.rows; ++v) {
    for (int u = 1; u + 1 < image.cols; ++u) {
      if (!test::uniform_face(truth.face, u, v, 1) || truth.face.at<int>(v, u) < 0) continue;
      const float lod = use_lod ? truth.lod.at<float>(v, u) : 0.0f;
      const float a =
          w.scene->albedo(truth.face.at<int>(v, u), truth.u.at<float>(v, u), truth.v.at<float>(v, u), lod);
      const int expected = static_cast<int>(std::round(255.0 * a));
      ++checked;
      if (image.at<std::uint8_t>(v, u) != expected) ++wrong;
    }
  }
  EXPECT_GT(checked, image.rows * image.cols * 9 / 10);
  EXPECT_EQ(wrong, 0) << "of " << checked;
}

TEST(RenderImages, DnEqualsAlbedoAwayFromEdges) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const SE3d T_w_c = cam0_pose_at(*w, 20.0);
  const StatusOr<TruthImage> truth = w->renderer->render_truth(0, T_w_c);
  ASSERT_TRUE(truth.ok());
  RenderOptions none;
  none.aa = AntiAliasing::kNone;
  const StatusOr<cv::Mat> point_sampled = with(*w->renderer, none).render(0, T_w_c, FrameInfo{});
  const StatusOr<cv::Mat> adaptive = w->renderer->render(0, T_w_c, FrameInfo{});
  ASSERT_TRUE(point_sampled.ok() && adaptive.ok());
  ASSERT_EQ(adaptive->type(), CV_8UC1);
  ASSERT_EQ(adaptive->size(), cv::Size(752, 480));
  expect_dn_equals_albedo(*w, *point_sampled, *truth, false);
  expect_dn_equals_albedo(*w, *adaptive, *truth, true);
}

TEST(RenderImages, AntiAliasingModesAgreeOnAverage) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const SE3d T_w_c = cam0_pose_at(*w, 20.0);
  RenderOptions full;
  full.aa = AntiAliasing::kFull;
  const StatusOr<cv::Mat> a = w->renderer->render(0, T_w_c, FrameInfo{});
  const StatusOr<cv::Mat> f = with(*w->renderer, full).render(0, T_w_c, FrameInfo{});
  ASSERT_TRUE(a.ok() && f.ok());
  const double mean_abs = cv::norm(*a, *f, cv::NORM_L1) / static_cast<double>(a->total());
  RecordProperty("mean_abs_adaptive_vs_full_dn", test::num(mean_abs));
  EXPECT_LT(mean_abs, 8.0);
  EXPECT_NEAR(cv::mean(*a)[0], cv::mean(*f)[0], 2.0);
  // Adaptive refinement touches only pixels next to a face change: a few percent.
  const StatusOr<TruthImage> truth = w->renderer->render_truth(0, T_w_c);
  ASSERT_TRUE(truth.ok());
  int edges = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 752; ++u) {
      const int f0 = truth->face.at<int>(v, u);
      edges += (u > 0 && truth->face.at<int>(v, u - 1) != f0) ||
               (u < 751 && truth->face.at<int>(v, u + 1) != f0) ||
               (v > 0 && truth->face.at<int>(v - 1, u) != f0) ||
               (v < 479 && truth->face.at<int>(v + 1, u) != f0);
    }
  }
  const double fraction = edges / (752.0 * 480.0);
  RecordProperty("edge_pixel_fraction", test::num(fraction));
  EXPECT_GT(fraction, 0.001);
  EXPECT_LT(fraction, 0.08);
}

TEST(RenderImages, FrameAndCameraGains) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const SE3d T_w_b = w->trajectory[test::pose_index_at(w->trajectory, 20.0)].T_w_b;
  RenderOptions options;
  options.stereo_gain_mismatch = 0.05;
  const StereoRenderer r = with(*w->renderer, options);
  const StatusOr<cv::Mat> radiance = r.render_radiance(1, r.camera_pose(1, T_w_b));
  const StatusOr<std::array<cv::Mat, 2>> images = r.render_stereo(T_w_b, FrameInfo{3, 0.8});
  ASSERT_TRUE(radiance.ok() && images.ok());
  int checked = 0;
  for (int v = 0; v < 480; v += 3) {
    for (int u = 0; u < 752; u += 3) {
      const double expected =
          std::clamp(std::round(0.8 * 1.05 * radiance->at<float>(v, u) * 255.0), 0.0, 255.0);
      ASSERT_EQ(static_cast<int>((*images)[1].at<std::uint8_t>(v, u)), static_cast<int>(expected))
          << u << "," << v;
      ++checked;
    }
  }
  EXPECT_GT(checked, 30000);
  // cam0 has gain 1: its mean is about 0.8 / (0.8 * 1.05) of cam1's (same scene, 11 cm apart).
  EXPECT_NEAR(cv::mean((*images)[0])[0] / cv::mean((*images)[1])[0], 1.0 / 1.05, 0.05);
}

TEST(RenderImages, NoiseStatisticsMatchTheModel) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const SE3d T_w_c = cam0_pose_at(*w, 40.0);
  const StatusOr<cv::Mat> clean = w->renderer->render(0, T_w_c, FrameInfo{5, 1.0});
  ASSERT_TRUE(clean.ok());
  for (const bool shot : {false, true}) {
    RenderOptions options;
    options.read_noise_sigma = 2.0;
    options.shot_noise = shot;
    const StatusOr<cv::Mat> noisy = with(*w->renderer, options).render(0, T_w_c, FrameInfo{5, 1.0});
    ASSERT_TRUE(noisy.ok());
    double sum = 0.0, sum_sq = 0.0, model_var = 0.0;
    int n = 0;
    for (int v = 0; v < 480; ++v) {
      for (int u = 0; u < 752; ++u) {
        const double c = clean->at<std::uint8_t>(v, u);
        const double sigma2 = 4.0 + (shot ? c / 4.0 : 0.0);
        if (c < 5.0 * std::sqrt(sigma2) || c > 255.0 - 5.0 * std::sqrt(sigma2)) continue;  // no clipping
        const double d = noisy->at<std::uint8_t>(v, u) - c;
        sum += d;
        sum_sq += d * d;
        model_var += sigma2 + 1.0 / 6.0;  // + the two roundings
        ++n;
      }
    }
    ASSERT_GT(n, 150000);
    const double mean = sum / n, sd = std::sqrt(sum_sq / n - mean * mean), model = std::sqrt(model_var / n);
    RecordProperty(shot ? "noise_sd_read_shot" : "noise_sd_read", test::num(sd));
    EXPECT_NEAR(sd, model, 0.1 * model) << (shot ? "read + shot" : "read");
    EXPECT_NEAR(sd, model, 0.02 * model) << "(the +-10 % bound of the brief has plenty of headroom)";
    EXPECT_LT(std::abs(mean), 0.05);
  }
}

TEST(RenderImages, IdenticalBytesForOneAndTwoThreads) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const SE3d T_w_b = w->trajectory[test::pose_index_at(w->trajectory, 33.0)].T_w_b;
  RenderOptions options;
  options.read_noise_sigma = 2.0;
  options.shot_noise = true;
  options.vignetting = -0.3;
  const StereoRenderer r = with(*w->renderer, options);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const StatusOr<std::array<cv::Mat, 2>> one = r.render_stereo(T_w_b, FrameInfo{17, 1.1});
  omp_set_num_threads(2);
  const StatusOr<std::array<cv::Mat, 2>> two = r.render_stereo(T_w_b, FrameInfo{17, 1.1});
  const StatusOr<std::array<cv::Mat, 2>> again = r.render_stereo(T_w_b, FrameInfo{17, 1.1});
  const StatusOr<std::array<cv::Mat, 2>> other_frame = r.render_stereo(T_w_b, FrameInfo{18, 1.1});
  omp_set_num_threads(threads);
  ASSERT_TRUE(one.ok() && two.ok() && again.ok() && other_frame.ok());
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(cv::norm((*one)[c], (*two)[c], cv::NORM_INF), 0.0) << "cam" << c;
    EXPECT_EQ(cv::norm((*two)[c], (*again)[c], cv::NORM_INF), 0.0) << "cam" << c;
    EXPECT_GT(cv::norm((*two)[c], (*other_frame)[c], cv::NORM_INF), 0.0) << "noise is keyed by frame";
  }
}

TEST(RenderImages, TextureRichness) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  int min_corners = 1 << 30, min_cells = 25;
  for (double seconds : {6.0, 20.0, 45.0, 70.0}) {
    const SE3d& T_w_b = w->trajectory[test::pose_index_at(w->trajectory, seconds)].T_w_b;
    const StatusOr<std::array<cv::Mat, 2>> images = w->renderer->render_stereo(T_w_b, FrameInfo{});
    ASSERT_TRUE(images.ok());
    for (const cv::Mat& image : *images) {
      std::vector<cv::Point2f> corners;
      cv::goodFeaturesToTrack(image, corners, 400, 0.01, 10);
      bool cells[5][5] = {};
      for (const cv::Point2f& p : corners)
        cells[static_cast<int>(p.y * 5 / 480)][static_cast<int>(p.x * 5 / 752)] = true;
      int occupied = 0;
      for (auto& row : cells) occupied += static_cast<int>(std::count(std::begin(row), std::end(row), true));
      min_corners = std::min(min_corners, static_cast<int>(corners.size()));
      min_cells = std::min(min_cells, occupied);
    }
  }
  RecordProperty("min_gftt_corners", min_corners);
  RecordProperty("min_grid_cells", min_cells);
  EXPECT_GE(min_corners, 150);
  EXPECT_GE(min_cells, 20);
}

TEST(RenderImages, BadRequestsAreErrors) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  cv::Mat image;
  EXPECT_EQ(r.render(2, SE3d(), FrameInfo{}, &image).code(), absl::StatusCode::kInvalidArgument);
  SE3d bad;
  bad.translation() = Vec3d(std::nan(""), 0.0, 0.0);
  EXPECT_EQ(r.render(0, bad, FrameInfo{}, &image).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_FALSE(r.render(0, SE3d(), FrameInfo{0, -1.0}, &image).ok());
  EXPECT_FALSE(r.render(0, SE3d(), FrameInfo{}, nullptr).ok());
  EXPECT_FALSE(r.render_truth(-1, SE3d()).ok());
  EXPECT_FALSE(r.cast_pixel(0, bad, Vec2d(1, 1)).has_value());
  RenderOptions options;
  options.vignetting = 5.0;
  const StatusOr<StereoRenderer> invalid = r.with_options(options);
  ASSERT_FALSE(invalid.ok());
  EXPECT_NE(invalid.status().message().find("vignetting"), absl::string_view::npos) << invalid.status();
  config::StereoRigCalibration rig = w->rig;
  rig.cameras[1].model = nullptr;
  const StatusOr<StereoRenderer> no_model = StereoRenderer::create(*w->scene, rig, RenderOptions{}, 1);
  ASSERT_FALSE(no_model.ok());
  EXPECT_NE(no_model.status().message().find("camera 1"), absl::string_view::npos) << no_model.status();
}

}  // namespace
}  // namespace mrvs::sim
