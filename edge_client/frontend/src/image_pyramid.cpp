#include "mrvs/edge/image_pyramid.h"

#include <fmt/format.h>
#include <opencv2/imgproc.hpp>

namespace mrvs::edge {
namespace {

/// Central differences inside, zero on the one-pixel border.
void central_gradients(GradientLevel* level) {
  const cv::Mat& img = level->image;
  level->gx.create(img.size(), CV_32F);
  level->gy.create(img.size(), CV_32F);
  level->mag2.create(img.size(), CV_32F);
  const int w = img.cols, h = img.rows;
  for (int y = 0; y < h; ++y) {
    const float* row = img.ptr<float>(y);
    const float* up = img.ptr<float>(y > 0 ? y - 1 : y);
    const float* down = img.ptr<float>(y + 1 < h ? y + 1 : y);
    float* gx = level->gx.ptr<float>(y);
    float* gy = level->gy.ptr<float>(y);
    float* m2 = level->mag2.ptr<float>(y);
    const bool border_row = y == 0 || y == h - 1;
    gx[0] = gy[0] = m2[0] = 0.0f;
    gx[w - 1] = gy[w - 1] = m2[w - 1] = 0.0f;
    for (int x = 1; x < w - 1; ++x) {
      const float dx = border_row ? 0.0f : 0.5f * (row[x + 1] - row[x - 1]);
      const float dy = border_row ? 0.0f : 0.5f * (down[x] - up[x]);
      gx[x] = dx;
      gy[x] = dy;
      m2[x] = dx * dx + dy * dy;
    }
  }
}

/// 2x2 block average (odd last row / column dropped).
void halve(const cv::Mat& src, cv::Mat* dst) {
  const int w = src.cols / 2, h = src.rows / 2;
  dst->create(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    const float* r0 = src.ptr<float>(2 * y);
    const float* r1 = src.ptr<float>(2 * y + 1);
    float* d = dst->ptr<float>(y);
    for (int x = 0; x < w; ++x) d[x] = 0.25f * (r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1]);
  }
}

}  // namespace

Status build_gradient_pyramid(const cv::Mat& image, int levels, GradientPyramid* out) {
  if (image.empty() || image.type() != CV_8UC1) {
    return absl::InvalidArgumentError(
        "build_gradient_pyramid: expected a non-empty 8-bit grey image (CV_8UC1)");
  }
  if (levels < 1 || levels > 12) {
    return absl::InvalidArgumentError(
        fmt::format("build_gradient_pyramid: levels {} not in [1, 12]", levels));
  }
  const int min_side = (1 << (levels - 1)) * 4;
  if (image.cols < min_side || image.rows < min_side) {
    return absl::InvalidArgumentError(
        fmt::format("build_gradient_pyramid: a {}x{} image is too small for {} levels (needs {} px a side)",
                    image.cols, image.rows, levels, min_side));
  }
  out->levels.resize(static_cast<std::size_t>(levels));
  image.convertTo(out->levels[0].image, CV_32F);
  for (std::size_t l = 1; l < out->levels.size(); ++l) halve(out->levels[l - 1].image, &out->levels[l].image);
  for (GradientLevel& level : out->levels) central_gradients(&level);
  return absl::OkStatus();
}

}  // namespace mrvs::edge
