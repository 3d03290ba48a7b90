// undistort(distort(x)) and distort(undistort(uv)) over whole images, and undistort errors.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <utility>

#include <gtest/gtest.h>

#include "camera_test_cases.h"
#include "mrvs/camera/camera_model.h"
#include "mrvs/camera/pinhole_equidistant.h"
#include "mrvs/camera/pinhole_radtan.h"

namespace mrvs::camera {
namespace {

using test::CameraCase;

// Distorted normalised radius theta_d at 90 degrees off axis for an equidistant camera.
double theta_d_at_90_degrees(const Params& p) {
  const double t = kPi / 2.0;
  const double t2 = t * t;
  return t * (1.0 + p[4] * t2 + p[5] * t2 * t2 + p[6] * t2 * t2 * t2 + p[7] * t2 * t2 * t2 * t2);
}

// Angle (radians) between the rays through normalised points a and b.
double ray_angle(const Vec2d& a, const Vec2d& b) {
  const Vec3d ra = Vec3d(a.x(), a.y(), 1.0).normalized();
  const Vec3d rb = Vec3d(b.x(), b.y(), 1.0).normalized();
  return std::atan2(ra.cross(rb).norm(), ra.dot(rb));
}

class CameraRoundTripTest : public ::testing::TestWithParam<CameraCase> {
 protected:
  void SetUp() override {
    cam_ = test::build(GetParam());
    ASSERT_NE(cam_, nullptr);
  }
  bool is_equidistant() const { return cam_->model() == DistortionModel::kEquidistant; }
  std::unique_ptr<CameraModel> cam_;
};

TEST_P(CameraRoundTripTest, DistortOfUndistortOverEveryPixel) {
  const double td90 = is_equidistant() ? theta_d_at_90_degrees(cam_->params()) : 0.0;
  double max_pixel_error = 0.0;
  int rejected = 0;
  int unexpected = 0;
  for (int v = 0; v < cam_->height(); ++v) {
    for (int u = 0; u < cam_->width(); ++u) {
      const Vec2d uv(u, v);
      const double rd = Vec2d((u - cam_->cx()) / cam_->fx(), (v - cam_->cy()) / cam_->fy()).norm();
      // Equidistant: pixels beyond theta_d(90 deg) look behind the image plane.
      const bool must_work = !is_equidistant() || rd < td90 * (1.0 - 1e-6);
      const bool must_fail = is_equidistant() && rd > td90 * (1.0 + 1e-6);
      const auto xn = cam_->undistort(uv);
      if (!xn.ok()) {
        ++rejected;
        if (must_work && ++unexpected <= 5) ADD_FAILURE() << "undistort failed: " << xn.status();
        continue;
      }
      if (must_fail && ++unexpected <= 5)
        ADD_FAILURE() << "accepted pixel beyond 90 degrees: " << uv.transpose();
      const double err = (cam_->distort(*xn) - uv).norm();
      if (!(err < 1e-6) && ++unexpected <= 5) ADD_FAILURE() << "pixel " << uv.transpose() << " error " << err;
      max_pixel_error = std::max(max_pixel_error, err);
    }
  }
  EXPECT_EQ(unexpected, 0);
  EXPECT_LT(max_pixel_error, 1e-6);
  std::printf("[   INFO   ] %s: max |distort(undistort(uv)) - uv| = %.3g px over %dx%d pixels, %d rejected\n",
              GetParam().name.c_str(), max_pixel_error, cam_->width(), cam_->height(), rejected);
  if (GetParam().name == "TumViCam0") {
    EXPECT_GT(rejected, 1000);  // its corners lie beyond 90 degrees
  } else {
    EXPECT_EQ(rejected, 0);
  }
}

TEST_P(CameraRoundTripTest, UndistortOfDistortOverAGridOfPoints) {
  // Radtan: a grid over the undistorted footprint of the image (points whose pixel is in the
  // image). Equidistant: a polar grid of rays up to 89.99 degrees off axis (the whole model domain).
  const double f = std::max(cam_->fx(), cam_->fy());
  double max_error = 0.0;  // pixels: f * |x' - x| (radtan), f * ray angle (equidistant)
  int checked = 0;
  int failures = 0;
  auto check = [&](const Vec2d& x) {
    const Vec2d uv = cam_->distort(x);
    const auto back = cam_->undistort(uv);
    ++checked;
    if (!back.ok()) {
      if (++failures <= 5) ADD_FAILURE() << "x " << x.transpose() << ": " << back.status();
      return;
    }
    const double err = is_equidistant() ? f * ray_angle(*back, x) : f * (*back - x).norm();
    if (!(err < 1e-6) && ++failures <= 5) ADD_FAILURE() << "x " << x.transpose() << " error " << err;
    max_error = std::max(max_error, err);
  };
  if (is_equidistant()) {
    for (int i = 0; i < 500; ++i) {
      for (int j = 0; j < 720; ++j) {
        check(test::from_angles(89.99 * kPi / 180.0 * i / 499.0, 2.0 * kPi * j / 720.0));
      }
    }
  } else {
    // Footprint bounds from the undistorted image border.
    Eigen::AlignedBox2d box;
    const int w = cam_->width(), h = cam_->height();
    for (int u = 0; u < w; ++u) {
      for (int v : {0, h - 1}) box.extend(*cam_->undistort(Vec2d(u, v)));
    }
    for (int v = 0; v < h; ++v) {
      for (int u : {0, w - 1}) box.extend(*cam_->undistort(Vec2d(u, v)));
    }
    for (int i = 0; i < h; ++i) {
      for (int j = 0; j < w; ++j) {
        const Vec2d x = box.min() + (box.max() - box.min()).cwiseProduct(Vec2d(j / (w - 1.0), i / (h - 1.0)));
        if (cam_->in_image(cam_->distort(x))) check(x);
      }
    }
  }
  EXPECT_EQ(failures, 0);
  EXPECT_GT(checked, 100000);
  std::printf("[   INFO   ] %s: max undistort(distort(x)) error = %.3g px over %d points\n",
              GetParam().name.c_str(), max_error, checked);
}

INSTANTIATE_TEST_SUITE_P(Models, CameraRoundTripTest, ::testing::ValuesIn(test::all_cases()),
                         test::case_name);

TEST(Undistort, RejectsNonFinitePixelsNamingThem) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const CameraCase& c : test::all_cases()) {
    const auto cam = test::build(c);
    ASSERT_NE(cam, nullptr);
    for (const Vec2d& uv : {Vec2d(nan, 10.0), Vec2d(12.5, inf)}) {
      const auto xn = cam->undistort(uv);
      ASSERT_FALSE(xn.ok()) << c.name;
      EXPECT_EQ(xn.status().code(), absl::StatusCode::kInvalidArgument);
      const std::string msg(xn.status().message());
      EXPECT_TRUE(msg.find(std::isnan(uv.x()) ? "(nan, 10)" : "(12.5, inf)") != std::string::npos) << msg;
      EXPECT_FALSE(cam->unproject(uv).ok());
    }
  }
}

TEST(Undistort, RadtanFoldRadius) {
  // d/dr [r (1 + k1 r^2 + k2 r^4)] = 1 + 3 k1 r^2 + 5 k2 r^4.
  const auto euroc = PinholeRadtan::create(752, 480, test::euroc_cam0().params);
  ASSERT_TRUE(euroc.ok()) << euroc.status();
  EXPECT_TRUE(std::isinf((*euroc)->max_monotonic_radius()));  // 9 k1^2 < 20 k2: no real root
  Params p = test::euroc_cam0().params;
  p[4] = -0.5;
  p[5] = 0.0;  // 1 - 1.5 r^2 = 0
  EXPECT_NEAR((*PinholeRadtan::create(752, 480, p))->max_monotonic_radius(), std::sqrt(1.0 / 1.5), 1e-15);
  p[4] = -0.6;
  p[5] = 0.05;  // 1 - 1.8 s + 0.25 s^2 = 0, s = r^2
  EXPECT_NEAR((*PinholeRadtan::create(752, 480, p))->max_monotonic_radius(),
              std::sqrt((1.8 - std::sqrt(1.8 * 1.8 - 1.0)) / 0.5), 1e-15);
  p[4] = 0.1;
  p[5] = -0.01;  // 1 + 0.3 s - 0.05 s^2 = 0
  EXPECT_NEAR((*PinholeRadtan::create(752, 480, p))->max_monotonic_radius(),
              std::sqrt((0.3 + std::sqrt(0.09 + 0.2)) / 0.1), 1e-14);
}

TEST(Undistort, RadtanRejectsPixelsBeyondTheFold) {
  // r (1 - 0.5 r^2) peaks at 0.544 for r = 0.816: pixels beyond that distorted radius have no
  // preimage on the valid branch (only on the folded one, with a negative radial factor).
  Params p;
  p << 500.0, 500.0, 320.0, 240.0, -0.5, 0.0, 0.0, 0.0;
  auto cam = make_camera(DistortionModel::kRadTan, 640, 480, p);
  ASSERT_TRUE(cam.ok()) << cam.status();
  const auto inside = (*cam)->undistort(Vec2d(520.0, 340.0));  // distorted radius 0.447
  ASSERT_TRUE(inside.ok()) << inside.status();
  EXPECT_LT(inside->norm(), std::sqrt(2.0 / 3.0));
  const auto xn = (*cam)->undistort(Vec2d(630.5, 470.25));  // distorted radius 0.773
  ASSERT_FALSE(xn.ok()) << "undistorted to " << xn->transpose();
  const std::string msg(xn.status().message());
  EXPECT_NE(msg.find("(630.5, 470.25)"), std::string::npos) << msg;
  EXPECT_FALSE((*cam)->unproject(Vec2d(630.5, 470.25)).ok());
}

TEST(Undistort, EquidistantRejectsPixelsBeyondTheFold) {
  // k1 = -0.4, k2 = 0.07: d theta_d / d theta = 1 - 1.2 t + 0.35 t^2 (t = theta^2) vanishes
  // first at t = 1 / 0.7; theta_d is 0.683 there, dips to 0.679 and is 0.690 at 90 degrees.
  Params p;
  p << 300.0, 300.0, 320.0, 240.0, -0.4, 0.07, 0.0, 0.0;
  const auto cam = PinholeEquidistant::create(640, 480, p);
  ASSERT_TRUE(cam.ok()) << cam.status();
  EXPECT_NEAR((*cam)->max_monotonic_theta(), std::sqrt(1.0 / 0.7), 1e-12);
  const auto inside = (*cam)->undistort(Vec2d(320.0 + 0.6 * 300.0, 240.0));
  ASSERT_TRUE(inside.ok()) << inside.status();
  EXPECT_LT(std::atan(inside->norm()), std::sqrt(1.0 / 0.7));
  const auto xn = (*cam)->undistort(Vec2d(525.95, 240.0));  // theta_d 0.6865: far branch only
  ASSERT_FALSE(xn.ok()) << "undistorted to " << xn->transpose();
  const std::string msg(xn.status().message());
  EXPECT_NE(msg.find("(525.95, 240)"), std::string::npos) << msg;
  EXPECT_NE(msg.find("folds over"), std::string::npos) << msg;
  // Monotonic models: the limit is 90 degrees.
  const auto tumvi = PinholeEquidistant::create(512, 512, test::tumvi_cam0().params);
  ASSERT_TRUE(tumvi.ok());
  EXPECT_EQ((*tumvi)->max_monotonic_theta(), kPi / 2.0);
}

TEST(Undistort, EquidistantReportsPixelsBeyondNinetyDegrees) {
  const auto cam = test::build(test::tumvi_cam0());
  ASSERT_NE(cam, nullptr);
  const std::pair<Vec2d, const char*> cases[] = {{Vec2d(0.5, 1.25), "(0.5, 1.25)"},
                                                 {Vec2d(511.0, 511.0), "(511, 511)"},
                                                 {Vec2d(-3000.0, 100.0), "(-3000, 100)"}};
  for (const auto& [uv, text] : cases) {
    const auto xn = cam->undistort(uv);
    ASSERT_FALSE(xn.ok()) << uv.transpose() << " undistorted to " << xn->transpose();
    const std::string msg(xn.status().message());
    EXPECT_NE(msg.find(text), std::string::npos) << msg;
    EXPECT_NE(msg.find("90 degrees"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace mrvs::camera
