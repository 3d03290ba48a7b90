#include "mrvs/map/voxel_map.h"

#include <cmath>

namespace mrvs::map {

int VoxelMap::level_of(double resolution) const {
  if (!std::isfinite(resolution) || !(resolution > 0.0)) return -1;
  constexpr double kRelativeTolerance = 1e-4;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    const double r = levels[i].resolution;
    if (std::abs(r - resolution) <= kRelativeTolerance * std::abs(r)) return static_cast<int>(i);
  }
  return -1;
}

std::vector<double> VoxelMap::resolutions() const {
  std::vector<double> out;
  out.reserve(levels.size());
  for (const MapLevel& level : levels) out.push_back(level.resolution);
  return out;
}

std::uint64_t VoxelMap::point_count() const {
  std::uint64_t n = 0;
  for (const MapLevel& level : levels) n += level.points.size();
  return n;
}

std::optional<voxel::VoxelIndex> voxel_of(const Eigen::Vector3f& local_position, double resolution) {
  if (!std::isfinite(resolution) || !(resolution > 0.0)) return std::nullopt;
  return voxel::index_of<double>(local_position.cast<double>(), resolution);
}

}  // namespace mrvs::map
