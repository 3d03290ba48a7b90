#pragma once
// Voxel indexing shared by the cloud map and the edge's registered-point grid.
//
// A point p (metres, in the frame of the grid) lies in voxel (floor(p.x / r), floor(p.y / r),
// floor(p.z / r)) of a grid of size r: floor, not truncation, so cell 0 is [0, r) and cell -1
// is [-r, 0). The index triple packs into one 64-bit key, 21 bits per axis in two's
// complement: indices must lie in [-2^20, 2^20), i.e. +-10.4 km at 1 cm, +-210 km at 20 cm.
#include <cmath>
#include <cstdint>
#include <optional>

#include <Eigen/Core>

namespace mrvs::voxel {

using VoxelIndex = Eigen::Matrix<std::int32_t, 3, 1>;

inline constexpr int kBitsPerAxis = 21;
inline constexpr std::int32_t kMinIndex = -(std::int32_t{1} << (kBitsPerAxis - 1));
inline constexpr std::int32_t kMaxIndex = (std::int32_t{1} << (kBitsPerAxis - 1)) - 1;

/// True when every component of `index` can be packed.
inline bool packable(const VoxelIndex& index) {
  return index.minCoeff() >= kMinIndex && index.maxCoeff() <= kMaxIndex;
}

/// Packs a voxel index (each component in [kMinIndex, kMaxIndex]) into a 64-bit key.
/// Distinct indices give distinct keys; the top bit is always 0.
inline std::uint64_t pack(const VoxelIndex& index) {
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kBitsPerAxis) - 1;
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(index.x())) & kMask) |
         ((static_cast<std::uint64_t>(static_cast<std::uint32_t>(index.y())) & kMask) << kBitsPerAxis) |
         ((static_cast<std::uint64_t>(static_cast<std::uint32_t>(index.z())) & kMask) << (2 * kBitsPerAxis));
}

/// Inverse of pack().
inline VoxelIndex unpack(std::uint64_t key) {
  constexpr std::uint64_t kMask = (std::uint64_t{1} << kBitsPerAxis) - 1;
  auto axis = [](std::uint64_t bits) {
    // Sign-extend 21 bits.
    const std::int64_t v = static_cast<std::int64_t>(bits << (64 - kBitsPerAxis)) >> (64 - kBitsPerAxis);
    return static_cast<std::int32_t>(v);
  };
  return VoxelIndex(axis(key & kMask), axis((key >> kBitsPerAxis) & kMask),
                    axis((key >> (2 * kBitsPerAxis)) & kMask));
}

/// Voxel index of point p in a grid of size `resolution` (floor). nullopt when p is not
/// finite or the index cannot be packed.
template <typename Scalar>
std::optional<VoxelIndex> index_of(const Eigen::Matrix<Scalar, 3, 1>& p, Scalar resolution) {
  VoxelIndex index;
  for (int k = 0; k < 3; ++k) {
    const Scalar cell = std::floor(p[k] / resolution);
    if (!std::isfinite(cell) || cell < Scalar(kMinIndex) || cell > Scalar(kMaxIndex)) return std::nullopt;
    index[k] = static_cast<std::int32_t>(cell);
  }
  return index;
}

}  // namespace mrvs::voxel
