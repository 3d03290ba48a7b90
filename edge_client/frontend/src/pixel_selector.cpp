#include "mrvs/edge/pixel_selector.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "mrvs/core/hash.h"

namespace mrvs::edge {
namespace {

constexpr int kHistBins = 50;
constexpr float kHistClip = 48.0f;

/// 16 unit directions; a cell's direction comes from a hash of its position and size.
const std::array<cv::Point2f, 16>& directions() {
  static const std::array<cv::Point2f, 16> dirs = [] {
    std::array<cv::Point2f, 16> d;
    for (int i = 0; i < 16; ++i) {
      const double a = 2.0 * M_PI * i / 16.0;
      d[static_cast<std::size_t>(i)] =
          cv::Point2f(static_cast<float>(std::cos(a)), static_cast<float>(std::sin(a)));
    }
    return d;
  }();
  return dirs;
}

cv::Point2f cell_direction(int x, int y, int size, int seed) {
  const std::uint64_t h =
      mix64(static_cast<std::uint64_t>(seed) ^
            mix64((static_cast<std::uint64_t>(x) << 32) ^ (static_cast<std::uint64_t>(y) << 8) ^
                  static_cast<std::uint64_t>(size)));
  return directions()[h & 15u];
}

struct Candidate {
  int x = -1, y = -1;
  float score = -1.0f;
  bool valid() const { return x >= 0; }
  void offer(int cx, int cy, float s) {
    if (s > score) x = cx, y = cy, score = s;
  }
};

/// One selection pass with finest cell size `pot`.
struct Pass {
  const GradientPyramid& pyr;
  const cv::Mat& mask;
  const cv::Mat& thresholds;
  const std::vector<int>& block_of_column;  ///< x -> threshold column
  const SelectorOptions& options;
  int pot;
  std::vector<SelectedPixel>* out;

  /// Best pixel of the square (x0, y0, size) at `level` along `d`: pixels whose |grad|^2 at
  /// that level exceeds the block threshold times down_weight (level 1) or its cube (level
  /// 2). Only called for level l when no pixel of the square passed a finer level, which is
  /// DSO's per-pixel "level 0, else level 1, else level 2" without testing every level.
  Candidate scan(int x0, int y0, int size, int level, const cv::Point2f& d) const {
    const GradientLevel& l0 = pyr.levels[0];
    const GradientLevel& lv = pyr.levels[static_cast<std::size_t>(level)];
    const int w = l0.image.cols, h = l0.image.rows, b = options.border_px;
    const float dw = static_cast<float>(options.down_weight);
    const float factor = level == 0 ? 1.0f : (level == 1 ? dw : dw * dw * dw);
    const int x_begin = std::max(x0, b), x_end = std::min(x0 + size, w - b);
    Candidate best;
    for (int y = std::max(y0, b); y < std::min(y0 + size, h - b); ++y) {
      const std::uint8_t* m = mask.empty() ? nullptr : mask.ptr<std::uint8_t>(y);
      const float* th_row = thresholds.ptr<float>(std::min(y / options.block_size, thresholds.rows - 1));
      const int yl = std::min(y >> level, lv.image.rows - 1);
      const float* mag = lv.mag2.ptr<float>(yl);
      const float* gx = lv.gx.ptr<float>(yl);
      const float* gy = lv.gy.ptr<float>(yl);
      const int x_max = lv.image.cols - 1;
      for (int x = x_begin; x < x_end; ++x) {
        if (m != nullptr && m[x] != 0) continue;
        const int xl = std::min(x >> level, x_max);
        if (mag[xl] > factor * th_row[block_of_column[static_cast<std::size_t>(x)]]) {
          best.offer(x, y, std::abs(gx[xl] * d.x + gy[xl] * d.y));
        }
      }
    }
    return best;
  }

  void push(const Candidate& c, int level) const {
    out->push_back(
        SelectedPixel{cv::Point2f(static_cast<float>(c.x), static_cast<float>(c.y)), level, c.score});
  }

  /// The 4 pot block at (bx, by): finest cells first, a 2 pot sub-block only when none of
  /// its cells produced a point, the block only when none of its sub-blocks did.
  void block(int bx, int by) const {
    bool found4 = false;
    const int seed = options.direction_seed;
    for (int sy = by; sy < by + 4 * pot; sy += 2 * pot) {
      for (int sx = bx; sx < bx + 4 * pot; sx += 2 * pot) {
        bool found2 = false;
        for (int cy = sy; cy < sy + 2 * pot; cy += pot) {
          for (int cx = sx; cx < sx + 2 * pot; cx += pot) {
            const Candidate c0 = scan(cx, cy, pot, 0, cell_direction(cx, cy, 1, seed));
            if (c0.valid()) push(c0, 0), found2 = true;
          }
        }
        if (!found2) {
          const Candidate c1 = scan(sx, sy, 2 * pot, 1, cell_direction(sx, sy, 2, seed));
          if (c1.valid()) push(c1, 1), found2 = true;
        }
        found4 = found4 || found2;
      }
    }
    if (!found4) {
      const Candidate c2 = scan(bx, by, 4 * pot, 2, cell_direction(bx, by, 4, seed));
      if (c2.valid()) push(c2, 2);
    }
  }

  void run() const {
    const int w = pyr.levels[0].image.cols, h = pyr.levels[0].image.rows;
    for (int by = 0; by < h; by += 4 * pot) {
      for (int bx = 0; bx < w; bx += 4 * pot) block(bx, by);
    }
  }
};

/// Keeps `want` of `pixels`, chosen by a position hash: an even thinning, deterministic.
void thin_evenly(std::vector<SelectedPixel>* pixels, std::size_t want, int seed) {
  const auto key = [seed](const SelectedPixel& p) {
    return mix64(static_cast<std::uint64_t>(seed) * 0x9E3779B97F4A7C15ull ^
                 (static_cast<std::uint64_t>(p.uv.x) << 20 | static_cast<std::uint64_t>(p.uv.y)));
  };
  std::vector<std::pair<std::uint64_t, std::size_t>> order;
  order.reserve(pixels->size());
  for (std::size_t i = 0; i < pixels->size(); ++i) order.emplace_back(key((*pixels)[i]), i);
  std::nth_element(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(want), order.end());
  order.resize(want);
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  std::vector<SelectedPixel> kept;
  kept.reserve(want);
  for (const auto& o : order) kept.push_back((*pixels)[o.second]);
  pixels->swap(kept);
}

}  // namespace

cv::Mat gradient_thresholds(const GradientLevel& level0, const SelectorOptions& options) {
  const int bs = options.block_size;
  const int bw = std::max(1, level0.mag2.cols / bs), bh = std::max(1, level0.mag2.rows / bs);
  cv::Mat raw(bh, bw, CV_32F);
  std::array<int, kHistBins> hist{};
  for (int j = 0; j < bh; ++j) {
    for (int i = 0; i < bw; ++i) {
      hist.fill(0);
      const int y_end = j == bh - 1 ? level0.mag2.rows : (j + 1) * bs;
      const int x_end = i == bw - 1 ? level0.mag2.cols : (i + 1) * bs;
      int count = 0;
      for (int y = j * bs; y < y_end; ++y) {
        const float* m = level0.mag2.ptr<float>(y);
        for (int x = i * bs; x < x_end; ++x, ++count) {
          ++hist[static_cast<std::size_t>(std::min(std::sqrt(m[x]), kHistClip))];
        }
      }
      const int target = static_cast<int>(options.hist_cut * count + 0.5);
      int bin = 0;
      for (int acc = 0; bin < kHistBins - 1; ++bin) {
        acc += hist[static_cast<std::size_t>(bin)];
        if (acc >= target) break;
      }
      raw.at<float>(j, i) = static_cast<float>(bin + options.hist_add);
    }
  }
  cv::Mat smoothed(bh, bw, CV_32F);
  for (int j = 0; j < bh; ++j) {
    for (int i = 0; i < bw; ++i) {
      float sum = 0.0f;
      int n = 0;
      for (int dj = -1; dj <= 1; ++dj) {
        for (int di = -1; di <= 1; ++di) {
          if (j + dj < 0 || j + dj >= bh || i + di < 0 || i + di >= bw) continue;
          sum += raw.at<float>(j + dj, i + di);
          ++n;
        }
      }
      const float t = sum / static_cast<float>(n);
      smoothed.at<float>(j, i) = t * t;
    }
  }
  return smoothed;
}

SelectorResult select_pixels(const GradientPyramid& pyramid, const cv::Mat& mask, int want,
                             const SelectorOptions& options, int pot_hint) {
  SelectorResult result;
  if (want <= 0 || pyramid.levels.size() < 3) return result;
  const cv::Mat thresholds = gradient_thresholds(pyramid.levels[0], options);
  const int w = pyramid.levels[0].image.cols, h = pyramid.levels[0].image.rows;
  std::vector<int> block_of_column(static_cast<std::size_t>(w));
  for (int x = 0; x < w; ++x)
    block_of_column[static_cast<std::size_t>(x)] = std::min(x / options.block_size, thresholds.cols - 1);
  const int max_pot = std::max(1, std::min(w, h) / 8);
  int pot = std::clamp(pot_hint > 0 ? pot_hint : options.initial_pot, 1, max_pot);
  for (int pass = 0; pass < 2; ++pass) {
    result.pixels.clear();
    Pass{pyramid, mask, thresholds, block_of_column, options, pot, &result.pixels}.run();
    result.pot = pot;
    result.passes = pass + 1;
    const double have = static_cast<double>(result.pixels.size());
    result.found = static_cast<int>(result.pixels.size());
    // DSO adapts when have/want leaves [0.25, 1.25]; a tracker needs the count it asked for,
    // and thinning a surplus is cheap.
    const double ratio = have / want;
    if (pass == 1 || (ratio >= 0.8 && ratio <= 2.0)) break;
    const double ideal = std::sqrt(have * (pot + 1) * (pot + 1) / want) - 1.0;
    const int next = std::clamp(static_cast<int>(std::lround(ideal)), 1, max_pot);
    if (next == pot) break;
    pot = next;
  }
  if (result.pixels.size() > static_cast<std::size_t>(want)) {
    thin_evenly(&result.pixels, static_cast<std::size_t>(want), options.direction_seed);
  }
  return result;
}

}  // namespace mrvs::edge
