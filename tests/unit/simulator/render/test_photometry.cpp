// Photometry: the exposure walk, camera gains, vignetting, the DN mapping and noise model.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/config/options.h"
#include "mrvs/sim/photometry.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

TEST(ExposureGains, DeterministicBoundedRandomWalk) {
  const std::vector<double> a = exposure_gains(5, 20000);
  const std::vector<double> b = exposure_gains(5, 20000);
  const std::vector<double> c = exposure_gains(6, 20000);
  ASSERT_EQ(a.size(), 20000u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(a[0], 1.0);
  double lo = 1.0, hi = 1.0, sum_sq = 0.0;
  int free_steps = 0;
  for (std::size_t k = 1; k < a.size(); ++k) {
    lo = std::min(lo, a[k]);
    hi = std::max(hi, a[k]);
    const double step = std::log(a[k] / a[k - 1]);
    // Steps away from the limits are the plain N(0, 0.02^2) increments.
    if (a[k] > 0.75 && a[k] < 1.25 && a[k - 1] > 0.75 && a[k - 1] < 1.25) {
      sum_sq += step * step;
      ++free_steps;
    }
  }
  EXPECT_GE(lo, 0.7 - 1e-12);
  EXPECT_LE(hi, 1.3 + 1e-12);
  // 20000 steps of 0.02 reach both limits (sqrt(20000) * 0.02 = 2.8 >> 0.3).
  EXPECT_LT(lo, 0.72);
  EXPECT_GT(hi, 1.28);
  ASSERT_GT(free_steps, 5000);
  EXPECT_NEAR(std::sqrt(sum_sq / free_steps), 0.02, 0.02 * 0.05);
}

TEST(ExposureGains, OptionsSwitchTheWalk) {
  RenderOptions options;
  EXPECT_EQ(exposure_gains(5, 10, options), std::vector<double>(10, 1.0));
  options.exposure_walk = true;
  options.exposure_sigma = 0.05;
  options.exposure_limit = 0.1;
  const std::vector<double> g = exposure_gains(5, 500, options);
  EXPECT_EQ(g, exposure_gains(5, 500, 0.05, 0.1));
  for (double x : g) {
    EXPECT_GE(x, 0.9 - 1e-12);
    EXPECT_LE(x, 1.1 + 1e-12);
  }
  EXPECT_TRUE(exposure_gains(5, 0).empty());
}

TEST(RenderOptions, YamlRoundTripAndValidation) {
  RenderOptions options;
  options.aa = AntiAliasing::kFull;
  options.vignetting = -0.3;
  options.shot_noise = true;
  const std::string text = config::options_to_yaml(options, "render");
  const StatusOr<config::YamlDocument> doc = config::parse_yaml_string(text);
  ASSERT_TRUE(doc.ok()) << doc.status();
  const StatusOr<RenderOptions> back = config::load_options<RenderOptions>(*doc, "render");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(*back, options);
  const StatusOr<config::YamlDocument> bad = config::parse_yaml_string("render:\n  aa: supersample\n");
  ASSERT_TRUE(bad.ok());
  const StatusOr<RenderOptions> rejected = config::load_options<RenderOptions>(*bad, "render");
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(rejected.status().message().find("render.aa"), absl::string_view::npos) << rejected.status();
}

TEST(CameraGain, Cam1CarriesTheMismatch) {
  RenderOptions options;
  options.stereo_gain_mismatch = -0.04;
  EXPECT_EQ(camera_gain(0, options), 1.0);
  EXPECT_DOUBLE_EQ(camera_gain(1, options), 0.96);
}

TEST(PixelPhotometry, DnMappingGainVignettingClip) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const camera::CameraModel& cam = *rig->cameras[1].model;
  RenderOptions options;
  options.stereo_gain_mismatch = 0.05;
  options.vignetting = -0.3;
  const PixelPhotometry p(options, cam, 1, 3, 1.1, 1);
  EXPECT_FALSE(p.has_noise());
  // At the principal point no vignetting: 1.1 * 1.05 * a * 255.
  const int cu = static_cast<int>(std::lround(cam.cx())), cv = static_cast<int>(std::lround(cam.cy()));
  const double r2 = (cu - cam.cx()) * (cu - cam.cx()) + (cv - cam.cy()) * (cv - cam.cy());
  EXPECT_NEAR(p.clean_value(0.5, cu, cv), 1.1 * 1.05 * 0.5 * 255.0, 1.1 * 1.05 * 0.3 * 255.0 * r2 / 1e5);
  // The farthest corner gets the full offset.
  double best = 0.0;
  int bu = 0, bv = 0;
  for (int u : {0, cam.width() - 1}) {
    for (int v : {0, cam.height() - 1}) {
      const double d = std::hypot(u - cam.cx(), v - cam.cy());
      if (d > best) best = d, bu = u, bv = v;
    }
  }
  EXPECT_NEAR(p.clean_value(0.5, bu, bv), 1.1 * 1.05 * (0.5 - 0.3) * 255.0, 1e-9);
  EXPECT_EQ(p.dn(0.5, cu, cv), static_cast<std::uint8_t>(std::round(1.1 * 1.05 * 0.5 * 255.0)));
  EXPECT_EQ(p.dn(1.0, cu, cv), 255);  // clipped
  EXPECT_EQ(p.dn(0.0, bu, bv), 0);    // negative clipped
}

TEST(PixelPhotometry, NoiseModelStatistics) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const camera::CameraModel& cam = *rig->cameras[0].model;
  RenderOptions options;
  options.read_noise_sigma = 2.0;
  options.shot_noise = true;
  const PixelPhotometry p(options, cam, 0, 4, 1.0, 99);
  ASSERT_TRUE(p.has_noise());
  const double clean = 100.0;
  EXPECT_DOUBLE_EQ(p.noise_sigma(clean), std::sqrt(4.0 + 100.0 / 4.0));
  double sum = 0.0, sum_sq = 0.0;
  int n = 0;
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u < cam.width(); ++u) {
      const double x = p.noise(clean, u, v);
      sum += x;
      sum_sq += x * x;
      ++n;
    }
  }
  const double mean = sum / n, sd = std::sqrt(sum_sq / n - mean * mean);
  EXPECT_NEAR(sd, p.noise_sigma(clean), 0.01 * p.noise_sigma(clean));
  EXPECT_LT(std::abs(mean), 4.0 * sd / std::sqrt(n));
  // Keyed by (camera, frame, pixel): another frame or camera draws other values.
  const PixelPhotometry other_frame(options, cam, 0, 5, 1.0, 99);
  const PixelPhotometry other_cam(options, cam, 1, 4, 1.0, 99);
  EXPECT_NE(p.noise(clean, 10, 10), other_frame.noise(clean, 10, 10));
  EXPECT_NE(p.noise(clean, 10, 10), other_cam.noise(clean, 10, 10));
  EXPECT_EQ(p.noise(clean, 10, 10), PixelPhotometry(options, cam, 0, 4, 1.0, 99).noise(clean, 10, 10));
}

TEST(PixelPhotometry, RowsEqualThePixelMappingAndNeighboursAreUncorrelated) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const camera::CameraModel& cam = *rig->cameras[0].model;
  RenderOptions options;
  options.read_noise_sigma = 3.0;
  options.shot_noise = true;
  options.vignetting = -0.2;
  const PixelPhotometry p(options, cam, 0, 7, 1.05, 5, 2.0);
  const int w = cam.width();
  std::vector<float> radiance(static_cast<std::size_t>(w));
  for (int u = 0; u < w; ++u) radiance[static_cast<std::size_t>(u)] = 0.1f + 0.8f * static_cast<float>(u) / w;
  std::vector<std::uint8_t> row(static_cast<std::size_t>(w));
  // Odd widths too: the last pixel's pair has no partner.
  for (const int width : {w, w - 1}) {
    for (const int v : {0, 17, cam.height() - 1}) {
      p.dn_row(radiance.data(), 0.9f, v, width, row.data());
      for (int u = 0; u < width; ++u) {
        ASSERT_EQ(row[static_cast<std::size_t>(u)], p.dn(radiance[static_cast<std::size_t>(u)] * 0.9f, u, v))
            << "u " << u << " v " << v << " width " << width;
      }
    }
  }
  // The two pixels of a pair (both Box-Muller outputs) and pairs side by side: no correlation.
  double s_pair = 0, s_next = 0, s_xx = 0;
  int n = 0;
  for (int v = 0; v < cam.height(); ++v) {
    for (int u = 0; u + 2 < w; u += 2) {
      const double a = p.noise(100.0, u, v), b = p.noise(100.0, u + 1, v), c = p.noise(100.0, u + 2, v);
      s_pair += a * b, s_next += b * c, s_xx += a * a, ++n;
    }
  }
  EXPECT_LT(std::abs(s_pair / s_xx), 4.0 / std::sqrt(n));
  EXPECT_LT(std::abs(s_next / s_xx), 4.0 / std::sqrt(n));
}

}  // namespace
}  // namespace mrvs::sim
