#pragma once
// The coarse stage: a branch-and-bound search over (x, y, z, yaw) for the poses that put the
// most submap points near the map's surface (Hess et al., ICRA 2016, in 3-D with gravity
// known). For every yaw step the submap's points are rotated once; a candidate is a window
// of 2^h x 2^h x 2^h anchor cells whose best score is bounded by the pyramid's level h, so a
// window that cannot beat the hypotheses kept so far is never opened. The result is exact on
// the grid's lattice: the best `max_hypotheses` mutually distinct poses.
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "likelihood_grid.h"

namespace mrvs::localise {

struct SearchWindow {
  Eigen::Vector3i anchor_min = Eigen::Vector3i::Zero();  ///< anchor cells searched, inclusive
  Eigen::Vector3i anchor_max = Eigen::Vector3i::Zero();
  /// The anchor must also lie within this distance of `centre` (map-local, m); nullopt: box only.
  std::optional<double> radius_m;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double yaw_step_rad = 0.02;
};

struct SearchOptions {
  int max_hypotheses = 4;
  double min_score = 0.2;       ///< a pose scoring less is no hypothesis, [0, 1]
  double relative_score = 0.0;  ///< ... nor one scoring less than this times the best found, [0, 1]
  long long max_nodes = 0;  ///< stop after scoring this many windows (0: never); SearchStats::complete says
  double distinct_m = 1.0;  ///< hypotheses closer than this ...
  double distinct_rad = 0.17;  ///< ... and turned less than this are one
};

struct Hypothesis {
  double yaw = 0.0;                                  ///< rad, about +z
  Eigen::Vector3d anchor = Eigen::Vector3d::Zero();  ///< map-local position of the submap's anchor, m
  double score = 0.0;                                ///< mean likelihood of the points, [0, 1]
};

struct SearchStats {
  long long nodes = 0;  ///< windows scored
  int yaws = 0;
  bool complete = true;  ///< false: stopped at max_nodes (the hypotheses are the best found so far)
};

/// The best distinct hypotheses, best first, for `points` (gravity-aligned, relative to the
/// anchor, m) over `window`.
std::vector<Hypothesis> correlative_search(const LikelihoodPyramid& grid,
                                           const std::vector<Eigen::Vector3d>& points,
                                           const SearchWindow& window, const SearchOptions& options,
                                           SearchStats* stats = nullptr);

/// True when a and b are the same pose within the options' distinct_m / distinct_rad.
bool same_pose(const Hypothesis& a, const Hypothesis& b, const SearchOptions& options);

/// Smallest angle between two yaws, rad.
double yaw_difference(double a, double b);

}  // namespace mrvs::localise
