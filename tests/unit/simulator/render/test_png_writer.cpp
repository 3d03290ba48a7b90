// PNG output: 8-bit grayscale, lossless round trip, deterministic bytes, errors naming the path.
#include <cstdint>
#include <fstream>
#include <iterator>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "mrvs/sim/png_writer.h"
#include "mrvs/sim/rng.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

cv::Mat test_image() {
  cv::Mat image(480, 752, CV_8UC1);
  const CounterRng rng(3, Stream::kImageNoise);
  for (int v = 0; v < image.rows; ++v) {
    for (int u = 0; u < image.cols; ++u) {
      image.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(
          (u / 16 + v / 16) % 2 == 0 ? 40 + (u % 7) : 200 + static_cast<int>(rng.uniform(0.0, 20.0, u, v)));
    }
  }
  return image;
}

std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(PngWriter, LosslessEightBitGrayDeterministic) {
  mrvs::test::TempDir dir;
  const cv::Mat image = test_image();
  const auto path = dir / "a.png";
  ASSERT_TRUE(write_png(path, image).ok());
  const cv::Mat back = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(back, image, cv::NORM_INF), 0.0);
  const std::vector<std::uint8_t> bytes = read_bytes(path);
  // IHDR: width, height (big endian), bit depth 8, colour type 0 (grayscale), no interlace.
  ASSERT_GT(bytes.size(), 33u);
  EXPECT_EQ(bytes[16 + 2], 752 >> 8);
  EXPECT_EQ(bytes[16 + 3], 752 & 0xFF);
  EXPECT_EQ(bytes[20 + 3], 480 & 0xFF);
  EXPECT_EQ(bytes[24], 8);
  EXPECT_EQ(bytes[25], 0);
  EXPECT_EQ(bytes[28], 0);
  // Same bytes from encode_png and from a second write.
  const StatusOr<std::vector<std::uint8_t>> encoded = encode_png(image);
  ASSERT_TRUE(encoded.ok());
  EXPECT_EQ(*encoded, bytes);
  ASSERT_TRUE(write_png(dir / "b.png", image).ok());
  EXPECT_EQ(read_bytes(dir / "b.png"), bytes);
}

TEST(PngWriter, ErrorsNameThePath) {
  mrvs::test::TempDir dir;
  const auto missing = dir / "no_such_folder" / "x.png";
  const Status s = write_png(missing, test_image());
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(missing.string()), absl::string_view::npos) << s;
  EXPECT_FALSE(std::filesystem::exists(missing));

  const Status wrong_type = write_png(dir / "c.png", cv::Mat(4, 4, CV_16UC1, cv::Scalar(0)));
  ASSERT_FALSE(wrong_type.ok());
  EXPECT_EQ(wrong_type.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(wrong_type.message().find("c.png"), absl::string_view::npos) << wrong_type;
  EXPECT_FALSE(encode_png(cv::Mat()).ok());
}

}  // namespace
}  // namespace mrvs::sim
