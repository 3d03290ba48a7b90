#include "visibility.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace mrvs::localise {

namespace {

/// An occupied cell holds 255 at the base level (its neighbours less: likelihood_grid.h).
constexpr std::uint8_t kOccupied = 255;

}  // namespace

std::vector<std::uint8_t> blocked_lines(const LikelihoodPyramid& grid, const std::vector<SightLine>& lines,
                                        double yaw, const Eigen::Vector3d& anchor, double start_m,
                                        double margin_m, double margin_fraction) {
  std::vector<std::uint8_t> out(lines.size(), 0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double step = 0.5 * grid.resolution();
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const SightLine& l = lines[i];
    const Eigen::Vector3d from = R * l.viewpoint + anchor;
    const Eigen::Vector3d to = R * l.point + anchor;
    const double length = (to - from).norm();
    const double end = length - margin_m - margin_fraction * length;
    if (end <= start_m) continue;
    const Eigen::Vector3d dir = (to - from) / length;
    for (double t = start_m; t <= end; t += step) {
      if (grid.value(0, grid.cell_of(from + t * dir)) == kOccupied) {
        out[i] = 1;
        break;
      }
    }
  }
  return out;
}

double blocked_share(const LikelihoodPyramid& grid, const std::vector<SightLine>& lines, double yaw,
                     const Eigen::Vector3d& anchor, double start_m, double margin_m, double margin_fraction) {
  if (lines.empty()) return 0.0;
  const std::vector<std::uint8_t> b =
      blocked_lines(grid, lines, yaw, anchor, start_m, margin_m, margin_fraction);
  return static_cast<double>(std::count(b.begin(), b.end(), 1)) / static_cast<double>(lines.size());
}

}  // namespace mrvs::localise
