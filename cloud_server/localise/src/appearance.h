#pragma once
// The appearance check: where a room's geometry fits two placements equally (turned by 90 or
// 180 deg, or slid along a wall), their textures differ. Under the right pose the submap's
// image brightness rises and falls with the map's intensity at the same places; under a wrong
// one it does not. Rank correlation (Spearman), so an unknown monotonic map between the
// camera's brightness and the scanner's reflectivity (gain, gamma, exposure) does not matter
// (Wolcott & Eustice, IROS 2014, localise a camera in a LiDAR reflectivity map the same way,
// with normalised mutual information).
#include <vector>

#include "map_surface.h"
#include "point_to_plane.h"

namespace mrvs::localise {

struct Appearance {
  double correlation = 0.0;  ///< Spearman's rho of brightness against map intensity, [-1, 1]
  int points = 0;            ///< inliers with a brightness and a map intensity
};

/// Spearman's rank correlation of two equally long samples (ties get their mean rank); 0 when
/// fewer than 3 values or either sample is constant.
double rank_correlation(const std::vector<double>& a, const std::vector<double>& b);

/// The correlation over the fine stage's inliers (FineResult::matched) that have a brightness
/// (> 0, one per fine point) and whose map point has an intensity.
Appearance appearance(const MapSurface& surface, const FineResult& fine,
                      const std::vector<float>& brightness);

struct SlideOptions {
  double range_m = 0.3;  ///< offsets tried: -range .. range ...
  double step_m = 0.02;  ///< ... in these steps: first every coarse_stride-th over the
                         ///< range, then every one within a stride of the best of those
  int coarse_stride = 1;
  double margin_sd = 2.0;           ///< a gain within this many standard errors is no gain
  int min_points = 50;              ///< fewer inliers with a brightness: no evidence
  double min_fitness_ratio = 0.95;  ///< a slid pose keeps at least this share of the start's fitness
};

struct Slide {
  double offset_m = 0.0;  ///< along the direction; 0: the start stays
  FineResult fine;        ///< the fit at the chosen pose (the start's when it stays)
  Appearance appearance;  ///< there
  Appearance start;       ///< at the start
  /// The best offset is the last one tried (+-range): the appearance still rises beyond the
  /// range, so the peak (and the pose) lies farther along; offset_m is then that edge.
  bool unbracketed = false;
};

/// Where the geometry leaves a direction weakly held (a submap of one wall and the floor slides
/// along the wall), the texture still holds it: the anchor moved by s * direction (unit) for s in
/// [-range, range] (coarse to fine: SlideOptions::coarse_stride), the offset whose appearance
/// correlation is highest, taken only when it beats
/// the start's by margin_sd standard errors and keeps the geometric fit (min_fitness_ratio).
/// Each pose is evaluated as it is (`fine` with no iterations).
Slide slide_by_appearance(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points,
                          const std::vector<float>& brightness, double yaw, const Eigen::Vector3d& anchor,
                          const Eigen::Vector3d& direction, FineOptions fine, const SlideOptions& options);

}  // namespace mrvs::localise
