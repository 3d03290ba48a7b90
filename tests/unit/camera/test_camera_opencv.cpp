// distort() against OpenCV's reference implementations (cv::projectPoints for radtan,
// cv::fisheye::projectPoints for equidistant).
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "camera_test_cases.h"
#include "mrvs/camera/camera_model.h"

namespace mrvs::camera {
namespace {

using test::CameraCase;

std::vector<cv::Point2d> opencv_project(const CameraModel& cam, const std::vector<Vec2d>& xn) {
  std::vector<cv::Point3d> object;
  object.reserve(xn.size());
  for (const Vec2d& x : xn) object.emplace_back(x.x(), x.y(), 1.0);
  const cv::Mat K =
      (cv::Mat_<double>(3, 3) << cam.fx(), 0.0, cam.cx(), 0.0, cam.fy(), cam.cy(), 0.0, 0.0, 1.0);
  const Params& p = cam.params();
  const cv::Vec4d D(p[4], p[5], p[6], p[7]);
  const cv::Vec3d zero(0.0, 0.0, 0.0);
  std::vector<cv::Point2d> image;
  if (cam.model() == DistortionModel::kRadTan) {
    cv::projectPoints(object, zero, zero, K, D, image);
  } else {
    cv::fisheye::projectPoints(object, image, zero, zero, K, D);
  }
  return image;
}

class CameraOpenCvTest : public ::testing::TestWithParam<CameraCase> {};

TEST_P(CameraOpenCvTest, DistortMatchesOpenCv) {
  const auto cam = test::build(GetParam());
  ASSERT_NE(cam, nullptr);
  std::mt19937 rng(2024);
  std::vector<Vec2d> xn = test::sample_points(*cam, rng, 1000);
  std::uniform_real_distribution<double> coord(-1.2, 1.2);
  for (int i = 0; i < 1000; ++i) xn.emplace_back(coord(rng), coord(rng));
  const std::vector<cv::Point2d> reference = opencv_project(*cam, xn);
  ASSERT_EQ(reference.size(), xn.size());
  double max_error = 0.0;
  for (std::size_t i = 0; i < xn.size(); ++i) {
    const Vec2d uv = cam->distort(xn[i]);
    const double err = (uv - Vec2d(reference[i].x, reference[i].y)).norm();
    EXPECT_LT(err, 1e-6) << "xn " << xn[i].transpose() << " ours " << uv.transpose() << " opencv "
                         << reference[i];
    max_error = std::max(max_error, err);
  }
  std::printf("[   INFO   ] %s: max |distort - OpenCV| = %.3g px over %zu points\n", GetParam().name.c_str(),
              max_error, xn.size());
}

INSTANTIATE_TEST_SUITE_P(Models, CameraOpenCvTest, ::testing::ValuesIn(test::all_cases()), test::case_name);

}  // namespace
}  // namespace mrvs::camera
