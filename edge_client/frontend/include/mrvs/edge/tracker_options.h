#pragma once
// Options of the edge front-end (algorithm.md section 5): section `tracker` of
// config/edge_*.yaml.
#include <string>

#include "mrvs/config/options.h"

namespace mrvs::edge {

/// OpenCV's default minEigThreshold of calcOpticalFlowPyrLK.
inline constexpr double kOpenCvMinEigenvalue = 1e-4;

/// DSO-style pixel selector (algorithm.md 5.2).
struct SelectorOptions : config::OptionsEquality<SelectorOptions> {
  int block_size = 32;           ///< gradient-histogram blocks, px
  double hist_cut = 0.5;         ///< threshold = this quantile of |grad| in a block ...
  double hist_add = 7.0;         ///< ... plus this, grey levels per px
  double down_weight = 0.75;     ///< threshold factor per coarser level (levels 1 and 2)
  int initial_pot = 3;           ///< finest cell size, px (adapted to the wanted count)
  int border_px = 5;             ///< pixels this close to the border are never selected
  int direction_seed = 3141592;  ///< keys the per-cell gradient direction (16 directions)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("block_size", block_size, in_range(8, 256), "gradient-histogram block size, px");
    v("hist_cut", hist_cut, in_range(0.0, 1.0), "quantile of the block's gradient histogram");
    v("hist_add", hist_add, in_range(0.0, 100.0), "added to the quantile, grey levels");
    v("down_weight", down_weight, in_range(0.1, 1.0), "threshold factor per coarser level");
    v("initial_pot", initial_pot, in_range(1, 64), "finest cell size, px");
    v("border_px", border_px, in_range(1, 100), "border never selected, px");
    v("direction_seed", direction_seed, in_range(0, 2147483647), "seed of the per-cell directions");
  }
};

struct TrackerOptions : config::OptionsEquality<TrackerOptions> {
  int max_features = 200;               ///< left-image features per frame (the paper's figure)
  int min_px_dist = 10;                 ///< one feature per cell of this size, px (EuRoC 10, KAIST 20)
  int detect_min_missing = 20;          ///< detect when more than min(this, max/2) are missing
  int border_px = 10;                   ///< features closer to the border are dropped, px
  std::string mask_mode = "square";     ///< around kept features: "square", or "row_band" (reference code)
  bool histogram_equalization = true;   ///< cv::equalizeHist before KLT
  int klt_window = 11;                  ///< KLT window side, px
  int klt_max_level = 4;                ///< KLT pyramid: levels 0..this
  int klt_iterations = 30;              ///< KLT iterations per level
  double klt_epsilon = 0.01;            ///< KLT convergence, px
  double temporal_ransac_px = 1.0;      ///< fundamental-matrix RANSAC threshold, px
  double temporal_round_trip_px = 0.5;  ///< max previous -> current -> previous KLT error, px (0 = off)
  /// Temporal KLT windows whose smallest gradient-matrix eigenvalue per pixel (OpenCV's
  /// minEigThreshold scale) is below this are lost: edge-like patches slide along the edge.
  double temporal_min_eigenvalue = kOpenCvMinEigenvalue;
  double temporal_ransac_confidence = 0.999;
  int min_ransac_points = 10;       ///< fewer temporal matches: all rejected (tracking lost)
  double stereo_epipolar_px = 1.0;  ///< max distance to the calibrated epipolar line, px
  double stereo_lr_px = 0.5;        ///< left -> right -> left round trip, px
  double stereo_min_depth_m = 0.1;  ///< stereo pairs triangulating nearer (or behind) are dropped
  SelectorOptions selector;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("max_features", max_features, in_range(1, 5000), "features per frame (left image)");
    v("min_px_dist", min_px_dist, in_range(1, 200), "one feature per cell of this size, px");
    v("detect_min_missing", detect_min_missing, in_range(1, 5000), "detect when this many are missing");
    v("border_px", border_px, in_range(1, 100), "features closer to the border are dropped, px");
    v("mask_mode", mask_mode, one_of({"square", "row_band"}), "mask around kept features");
    v("histogram_equalization", histogram_equalization, any(), "equalize images before KLT");
    v("klt_window", klt_window, in_range(5, 61), "KLT window side, px");
    v("klt_max_level", klt_max_level, in_range(0, 8), "KLT pyramid levels above the image");
    v("klt_iterations", klt_iterations, in_range(1, 200), "KLT iterations per level");
    v("klt_epsilon", klt_epsilon, in_range(1e-6, 1.0), "KLT convergence, px");
    v("temporal_ransac_px", temporal_ransac_px, in_range(0.05, 20.0), "temporal RANSAC threshold, px");
    v("temporal_round_trip_px", temporal_round_trip_px, in_range(0.0, 20.0),
      "temporal KLT round trip, px (0 = off)");
    v("temporal_min_eigenvalue", temporal_min_eigenvalue, in_range(0.0, 1.0),
      "temporal KLT: smallest eigenvalue per pixel of a tracked window (OpenCV's minEigThreshold)");
    v("temporal_ransac_confidence", temporal_ransac_confidence, in_range(0.5, 0.999999), "RANSAC confidence");
    v("min_ransac_points", min_ransac_points, in_range(8, 1000), "fewer temporal matches: tracking lost");
    v("stereo_epipolar_px", stereo_epipolar_px, in_range(0.05, 20.0), "stereo epipolar threshold, px");
    v("stereo_lr_px", stereo_lr_px, in_range(0.01, 20.0), "stereo left-right consistency, px");
    v("stereo_min_depth_m", stereo_min_depth_m, in_range(0.0, 100.0), "nearest accepted stereo depth, m");
    v.section("selector", selector, "DSO-style pixel selector");
  }
};

}  // namespace mrvs::edge
