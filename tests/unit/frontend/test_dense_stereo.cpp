// Dense stereo on synthetic rigs: the rectification of both distortion models against points
// projected through the camera models (same rectified row, disparity giving the depth, maps
// pointing at the raw pixels), points of a textured plane rendered through each model, and
// the errors of bad options, calibrations and images.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "mrvs/camera/camera_model.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/dense_stereo.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::edge {
namespace {

using camera::DistortionModel;

/// A stereo rig with a non-trivial relative pose: cam1 0.11 m to the right, 3 and 4 mm off
/// the axis, turned by about 1.5 degrees. Radtan: the EuRoC cam0 intrinsics. Equidistant:
/// a TUM-VI-like wide-angle camera (512x512, f 190 px), where the pinhole and fisheye
/// projections differ by tens of pixels at the rectified image's edges.
config::StereoRigCalibration synthetic_rig(DistortionModel model) {
  camera::Params p;
  int w = 752, h = 480;
  if (model == DistortionModel::kRadTan) {
    p << 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  } else {
    w = h = 512;
    p << 190.978, 190.973, 254.932, 256.897, 0.00348239, 0.00071503, -0.00205324, 0.00020294;
  }
  camera::Params p1 = p;
  p1[0] *= 1.004, p1[1] *= 0.997, p1[2] += 3.0, p1[3] -= 2.0;  // cam1 not identical to cam0
  config::StereoRigCalibration rig;
  rig.cameras[0].model = std::move(camera::make_camera(model, w, h, p)).value();
  rig.cameras[1].model = std::move(camera::make_camera(model, w, h, p1)).value();
  rig.cameras[0].T_b_c = SE3d();
  rig.cameras[1].T_b_c =
      SE3d(Quatd(Eigen::AngleAxisd(0.026, Vec3d(0.3, -0.8, 0.5).normalized())), Vec3d(0.110, 0.003, -0.004));
  return rig;
}

std::string model_name(DistortionModel m) { return m == DistortionModel::kRadTan ? "radtan" : "equidistant"; }

/// Bilinear sample of a CV_32FC2 map at (x, y).
Vec2d sample_map(const cv::Mat& map, const Vec2d& uv) {
  const int x0 = static_cast<int>(std::floor(uv.x())), y0 = static_cast<int>(std::floor(uv.y()));
  const double ax = uv.x() - x0, ay = uv.y() - y0;
  Vec2d out = Vec2d::Zero();
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      const cv::Vec2f m = map.at<cv::Vec2f>(y0 + dy, x0 + dx);
      out += (dx ? ax : 1.0 - ax) * (dy ? ay : 1.0 - ay) * Vec2d(m[0], m[1]);
    }
  }
  return out;
}

class DenseStereoRectification : public ::testing::TestWithParam<std::tuple<DistortionModel, int>> {};

// A point projected into both raw images through the camera models lands on the same
// rectified row, its disparity gives its depth in the rectified frame, and the maps
// (rectified -> raw, what remap uses) point back at the raw pixels.
TEST_P(DenseStereoRectification, PointsLandOnOneRowAtTheirDisparity) {
  const auto [model, s] = GetParam();
  const config::StereoRigCalibration rig = synthetic_rig(model);
  auto rect = rectify_stereo_rig(rig, s);
  ASSERT_TRUE(rect.ok()) << rect.status();
  const SE3d T_c1_c0 = rig.T_c0_c1().inverse();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(-1.0, 1.0), depth(0.4, 8.0);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const double z = depth(rng);
    const Vec3d p_r((unit(rng) * rect->width / 2) * z / rect->f, (unit(rng) * rect->height / 2) * z / rect->f,
                    z);
    const Vec3d p_c0 = rect->R_c0_r * p_r;
    std::array<Vec2d, 2> raw, rectified;
    bool seen = true;
    for (int c = 0; c < 2 && seen; ++c) {
      const auto& cam = *rig.cameras[static_cast<std::size_t>(c)].model;
      const auto uv = cam.project(c == 0 ? p_c0 : T_c1_c0 * p_c0);
      seen = uv && cam.in_image(*uv, 2.0 * s);
      if (!seen) break;
      raw[c] = *uv;
      const auto r = rect->rectified_pixel(rig, c, *uv);
      ASSERT_TRUE(r.has_value());
      rectified[c] = *r;
      seen = rectified[c].x() >= 0 && rectified[c].y() >= 0 && rectified[c].x() < rect->width - 1 &&
             rectified[c].y() < rect->height - 1;
    }
    if (!seen) continue;
    ++checked;
    EXPECT_LT(std::abs(rectified[0].y() - rectified[1].y()), 0.1) << "point " << p_c0.transpose();
    const double disparity = rectified[0].x() - rectified[1].x();
    ASSERT_GT(disparity, 0.0);
    EXPECT_NEAR(rect->f * rect->baseline_m / disparity, z, 1e-6 * z);
    for (int c = 0; c < 2; ++c) {
      const Vec2d expected = (raw[c] + Vec2d(0.5, 0.5)) / s - Vec2d(0.5, 0.5);
      EXPECT_LT((sample_map(rect->map[c], rectified[c]) - expected).norm(), 0.05) << "camera " << c;
    }
  }
  EXPECT_GT(checked, 500);
  EXPECT_NEAR(rect->baseline_m, rig.T_c0_c1().translation().norm(), 1e-12);
}

INSTANTIATE_TEST_SUITE_P(BothModels, DenseStereoRectification,
                         ::testing::Combine(::testing::Values(DistortionModel::kRadTan,
                                                              DistortionModel::kEquidistant),
                                            ::testing::Values(1, 2, 4)),
                         [](const auto& test) {
                           return model_name(std::get<0>(test.param)) + "_downsample" +
                                  std::to_string(std::get<1>(test.param));
                         });

/// A textured plane in the cam0 frame: through `origin`, normal `normal`; its texture is
/// bilinear value noise with cells of `cell_m` metres (two octaves).
struct TexturedPlane {
  Vec3d origin;
  Vec3d normal;
  double cell_m;

  double texture(const Vec3d& x) const {
    const Vec3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
    const Vec3d d = x - origin;
    return 0.65 * noise(d.dot(e1) / cell_m, d.dot(e2) / cell_m, 1) +
           0.35 * noise(d.dot(e1) / (0.4 * cell_m), d.dot(e2) / (0.4 * cell_m), 2);
  }
  static double lattice(long i, long j, unsigned seed) {
    std::uint64_t h = static_cast<std::uint64_t>(i) * 0x9E3779B97F4A7C15ull ^
                      static_cast<std::uint64_t>(j) * 0xC2B2AE3D27D4EB4Full ^ seed;
    h ^= h >> 31, h *= 0xBF58476D1CE4E5B9ull, h ^= h >> 29;
    return static_cast<double>(h % 1000) / 999.0;
  }
  static double noise(double x, double y, unsigned seed) {
    const double fx = std::floor(x), fy = std::floor(y);
    const auto i = static_cast<long>(fx), j = static_cast<long>(fy);
    const double ax = x - fx, ay = y - fy;
    return (1 - ax) * (1 - ay) * lattice(i, j, seed) + ax * (1 - ay) * lattice(i + 1, j, seed) +
           (1 - ax) * ay * lattice(i, j + 1, seed) + ax * ay * lattice(i + 1, j + 1, seed);
  }
};

/// Raw image of camera `c` seeing `plane` (pixel noise 1 DN, fixed seed); 2x2 samples per pixel.
cv::Mat render_plane(const config::StereoRigCalibration& rig, int c, const TexturedPlane& plane) {
  const auto& cam = *rig.cameras[static_cast<std::size_t>(c)].model;
  const SE3d T_c0_c = c == 0 ? SE3d() : rig.T_c0_c1();
  cv::Mat img(cam.height(), cam.width(), CV_8UC1);
  std::mt19937 rng(11 + c);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (int v = 0; v < img.rows; ++v) {
    for (int u = 0; u < img.cols; ++u) {
      double sum = 0.0;
      for (int k = 0; k < 4; ++k) {
        const auto bearing = cam.unproject(Vec2d(u - 0.25 + 0.5 * (k % 2), v - 0.25 + 0.5 * (k / 2)));
        if (!bearing.ok()) continue;
        const Vec3d dir = T_c0_c.rotation_matrix() * *bearing;
        const double t = plane.normal.dot(plane.origin - T_c0_c.translation()) / plane.normal.dot(dir);
        sum += t > 0.0 ? plane.texture(T_c0_c.translation() + t * dir) : 0.0;
      }
      img.at<std::uint8_t>(v, u) = cv::saturate_cast<std::uint8_t>(30.0 + 190.0 * sum / 4.0 + noise(rng));
    }
  }
  return img;
}

class DenseStereoPlane : public ::testing::TestWithParam<DistortionModel> {};

// Every point of a pair rendered through the camera models lies on the plane. The bounds
// follow from stereo geometry: a disparity error of 0.2 px at the level moves a point by
// z^2 / (f b) x 0.2 along its ray; at 1.5 m and downsample 2 that is 1.8 cm for the radtan rig
// (f b = 25 px m) and 4.3 cm for the wide-angle one (f b = 10.5 px m). The medians must be a
// third of that (about 0.06 px), and the signed median (a wrong scale, a shifted row, the
// matcher's rounding) a tenth.
TEST_P(DenseStereoPlane, PointsOfARenderedPlaneLieOnIt) {
  const config::StereoRigCalibration rig = synthetic_rig(GetParam());
  const double z0 = 1.5;
  const double f = rig.cameras[0].model->fx();
  TexturedPlane plane{
      Vec3d(0.1, -0.05, z0),
      (Eigen::AngleAxisd(0.35, Vec3d::UnitY()) * Eigen::AngleAxisd(-0.2, Vec3d::UnitX()) * Vec3d::UnitZ()),
      5.0 * z0 / f};
  const cv::Mat left = render_plane(rig, 0, plane), right = render_plane(rig, 1, plane);
  DenseStereoOptions options;
  options.max_points = 0;
  auto stereo = DenseStereo::create(options, rig);
  ASSERT_TRUE(stereo.ok()) << stereo.status();
  auto points = stereo->points(left, right);
  ASSERT_TRUE(points.ok()) << points.status();
  std::vector<double> distance, signed_distance;
  for (const Eigen::Vector3f& p : *points) {
    signed_distance.push_back(plane.normal.dot(p.cast<double>() - plane.origin));
    distance.push_back(std::abs(signed_distance.back()));
  }
  const auto& r = stereo->rectification();
  const double grid =
      std::ceil(r.width / double(options.pixel_step)) * std::ceil(r.height / double(options.pixel_step));
  EXPECT_GT(static_cast<double>(distance.size()), 0.5 * grid) << "of " << grid;
  const double bound = 0.2 * z0 * z0 / (r.f * r.baseline_m);
  EXPECT_LT(quantile(distance, 0.5), 0.3 * bound);
  EXPECT_LT(quantile(distance, 0.9), bound);
  EXPECT_LT(std::abs(quantile(signed_distance, 0.5)), 0.1 * bound);  // no bias (a wrong scale, a shifted row)
  std::printf(
      "%s: %zu points, |distance to the plane| median %.2f mm, p90 %.2f mm, signed median %.2f mm (bound "
      "%.1f mm)\n",
      model_name(GetParam()).c_str(), distance.size(), 1e3 * quantile(distance, 0.5),
      1e3 * quantile(distance, 0.9), 1e3 * quantile(signed_distance, 0.5), 1e3 * bound);
}

INSTANTIATE_TEST_SUITE_P(BothModels, DenseStereoPlane,
                         ::testing::Values(DistortionModel::kRadTan, DistortionModel::kEquidistant),
                         [](const auto& test) { return model_name(test.param); });

TEST(DenseStereo, WrongImagesAreErrorsNamingTheExpectedSize) {
  const config::StereoRigCalibration rig = synthetic_rig(DistortionModel::kRadTan);
  auto stereo = DenseStereo::create(DenseStereoOptions{}, rig);
  ASSERT_TRUE(stereo.ok()) << stereo.status();
  const cv::Mat good(480, 752, CV_8UC1, cv::Scalar(100));
  const auto message = [&](const cv::Mat& l, const cv::Mat& r) {
    auto p = stereo->points(l, r);
    EXPECT_FALSE(p.ok());
    EXPECT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(p.status().message());
  };
  std::string m = message(cv::Mat(480, 640, CV_8UC1, cv::Scalar(0)), good);
  EXPECT_NE(m.find("left image (cam0) is 640x480"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 752x480 CV_8UC1"), std::string::npos) << m;
  m = message(good, cv::Mat(480, 752, CV_8UC3, cv::Scalar(0)));
  EXPECT_NE(m.find("right image (cam1)"), std::string::npos) << m;
  EXPECT_NE(m.find("CV_8UC3"), std::string::npos) << m;
  EXPECT_NE(m.find("expected 752x480 CV_8UC1"), std::string::npos) << m;
  m = message(good, cv::Mat());
  EXPECT_NE(m.find("is 0x0"), std::string::npos) << m;
  m = message(cv::Mat(480, 752, CV_16UC1, cv::Scalar(0)), good);
  EXPECT_NE(m.find("CV_16UC1"), std::string::npos) << m;
  auto ok = stereo->points(good, good);  // a flat pair: no texture, no points, no error
  ASSERT_TRUE(ok.ok()) << ok.status();
}

/// The error message of DenseStereo::create, "" when it succeeds.
std::string create_error(const DenseStereoOptions& o, const config::StereoRigCalibration& rig) {
  auto s = DenseStereo::create(o, rig);
  return s.ok() ? std::string() : std::string(s.status().message());
}

TEST(DenseStereo, BadOptionsAndCalibrationsAreErrorsNamingTheProblem) {
  const config::StereoRigCalibration rig = synthetic_rig(DistortionModel::kRadTan);
  const auto expect_error = [&](const DenseStereoOptions& o, const config::StereoRigCalibration& r,
                                const std::string& what) {
    const std::string m = create_error(o, r);
    EXPECT_NE(m.find(what), std::string::npos)
        << "message: '" << m << "', expected to contain '" << what << "'";
  };
  DenseStereoOptions o;
  o.downsample = 3;
  expect_error(o, rig, "downsample must be 1, 2 or 4, got 3");
  o = DenseStereoOptions{};
  o.block_size = 4;
  expect_error(o, rig, "block_size must be odd, got 4");
  o = DenseStereoOptions{};
  o.num_disparities = 40;
  expect_error(o, rig, "num_disparities must be a multiple of 16");
  o = DenseStereoOptions{};
  o.min_depth_m = 6.0;
  o.max_depth_m = 5.0;
  expect_error(o, rig, "min_depth_m (6) must be below max_depth_m (5)");
  o = DenseStereoOptions{};
  o.min_depth_m = 0.02;
  expect_error(o, rig, "raise min_depth_m");
  o = DenseStereoOptions{};
  o.matcher = "census";
  expect_error(o, rig, "matcher");
  o = DenseStereoOptions{};
  o.pixel_step = 0;
  expect_error(o, rig, "pixel_step");
  o = DenseStereoOptions{};
  o.matcher = "bm";
  o.block_size = 3;
  expect_error(o, rig, "matcher 'bm' needs block_size >= 5");

  config::StereoRigCalibration bad = rig;
  bad.cameras[1].model.reset();
  expect_error(DenseStereoOptions{}, bad, "camera 1 has no model");
  bad = rig;
  bad.cameras[1].T_b_c = rig.cameras[0].T_b_c;
  expect_error(DenseStereoOptions{}, bad, "baseline |p_c0_c1| is 0 m");
  bad = rig;
  bad.cameras[1].T_b_c = SE3d(Quatd::Identity(), Vec3d(-0.11, 0.0, 0.0));
  expect_error(DenseStereoOptions{}, bad, "cam1 must lie to the right of cam0");
  bad = rig;
  bad.cameras[1].T_b_c = SE3d(Quatd::Identity(), Vec3d(0.0, 0.11, 0.0));
  expect_error(DenseStereoOptions{}, bad, "cam1 must lie to the right of cam0");
  EXPECT_EQ(create_error(DenseStereoOptions{}, rig), "");
}

TEST(DenseStereo, OutputIsDeterministicAndThinnedToMaxPoints) {
  const config::StereoRigCalibration rig = synthetic_rig(DistortionModel::kRadTan);
  const TexturedPlane plane{Vec3d(0.0, 0.0, 2.0), Vec3d(0.1, -0.1, 1.0).normalized(), 0.02};
  const cv::Mat left = render_plane(rig, 0, plane), right = render_plane(rig, 1, plane);
  DenseStereoOptions o;
  o.max_points = 0;
  auto all = DenseStereo::create(o, rig);
  ASSERT_TRUE(all.ok()) << all.status();
  auto every = all->points(left, right);
  ASSERT_TRUE(every.ok());
  ASSERT_GT(every->size(), 2000u);
  o.max_points = 1000;
  auto thinned = DenseStereo::create(o, rig);
  ASSERT_TRUE(thinned.ok());
  auto a = thinned->points(left, right), b = thinned->points(left, right);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->size(), 1000u);
  ASSERT_EQ(*a, *b);
  // Evenly thinned: the i-th kept point is the floor(i n / 1000)-th of all.
  const std::size_t n = every->size();
  for (std::size_t i = 0; i < a->size(); ++i) ASSERT_EQ((*a)[i], (*every)[i * n / 1000]) << i;
}

// Each point's brightness is the image around it: it follows the rendered texture at the
// point (30 + 190 texture, blurred by the 3 x 3 level box), and it is thinned with the points.
TEST(DenseStereo, BrightnessFollowsTheTextureAtEachPointAndIsThinnedWithIt) {
  const config::StereoRigCalibration rig = synthetic_rig(DistortionModel::kRadTan);
  const TexturedPlane plane{Vec3d(0.0, 0.0, 2.0), Vec3d(0.1, -0.1, 1.0).normalized(), 0.08};
  const cv::Mat left = render_plane(rig, 0, plane), right = render_plane(rig, 1, plane);
  DenseStereoOptions o;
  o.max_points = 0;
  auto all = DenseStereo::create(o, rig);
  ASSERT_TRUE(all.ok()) << all.status();
  std::vector<std::uint8_t> brightness;
  auto every = all->points(left, right, &brightness);
  ASSERT_TRUE(every.ok());
  ASSERT_EQ(brightness.size(), every->size());
  ASSERT_GT(every->size(), 2000u);
  double sum_abs = 0.0, sxy = 0.0, sxx = 0.0, syy = 0.0, mx = 0.0, my = 0.0;
  const double n = static_cast<double>(every->size());
  std::vector<double> expected;
  for (const Eigen::Vector3f& p : *every) expected.push_back(30.0 + 190.0 * plane.texture(p.cast<double>()));
  for (std::size_t i = 0; i < expected.size(); ++i) {
    mx += expected[i] / n;
    my += brightness[i] / n;
    sum_abs += std::abs(expected[i] - brightness[i]);
  }
  for (std::size_t i = 0; i < expected.size(); ++i) {
    sxy += (expected[i] - mx) * (brightness[i] - my);
    sxx += (expected[i] - mx) * (expected[i] - mx);
    syy += (brightness[i] - my) * (brightness[i] - my);
  }
  EXPECT_GT(sxy / std::sqrt(sxx * syy), 0.9);
  EXPECT_LT(sum_abs / n, 12.0);
  for (std::uint8_t b : brightness) ASSERT_GE(b, 1);  // 0 means "not known"
  o.max_points = 1000;
  auto thinned = DenseStereo::create(o, rig);
  ASSERT_TRUE(thinned.ok());
  std::vector<std::uint8_t> kept;
  auto some = thinned->points(left, right, &kept);
  ASSERT_TRUE(some.ok());
  ASSERT_EQ(kept.size(), 1000u);
  for (std::size_t i = 0; i < kept.size(); ++i) ASSERT_EQ(kept[i], brightness[i * every->size() / 1000]) << i;
}

}  // namespace
}  // namespace mrvs::edge
