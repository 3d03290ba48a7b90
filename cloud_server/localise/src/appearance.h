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

}  // namespace mrvs::localise
