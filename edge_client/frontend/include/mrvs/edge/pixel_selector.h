#pragma once
// DSO-style pixel selection (algorithm.md 5.2): per 32x32 block an adaptive gradient
// threshold; three nested cell sizes pot, 2 pot, 4 pot; in each finest cell the pixel with the
// largest gradient along a per-cell direction among those above the threshold, and a coarser
// cell (judged on pyramid level 1 or 2 with a lowered threshold) only when no finer cell in it
// produced one. pot adapts once to the wanted count; a surplus is thinned evenly.
#include <vector>

#include <opencv2/core/types.hpp>

#include "mrvs/edge/image_pyramid.h"
#include "mrvs/edge/tracker_options.h"

namespace mrvs::edge {

struct SelectedPixel {
  cv::Point2f uv;      ///< level-0 pixel
  int level = 0;       ///< 0, 1 or 2: the cell size (pot, 2 pot, 4 pot) it won
  float score = 0.0f;  ///< |gradient . direction| at its level
};

struct SelectorResult {
  std::vector<SelectedPixel> pixels;
  int pot = 0;     ///< finest cell size of the last pass, px
  int passes = 0;  ///< 1, or 2 when pot was adapted
  int found = 0;   ///< what the last pass found, before thinning to `want`
};

/// Block thresholds on |grad|^2 of level 0 (one per block_size block, row-major), smoothed
/// over 3x3 blocks and squared. Exposed for tests.
cv::Mat gradient_thresholds(const GradientLevel& level0, const SelectorOptions& options);

/// Selects about `want` pixels of `pyramid` (at least 3 levels) outside `mask` (CV_8UC1 of
/// level 0's size, non-zero = excluded; may be empty). At most `want` are returned.
/// `pot_hint` > 0 starts from that cell size instead of options.initial_pot (DSO keeps the
/// last frame's: one pass instead of two when the scene changes slowly).
SelectorResult select_pixels(const GradientPyramid& pyramid, const cv::Mat& mask, int want,
                             const SelectorOptions& options, int pot_hint = 0);

}  // namespace mrvs::edge
