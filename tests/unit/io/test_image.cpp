#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "mrvs/io/image.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using ::testing::HasSubstr;

ImageRecord write(const test::TempDir& dir, const std::string& name, const cv::Mat& image) {
  const auto path = dir / name;
  EXPECT_TRUE(cv::imwrite(path.string(), image));
  return ImageRecord{1403636579763555584, path};
}

TEST(LoadImage, ReadsEightBitGray) {
  test::TempDir dir;
  cv::Mat image(12, 16, CV_8UC1, cv::Scalar(0));
  image.at<std::uint8_t>(3, 5) = 200;
  const ImageRecord record = write(dir, "a.png", image);
  const auto loaded = load_image(record, 16, 12);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->type(), CV_8UC1);
  EXPECT_EQ(loaded->cols, 16);
  EXPECT_EQ(loaded->rows, 12);
  EXPECT_EQ(loaded->at<std::uint8_t>(3, 5), 200);
  EXPECT_EQ(loaded->at<std::uint8_t>(0, 0), 0);
  // Size check off with 0 x 0.
  EXPECT_TRUE(load_image(record, 0, 0).ok());
}

TEST(LoadImage, ConvertsSixteenBitAndColour) {
  test::TempDir dir;
  const ImageRecord deep = write(dir, "deep.png", cv::Mat(4, 6, CV_16UC1, cv::Scalar(0x8000)));
  const auto a = load_image(deep, 6, 4);
  ASSERT_TRUE(a.ok()) << a.status();
  EXPECT_EQ(a->type(), CV_8UC1);
  EXPECT_EQ(a->at<std::uint8_t>(1, 1), 128);
  const ImageRecord colour = write(dir, "colour.png", cv::Mat(4, 6, CV_8UC3, cv::Scalar(100, 100, 100)));
  const auto b = load_image(colour, 6, 4);
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(b->type(), CV_8UC1);
  EXPECT_EQ(b->at<std::uint8_t>(2, 3), 100);
}

TEST(LoadImage, WrongSizeNamesFileAndBothSizes) {
  test::TempDir dir;
  const ImageRecord record = write(dir, "small.png", cv::Mat(12, 16, CV_8UC1, cv::Scalar(7)));
  const auto loaded = load_image(record, 752, 480);
  ASSERT_FALSE(loaded.ok());
  EXPECT_EQ(loaded.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string msg(loaded.status().message());
  EXPECT_THAT(msg, HasSubstr(record.path.string()));
  EXPECT_THAT(msg, HasSubstr("is 16x12 pixels but the camera calibration says 752x480"));
}

TEST(LoadImage, MissingAndUnreadableFilesAreNamed) {
  test::TempDir dir;
  const ImageRecord missing{5, dir / "gone.png"};
  const auto a = load_image(missing, 0, 0);
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(a.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(a.status().message()),
              HasSubstr(missing.path.string() + " (t = 5 ns) does not exist"));
  const ImageRecord garbage{6, dir.write("bad.png", "this is not a png")};
  const auto b = load_image(garbage, 0, 0);
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(b.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(b.status().message()), HasSubstr("cannot decode image " + garbage.path.string()));
  const ImageRecord truncated{7, dir.write("cut.png", std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16))};
  EXPECT_FALSE(load_image(truncated, 0, 0).ok());
}

}  // namespace
}  // namespace mrvs::io
