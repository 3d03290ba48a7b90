// Model names, parameter validation, describe/clone, in_image and project/unproject.
#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "camera_test_cases.h"
#include "mrvs/camera/camera_model.h"
#include "mrvs/camera/pinhole_equidistant.h"
#include "mrvs/camera/pinhole_radtan.h"

namespace mrvs::camera {
namespace {

using test::CameraCase;

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(DistortionModelNames, AcceptsKalibrEurocAndAliases) {
  const std::array<std::pair<const char*, DistortionModel>, 7> accepted = {{
      {"radtan", DistortionModel::kRadTan},
      {"radial-tangential", DistortionModel::kRadTan},
      {"RadTan", DistortionModel::kRadTan},
      {"equidistant", DistortionModel::kEquidistant},
      {"equi", DistortionModel::kEquidistant},
      {"fisheye", DistortionModel::kEquidistant},
      {"Equidistant", DistortionModel::kEquidistant},
  }};
  for (const auto& [name, model] : accepted) {
    auto parsed = distortion_model_from_string(name);
    ASSERT_TRUE(parsed.ok()) << name << ": " << parsed.status();
    EXPECT_EQ(*parsed, model) << name;
  }
}

TEST(DistortionModelNames, ToStringRoundTrips) {
  EXPECT_EQ(to_string(DistortionModel::kRadTan), "radtan");
  EXPECT_EQ(to_string(DistortionModel::kEquidistant), "equidistant");
  for (DistortionModel m : {DistortionModel::kRadTan, DistortionModel::kEquidistant}) {
    auto parsed = distortion_model_from_string(to_string(m));
    ASSERT_TRUE(parsed.ok()) << parsed.status();
    EXPECT_EQ(*parsed, m);
  }
}

TEST(DistortionModelNames, RejectsUnknownNamesListingAcceptedOnes) {
  for (const char* bad : {"", "pinhole", "radtan ", "kannala", "omni"}) {
    auto parsed = distortion_model_from_string(bad);
    ASSERT_FALSE(parsed.ok()) << "accepted '" << bad << "'";
    const std::string msg(parsed.status().message());
    EXPECT_EQ(parsed.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_TRUE(contains(msg, "'" + std::string(bad) + "'")) << msg;
    for (const char* name : {"radtan", "radial-tangential", "equidistant"}) {
      EXPECT_TRUE(contains(msg, name)) << msg;
    }
  }
}

TEST(MakeCamera, BuildsValidCamerasWithTheirParameters) {
  for (const CameraCase& c : test::all_cases()) {
    auto cam = make_camera(c.model, c.width, c.height, c.params);
    ASSERT_TRUE(cam.ok()) << c.name << ": " << cam.status();
    EXPECT_EQ((*cam)->model(), c.model);
    EXPECT_EQ((*cam)->width(), c.width);
    EXPECT_EQ((*cam)->height(), c.height);
    EXPECT_EQ((*cam)->params(), c.params);
    EXPECT_EQ((*cam)->fx(), c.params[0]);
    EXPECT_EQ((*cam)->fy(), c.params[1]);
    EXPECT_EQ((*cam)->cx(), c.params[2]);
    EXPECT_EQ((*cam)->cy(), c.params[3]);
  }
  const CameraCase c = test::euroc_cam0();
  EXPECT_TRUE(PinholeRadtan::create(c.width, c.height, c.params).ok());
  EXPECT_TRUE(PinholeEquidistant::create(c.width, c.height, c.params).ok());
}

TEST(MakeCamera, RejectsBadImageSize) {
  const CameraCase c = test::euroc_cam0();
  for (auto [w, h] : {std::pair{0, 480}, std::pair{752, 0}, std::pair{-752, 480}, std::pair{752, -1}}) {
    auto cam = make_camera(c.model, w, h, c.params);
    ASSERT_FALSE(cam.ok()) << w << "x" << h;
    const std::string msg(cam.status().message());
    EXPECT_TRUE(contains(msg, std::to_string(w) + "x" + std::to_string(h))) << msg;
    EXPECT_TRUE(contains(msg, "> 0")) << msg;
  }
}

TEST(MakeCamera, RejectsNonFiniteValuesNamingTheParameter) {
  const std::array<const char*, 8> radtan_names = {"fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2"};
  const std::array<const char*, 8> equi_names = {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4"};
  for (const CameraCase& c : {test::euroc_cam0(), test::tumvi_cam0()}) {
    const auto& names = c.model == DistortionModel::kRadTan ? radtan_names : equi_names;
    for (int i = 0; i < kNumParams; ++i) {
      EXPECT_EQ(param_name(c.model, i), names[static_cast<std::size_t>(i)]);
      for (double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                         -std::numeric_limits<double>::infinity()}) {
        Params p = c.params;
        p[i] = bad;
        auto cam = make_camera(c.model, c.width, c.height, p);
        ASSERT_FALSE(cam.ok()) << c.name << " param " << i << " = " << bad;
        const std::string msg(cam.status().message());
        EXPECT_EQ(cam.status().code(), absl::StatusCode::kInvalidArgument);
        EXPECT_TRUE(contains(msg, std::string(names[static_cast<std::size_t>(i)]) + " = ")) << msg;
        EXPECT_TRUE(contains(msg, "finite")) << msg;
      }
    }
  }
}

TEST(MakeCamera, RejectsNonPositiveFocalLengths) {
  const CameraCase c = test::euroc_cam0();
  for (int i : {0, 1}) {
    for (double bad : {0.0, -458.654, -1e-12}) {
      Params p = c.params;
      p[i] = bad;
      auto cam = make_camera(c.model, c.width, c.height, p);
      ASSERT_FALSE(cam.ok()) << i << " " << bad;
      const std::string msg(cam.status().message());
      EXPECT_TRUE(contains(msg, i == 0 ? "fx = " : "fy = ")) << msg;
      EXPECT_TRUE(contains(msg, "> 0")) << msg;
    }
  }
}

TEST(MakeCamera, RejectsPrincipalPointOutsideTheImage) {
  const CameraCase c = test::euroc_cam0();
  struct Bad {
    int index;
    double value;
    const char* name;
    const char* range;
  };
  for (const Bad& b :
       {Bad{2, -0.51, "cx = -0.51", "[-0.5, 751.5]"}, Bad{2, 752.0, "cx = 752", "[-0.5, 751.5]"},
        Bad{3, -3.0, "cy = -3", "[-0.5, 479.5]"}, Bad{3, 479.6, "cy = 479.6", "[-0.5, 479.5]"}}) {
    Params p = c.params;
    p[b.index] = b.value;
    auto cam = make_camera(c.model, c.width, c.height, p);
    ASSERT_FALSE(cam.ok()) << b.name;
    const std::string msg(cam.status().message());
    EXPECT_TRUE(contains(msg, b.name)) << msg;
    EXPECT_TRUE(contains(msg, b.range)) << msg;
  }
  // The limits themselves are accepted.
  for (auto [i, v] : {std::pair{2, -0.5}, std::pair{2, 751.5}, std::pair{3, -0.5}, std::pair{3, 479.5}}) {
    Params p = c.params;
    p[i] = v;
    EXPECT_TRUE(make_camera(c.model, c.width, c.height, p).ok()) << i << " " << v;
  }
}

TEST(CameraModel, DescribeNamesModelSizeAndParameters) {
  const auto cam = test::build(test::euroc_cam0());
  ASSERT_NE(cam, nullptr);
  const std::string d = cam->describe();
  for (const char* part : {"radtan 752x480", "fx=458.654", "fy=457.296", "cx=367.215", "cy=248.375",
                           "-0.28340811", "0.07395907", "0.00019359", "1.76187114e-05"}) {
    EXPECT_TRUE(contains(d, part)) << d << " lacks " << part;
  }
  EXPECT_FALSE(contains(d, "\n"));
  const auto fisheye = test::build(test::tumvi_cam0());
  ASSERT_NE(fisheye, nullptr);
  EXPECT_TRUE(contains(fisheye->describe(), "equidistant 512x512")) << fisheye->describe();
}

TEST(CameraModel, CloneIsAnIndependentEqualCopy) {
  for (const CameraCase& c : test::all_cases()) {
    const auto cam = test::build(c);
    ASSERT_NE(cam, nullptr);
    const std::unique_ptr<CameraModel> copy = cam->clone();
    ASSERT_NE(copy, nullptr);
    EXPECT_NE(copy.get(), cam.get());
    EXPECT_EQ(copy->model(), cam->model());
    EXPECT_EQ(copy->width(), cam->width());
    EXPECT_EQ(copy->height(), cam->height());
    EXPECT_EQ(copy->params(), cam->params());
    const Vec2d xn(0.3, -0.2);
    EXPECT_EQ(copy->distort(xn), cam->distort(xn));
  }
}

TEST(CameraModel, InImageRespectsBorders) {
  const auto cam = test::build(test::euroc_cam0());
  ASSERT_NE(cam, nullptr);
  EXPECT_TRUE(cam->in_image(Vec2d(0, 0)));
  EXPECT_TRUE(cam->in_image(Vec2d(751, 479)));
  EXPECT_TRUE(cam->in_image(Vec2d(367.2, 248.4)));
  EXPECT_FALSE(cam->in_image(Vec2d(-1e-9, 10)));
  EXPECT_FALSE(cam->in_image(Vec2d(10, -1e-9)));
  EXPECT_FALSE(cam->in_image(Vec2d(751.000001, 10)));
  EXPECT_FALSE(cam->in_image(Vec2d(10, 479.000001)));
  EXPECT_TRUE(cam->in_image(Vec2d(5, 5), 5.0));
  EXPECT_TRUE(cam->in_image(Vec2d(746, 474), 5.0));
  EXPECT_FALSE(cam->in_image(Vec2d(4.999, 100), 5.0));
  EXPECT_FALSE(cam->in_image(Vec2d(100, 4.999), 5.0));
  EXPECT_FALSE(cam->in_image(Vec2d(746.001, 100), 5.0));
  EXPECT_FALSE(cam->in_image(Vec2d(100, 474.001), 5.0));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(cam->in_image(Vec2d(nan, 10)));
  EXPECT_FALSE(cam->in_image(Vec2d(10, nan)));
  EXPECT_FALSE(cam->in_image(Vec2d(100, 100), 300.0));  // border larger than half the image
}

TEST(CameraModel, ProjectRejectsPointsBehindOrTooClose) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const CameraCase& c : test::all_cases()) {
    const auto cam = test::build(c);
    ASSERT_NE(cam, nullptr);
    Eigen::Matrix<double, 2, 3> J = Eigen::Matrix<double, 2, 3>::Constant(42.0);
    EXPECT_FALSE(cam->project(Vec3d(0.1, 0.2, -1.0), &J).has_value());
    EXPECT_FALSE(cam->project(Vec3d(0.1, 0.2, 0.0), &J).has_value());
    EXPECT_FALSE(cam->project(Vec3d(0.0, 0.0, 1e-7), &J).has_value());
    EXPECT_FALSE(cam->project(Vec3d(0.0, 0.0, 0.5), &J, 1.0).has_value());
    EXPECT_FALSE(cam->project(Vec3d(0.0, 0.0, nan), &J).has_value());
    EXPECT_FALSE(cam->project(Vec3d(nan, 0.0, 1.0), &J).has_value());
    EXPECT_EQ(J, (Eigen::Matrix<double, 2, 3>::Constant(42.0))) << "J written without a pixel";
    EXPECT_TRUE(cam->project(Vec3d(0.0, 0.0, 1.0), &J, 1.0).has_value());
    EXPECT_TRUE(cam->project(Vec3d(0.0, 0.0, 2e-6)).has_value());
  }
}

TEST(CameraModel, OpticalAxisMapsToPrincipalPoint) {
  for (const CameraCase& c : test::all_cases()) {
    const auto cam = test::build(c);
    ASSERT_NE(cam, nullptr);
    Mat2d J;
    EXPECT_EQ(cam->distort(Vec2d::Zero(), &J), Vec2d(cam->cx(), cam->cy())) << c.name;
    ASSERT_TRUE(J.allFinite()) << c.name;
    auto xn = cam->undistort(Vec2d(cam->cx(), cam->cy()));
    ASSERT_TRUE(xn.ok()) << xn.status();
    EXPECT_LT(xn->norm(), 1e-15) << c.name;
    auto bearing = cam->unproject(Vec2d(cam->cx(), cam->cy()));
    ASSERT_TRUE(bearing.ok()) << bearing.status();
    EXPECT_NEAR(bearing->z(), 1.0, 1e-15) << c.name;
  }
}

class CameraCaseTest : public ::testing::TestWithParam<CameraCase> {};

TEST_P(CameraCaseTest, UnprojectGivesUnitBearingsThatProjectBack) {
  const auto cam = test::build(GetParam());
  ASSERT_NE(cam, nullptr);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> depth(0.05, 80.0);
  int checked = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec2d uv(unit(rng) * (cam->width() - 1), unit(rng) * (cam->height() - 1));
    auto bearing = cam->unproject(uv);
    if (!bearing.ok()) continue;  // fisheye corners beyond 90 degrees, tested elsewhere
    ++checked;
    EXPECT_NEAR(bearing->norm(), 1.0, 1e-12);
    EXPECT_GT(bearing->z(), 0.0);
    const auto back = cam->project(depth(rng) * *bearing);
    ASSERT_TRUE(back.has_value());
    EXPECT_LT((*back - uv).norm(), 1e-6) << "uv " << uv.transpose();
  }
  EXPECT_GT(checked, 1500);
  // And the other way: points in front of the camera.
  for (int i = 0; i < 2000; ++i) {
    const Vec3d p = Vec3d(1.6 * unit(rng) - 0.8, 1.6 * unit(rng) - 0.8, 1.0) * depth(rng);
    const auto uv = cam->project(p);
    ASSERT_TRUE(uv.has_value());
    auto bearing = cam->unproject(*uv);
    ASSERT_TRUE(bearing.ok()) << bearing.status();
    EXPECT_LT((*bearing - p.normalized()).norm(), 1e-9) << "p " << p.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Models, CameraCaseTest, ::testing::ValuesIn(test::all_cases()), test::case_name);

}  // namespace
}  // namespace mrvs::camera
