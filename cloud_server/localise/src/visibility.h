#pragma once
// Free-space evidence: a camera saw each submap point along a line of sight, so under the
// right pose that line crosses no surface of the map before the point. Under a pose that puts
// the submap's walls on another room's walls (a turned, self-similar room) the lines to what
// lies behind that room's boxes pass through them. The share of lines that do is what tells
// such poses apart where the surfaces alone fit almost equally well.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "likelihood_grid.h"

namespace mrvs::localise {

/// A point and where it was seen from (gravity-aligned, relative to the anchor, m).
struct SightLine {
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
};

/// Share of `lines`, placed at (yaw, anchor) (map-local), that cross an occupied cell of
/// `grid`'s base level on their way: from `start_m` after the viewpoint to margin_m +
/// margin_fraction * length before the point (the surface the point lies on, its noise, and a
/// line that grazes it at a low angle do not count). 0 without lines.
double blocked_share(const LikelihoodPyramid& grid, const std::vector<SightLine>& lines, double yaw,
                     const Eigen::Vector3d& anchor, double start_m, double margin_m, double margin_fraction);

/// The same check per line, in order: 1 where the line crosses a surface, else 0.
std::vector<std::uint8_t> blocked_lines(const LikelihoodPyramid& grid, const std::vector<SightLine>& lines,
                                        double yaw, const Eigen::Vector3d& anchor, double start_m,
                                        double margin_m, double margin_fraction);

}  // namespace mrvs::localise
