// Auto-exposure, analog gain and the dim area against their models: the controller holds the
// mean DN within its deadband of the target in whole steps, never leaves [min exposure,
// min(max exposure, frame interval)] x [1, max gain], and the light scales each pixel's
// radiance by 1 - (1 - level) exp(-d^2 / 2r^2) of the point it sees.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "mrvs/sim/photometry.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

/// A scene of mean DN `scene_dn` at the reference exposure: the image mean the controller
/// meters (linear in the brightness, clipped at 255).
double metered(const AutoExposure& ae, double scene_dn) {
  return std::min(255.0, scene_dn * ae.relative_gain());
}

/// Runs `frames` control steps on the scene; true when every change was a whole number of steps.
bool run(AutoExposure& ae, double scene_dn, int frames, double step_ev) {
  bool whole_steps = true;
  for (int k = 0; k < frames; ++k) {
    const double before = ae.brightness_ms();
    ae.observe(metered(ae, scene_dn));
    const double steps = std::log2(ae.brightness_ms() / before) / step_ev;
    const bool clamped = ae.brightness_ms() == ae.max_exposure_ms() * 4.0 || ae.brightness_ms() == 0.05;
    if (!clamped && std::abs(steps - std::round(steps)) > 1e-9) whole_steps = false;
  }
  return whole_steps;
}

TEST(AutoExposure, HoldsTheTargetWithinItsDeadbandInWholeStepsAndStaysInBounds) {
  RenderOptions o;  // target 110 DN, deadband 0.1 EV, steps of 1/8 EV, 0.05 .. 20 ms, gain <= 4
  for (double scene_dn : {0.5, 5.0, 30.0, 110.0, 400.0, 2000.0, 1e6}) {
    StatusOr<AutoExposure> ae = AutoExposure::create(o, 50.0);
    ASSERT_TRUE(ae.ok()) << ae.status();
    EXPECT_TRUE(run(*ae, scene_dn, 200, o.ae_step_ev)) << scene_dn;
    const ExposureSetting s = ae->setting();
    const double needed_ms = o.exposure_ms * o.ae_target_dn / scene_dn;  // exposure * gain for the target
    EXPECT_GE(s.exposure_ms, o.ae_min_exposure_ms) << scene_dn;
    EXPECT_LE(s.exposure_ms, o.ae_max_exposure_ms) << scene_dn;
    EXPECT_GE(s.analog_gain, 1.0) << scene_dn;
    EXPECT_LE(s.analog_gain, o.ae_max_analog_gain + 1e-12) << scene_dn;
    if (s.analog_gain > 1.0) {
      EXPECT_EQ(s.exposure_ms, o.ae_max_exposure_ms) << "gain only at the longest";
    }
    EXPECT_NEAR(s.exposure_ms * s.analog_gain, ae->brightness_ms(), 1e-12);
    if (needed_ms > 80.0) {  // darker than the longest exposure at full gain can fix
      EXPECT_EQ(s.exposure_ms, 20.0) << scene_dn;
      EXPECT_NEAR(s.analog_gain, 4.0, 1e-12) << scene_dn;
    } else if (needed_ms < 0.05) {
      EXPECT_EQ(s.exposure_ms, 0.05) << scene_dn;
    } else {
      const double error_ev = std::log2(o.ae_target_dn / metered(*ae, scene_dn));
      EXPECT_LE(std::abs(error_ev), o.ae_deadband_ev) << scene_dn;
      // Converged: one more frame changes nothing.
      const double before = ae->brightness_ms();
      ae->observe(metered(*ae, scene_dn));
      EXPECT_EQ(ae->brightness_ms(), before) << scene_dn;
    }
  }
}

TEST(AutoExposure, AJumpInBrightnessIsCorrectedMonotonicallyWithinAFewFrames) {
  RenderOptions o;
  StatusOr<AutoExposure> ae = AutoExposure::create(o, 50.0);
  ASSERT_TRUE(ae.ok());
  ae->settle(110.0);
  EXPECT_NEAR(ae->setting().exposure_ms, 5.0, 1e-12);  // already on target at the reference
  // The scene gets 4x darker (2 EV): damping 0.5 halves the error each frame.
  std::vector<double> b{ae->brightness_ms()};
  for (int k = 0; k < 12; ++k) {
    ae->observe(metered(*ae, 27.5));
    b.push_back(ae->brightness_ms());
  }
  for (std::size_t k = 1; k < b.size(); ++k) EXPECT_GE(b[k], b[k - 1]) << k;  // never overshoots back
  EXPECT_GT(b[1], b[0]);                                                      // reacts on the next frame
  EXPECT_LE(std::abs(std::log2(b[6] / 20.0)), o.ae_deadband_ev + 1e-9);       // 20 ms within 6 frames
  EXPECT_EQ(b[6], b.back());
  // settle() starts converged on any scene.
  StatusOr<AutoExposure> fresh = AutoExposure::create(o, 50.0);
  fresh->settle(27.5);
  EXPECT_LE(std::abs(std::log2(110.0 / metered(*fresh, 27.5))), o.ae_deadband_ev);
}

TEST(AutoExposure, TheFrameIntervalBoundsTheExposureAndBadBoundsAreRejected) {
  RenderOptions o;
  o.ae_max_exposure_ms = 100.0;
  StatusOr<AutoExposure> ae = AutoExposure::create(o, 1000.0 / 30.0);  // 30 Hz
  ASSERT_TRUE(ae.ok());
  run(*ae, 1.0, 100, o.ae_step_ev);
  EXPECT_NEAR(ae->setting().exposure_ms, 1000.0 / 30.0, 1e-9);
  EXPECT_NEAR(ae->setting().analog_gain, o.ae_max_analog_gain, 1e-9);
  o.ae_min_exposure_ms = 40.0;
  const StatusOr<AutoExposure> bad = AutoExposure::create(o, 1000.0 / 30.0);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(std::string(bad.status().message()).find("ae_min_exposure_ms"), std::string::npos);
  EXPECT_FALSE(AutoExposure::create(RenderOptions{}, 0.0).ok());
}

TEST(PixelPhotometry, TheAnalogGainAmplifiesReadAndShotNoise) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  RenderOptions options;
  options.read_noise_sigma = 2.0;
  options.shot_noise = true;
  const PixelPhotometry p(options, *rig->cameras[0].model, 0, 4, 4.0, 99, 4.0);
  // S = 100 DN made of 4x fewer electrons, each worth 4x more DN.
  EXPECT_DOUBLE_EQ(p.noise_sigma(100.0), std::sqrt(16.0 * 4.0 + 4.0 * 100.0 / 4.0));
}

TEST(Illumination, EachPixelIsItsPointsAlbedoTimesTheLightThere) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  const SE3d T_w_c = r.camera_pose(0, w->trajectory[test::pose_index_at(w->trajectory, 20.0)].T_w_b);
  const std::optional<PixelHit> centre = r.cast_pixel(0, T_w_c, Vec2d(376.0, 240.0));
  ASSERT_TRUE(centre.has_value());
  Illumination light;
  light.enabled = true;
  light.centre_xy = centre->point_w.head<2>().cast<float>();  // dim where the camera looks
  light.level = 0.25f;
  light.radius_m = 1.5f;
  EXPECT_FALSE(r.with_illumination(Illumination{true, {0.0f, 0.0f}, 0.0f, 1.0f}).ok());
  EXPECT_FALSE(r.with_illumination(Illumination{true, {0.0f, 0.0f}, 0.5f, -1.0f}).ok());
  const StatusOr<StereoRenderer> dim = r.with_illumination(light);
  ASSERT_TRUE(dim.ok()) << dim.status();
  const StatusOr<cv::Mat> lit = r.render_radiance(0, T_w_c);
  const StatusOr<cv::Mat> dimmed = dim->render_radiance(0, T_w_c);
  const StatusOr<TruthImage> truth = r.render_truth(0, T_w_c);
  ASSERT_TRUE(lit.ok() && dimmed.ok() && truth.ok());
  int checked = 0;
  double lowest = 1.0;
  for (int v = 10; v < lit->rows - 10; v += 7) {
    for (int u = 10; u < lit->cols - 10; u += 7) {
      if (!test::uniform_face(truth->face, u, v, 1) || lit->at<float>(v, u) < 0.05f) continue;
      const std::optional<PixelHit> hit = r.cast_pixel(0, T_w_c, Vec2d(u, v));
      if (!hit) continue;
      const double d2 = (hit->point_w.head<2>() - centre->point_w.head<2>()).squaredNorm();
      const double expected = 1.0 - 0.75 * std::exp(-d2 / (2.0 * 1.5 * 1.5));
      EXPECT_NEAR(dimmed->at<float>(v, u) / lit->at<float>(v, u), expected, 2e-3) << u << " " << v;
      lowest = std::min(lowest, expected);
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
  EXPECT_LT(lowest, 0.3);  // the dim centre is in view
  EXPECT_FLOAT_EQ(light.light(centre->point_w.cast<float>()), 0.25f);
}

}  // namespace
}  // namespace mrvs::sim
