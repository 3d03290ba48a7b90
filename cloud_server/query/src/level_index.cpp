#include "level_index.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

#include <fmt/format.h>

#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map::detail {
namespace {

/// Dense brick bitmaps covering more bricks than this are not built (hash table instead):
/// 16 bytes per 64 bricks, so at most 32 MiB.
constexpr std::uint64_t kMaxDenseBricks = std::uint64_t{1} << 27;

std::string level_name(int level_number, double resolution) {
  return fmt::format("map level {} (resolution {} m)", level_number, resolution);
}

}  // namespace

std::uint64_t LevelIndex::pack_brick(std::int32_t bx, std::int32_t by, std::int32_t bz) {
  return voxel::pack(voxel::VoxelIndex(bx, by, bz));
}

StatusOr<LevelIndex> LevelIndex::build(const MapLevel& level, int level_number) {
  if (!std::isfinite(level.resolution) || !(level.resolution > 0.0)) {
    return absl::InvalidArgumentError(
        fmt::format("{}: the resolution must be finite and positive (rebuild the map with valid levels)",
                    level_name(level_number, level.resolution)));
  }
  if (level.points.size() >= std::numeric_limits<std::uint32_t>::max()) {
    return absl::InvalidArgumentError(fmt::format("{}: {} points, the query index holds at most 2^32 - 2",
                                                  level_name(level_number, level.resolution),
                                                  level.points.size()));
  }
  LevelIndex index;
  index.resolution_ = level.resolution;
  std::vector<Entry> entries;
  MRVS_RETURN_IF_ERROR(index.collect(level, level_number, entries));
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return a.cell != b.cell ? a.cell < b.cell : (a.bit != b.bit ? a.bit < b.bit : a.point < b.point);
  });
  MRVS_RETURN_IF_ERROR(index.fill(level, level_number, entries));
  index.build_lookup();
  return index;
}

Status LevelIndex::collect(const MapLevel& level, int level_number, std::vector<Entry>& entries) {
  std::vector<voxel::VoxelIndex> voxels;
  voxels.reserve(level.points.size());
  for (std::size_t i = 0; i < level.points.size(); ++i) {
    const Eigen::Vector3f& p = level.points[i].position;
    if (!p.allFinite()) {
      return absl::InvalidArgumentError(
          fmt::format("{}: point {} has a non-finite position (remove it from the map)",
                      level_name(level_number, level.resolution), i));
    }
    const std::optional<voxel::VoxelIndex> v = voxel_of(p, level.resolution);
    if (!v) {
      return absl::InvalidArgumentError(
          fmt::format("{}: point {} at ({}, {}, {}) m is outside the packable voxel range +-2^20 voxels "
                      "(choose a map origin closer to the points)",
                      level_name(level_number, level.resolution), i, p.x(), p.y(), p.z()));
    }
    voxels.push_back(*v);
  }
  if (voxels.empty()) return absl::OkStatus();
  // Traversal box: the occupied bricks plus one empty brick of margin on every side, which
  // absorbs rounding where a ray is clipped to the box.
  Eigen::Vector3i lo = voxels.front().unaryExpr(&brick_of);
  Eigen::Vector3i hi = lo;
  for (const voxel::VoxelIndex& v : voxels) {
    lo = lo.cwiseMin(v.unaryExpr(&brick_of));
    hi = hi.cwiseMax(v.unaryExpr(&brick_of));
  }
  brick_lo_ = lo.array() - 1;
  brick_hi_ = hi.array() + 1;
  for (int a = 0; a < 3; ++a)
    dims_[static_cast<std::size_t>(a)] = static_cast<std::uint64_t>(brick_hi_[a] - brick_lo_[a] + 1);
  const double brick_m = kBrickEdge * resolution_;
  box_ = Eigen::AlignedBox3d(brick_lo_.cast<double>() * brick_m,
                             (brick_hi_.cast<double>().array() + 1.0).matrix() * brick_m);
  entries.reserve(voxels.size());
  for (std::size_t i = 0; i < voxels.size(); ++i) {
    const voxel::VoxelIndex& v = voxels[i];
    entries.push_back({cell_of(brick_of(v.x()), brick_of(v.y()), brick_of(v.z())),
                       static_cast<std::uint32_t>(bit_of(v.x(), v.y(), v.z())),
                       static_cast<std::uint32_t>(i)});
  }
  return absl::OkStatus();
}

Status LevelIndex::fill(const MapLevel& level, int level_number, const std::vector<Entry>& entries) {
  order_.reserve(entries.size());
  positions_.reserve(entries.size());
  for (std::size_t e = 0; e < entries.size(); ++e) {
    const Entry& entry = entries[e];
    const Eigen::Vector3f& p = level.points[entry.point].position;
    if (e > 0 && entry.cell == entries[e - 1].cell && entry.bit == entries[e - 1].bit) {
      const voxel::VoxelIndex v = voxel_of(p, level.resolution).value();
      return absl::InvalidArgumentError(fmt::format(
          "{}: points {} and {} are both in voxel ({}, {}, {}); a level holds at most one point per voxel "
          "(build the map with build_voxel_map)",
          level_name(level_number, level.resolution), entries[e - 1].point, entry.point, v.x(), v.y(),
          v.z()));
    }
    if (e == 0 || entry.cell != entries[e - 1].cell) {
      masks_.emplace_back();
      bases_.push_back(static_cast<std::uint32_t>(e));
      const voxel::VoxelIndex v = voxel_of(p, level.resolution).value();
      brick_coords_.push_back(v.unaryExpr(&brick_of));
    }
    masks_.back().words[entry.bit >> 6] |= std::uint64_t{1} << (entry.bit & 63);
    order_.push_back(entry.point);
    positions_.push_back(p);
  }
  return absl::OkStatus();
}

void LevelIndex::build_lookup() {
  if (brick_coords_.empty()) return;
  const bool dense = dims_[0] <= kMaxDenseBricks && dims_[1] <= kMaxDenseBricks &&
                     dims_[2] <= kMaxDenseBricks && dims_[0] * dims_[1] <= kMaxDenseBricks &&
                     dims_[0] * dims_[1] * dims_[2] <= kMaxDenseBricks;
  if (dense) {
    // Ordinals follow the box order (entries were sorted by cell): rank = ordinal.
    dense_.assign((dims_[0] * dims_[1] * dims_[2] + 63) / 64, DenseWord{});
    for (const Eigen::Vector3i& b : brick_coords_) {
      const std::uint64_t cell = cell_of(b.x(), b.y(), b.z());
      dense_[cell >> 6].bits |= std::uint64_t{1} << (cell & 63);
    }
    std::uint32_t rank = 0;
    for (DenseWord& word : dense_) {
      word.rank = rank;
      rank += static_cast<std::uint32_t>(__builtin_popcountll(word.bits));
    }
  } else {
    std::uint64_t capacity = 16;
    while (capacity < 2 * masks_.size()) capacity *= 2;
    slots_.assign(capacity, BrickSlot{});
    slot_mask_ = capacity - 1;
    for (std::uint32_t b = 0; b < masks_.size(); ++b) {
      const std::uint64_t key = pack_brick(brick_coords_[b].x(), brick_coords_[b].y(), brick_coords_[b].z());
      std::uint64_t i = mix64(key) & slot_mask_;
      while (slots_[i].key != kEmptyKey) i = (i + 1) & slot_mask_;
      slots_[i].key = key;
      slots_[i].brick = b;
    }
  }
  brick_coords_.clear();
  brick_coords_.shrink_to_fit();
}

std::size_t LevelIndex::memory_bytes() const {
  return slots_.size() * sizeof(BrickSlot) + masks_.size() * sizeof(BrickMask) +
         bases_.size() * sizeof(std::uint32_t) + order_.size() * sizeof(std::uint32_t) +
         positions_.size() * sizeof(Eigen::Vector3f) + dense_.size() * sizeof(DenseWord);
}

}  // namespace mrvs::map::detail
