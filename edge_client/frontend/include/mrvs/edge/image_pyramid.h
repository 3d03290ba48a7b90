#pragma once
// Image processing of one frame (algorithm.md 5.1): a float pyramid by 2x2 averaging and
// central-difference gradients per level, as the pixel selector needs them.
#include <vector>

#include <opencv2/core/mat.hpp>

#include "mrvs/core/status.h"

namespace mrvs::edge {

struct GradientLevel {
  cv::Mat image;  ///< CV_32F grey levels
  cv::Mat gx;     ///< CV_32F, (I(x+1) - I(x-1)) / 2; 0 on the border columns
  cv::Mat gy;     ///< CV_32F, (I(y+1) - I(y-1)) / 2; 0 on the border rows
  cv::Mat mag2;   ///< CV_32F, gx^2 + gy^2
};

struct GradientPyramid {
  std::vector<GradientLevel> levels;  ///< level l has half the size of level l - 1 (floor)
};

/// Builds `levels` levels (>= 1) of `image` (CV_8UC1, at least 2^(levels-1) * 4 px a side)
/// into `out`, reusing its buffers. InvalidArgument for another type or a too small image.
Status build_gradient_pyramid(const cv::Mat& image, int levels, GradientPyramid* out);

}  // namespace mrvs::edge
