#include "mrvs/edge/registered_map.h"

#include <algorithm>

namespace mrvs::edge {

std::optional<std::uint64_t> RegisteredMap::key_of(const Vec3d& p) const {
  const auto index = voxel::index_of<double>(p, voxel_m_);
  if (!index) return std::nullopt;
  return voxel::pack(*index);
}

bool RegisteredMap::has_room(const Vec3d& p) const {
  const auto key = key_of(p);
  if (!key) return false;
  const auto it = cells_.find(*key);
  return it == cells_.end() || static_cast<int>(it->second.size()) < per_voxel_;
}

bool RegisteredMap::add(FeatureId id, const Vec3d& p) {
  const auto key = key_of(p);
  if (!key || contains(id) || !has_room(p)) return false;
  cells_[*key].push_back(id);
  host_[id] = *key;
  return true;
}

void RegisteredMap::remove(FeatureId id) {
  const auto it = host_.find(id);
  if (it == host_.end()) return;
  auto& cell = cells_[it->second];
  cell.erase(std::remove(cell.begin(), cell.end(), id), cell.end());
  if (cell.empty()) cells_.erase(it->second);
  host_.erase(it);
}

void RegisteredMap::move(FeatureId id, const Vec3d& p) {
  const auto it = host_.find(id);
  const auto key = key_of(p);
  if (it == host_.end() || !key || *key == it->second || !has_room(p)) return;
  remove(id);
  cells_[*key].push_back(id);
  host_[id] = *key;
}

std::vector<FeatureId> RegisteredMap::neighbourhood(const Vec3d& p, int radius) const {
  std::vector<FeatureId> out;
  const auto index = voxel::index_of<double>(p, voxel_m_);
  if (!index) return out;
  for (int dx = -radius; dx <= radius; ++dx) {
    for (int dy = -radius; dy <= radius; ++dy) {
      for (int dz = -radius; dz <= radius; ++dz) {
        const voxel::VoxelIndex n = *index + voxel::VoxelIndex(dx, dy, dz);
        if (!voxel::packable(n)) continue;
        const auto it = cells_.find(voxel::pack(n));
        if (it != cells_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
      }
    }
  }
  return out;
}

}  // namespace mrvs::edge
