#pragma once
// The ray-traversal index of one map level (internal to mrvs::map_query).
//
// Voxels are grouped in bricks of 8 x 8 x 8. Every occupied brick has a 512-bit occupancy
// mask (bit = x | y << 3 | z << 6 of the voxel inside the brick) and the index of its first
// point in `points` (points sorted by brick, then by bit), so the point of an occupied voxel
// is base + the number of set bits below its own. Bricks are found through a
// dense bitmap over the level's bounding box (bricks numbered in box order, so a brick's
// ordinal is the rank of its bit: a 64-bit word and a running count per 64 bricks; an indoor
// room at 1 cm: ~200 KB, stays in cache) or, when the box is too large for that, through an
// open-addressing hash table (64-bit packed brick key, splitmix64, linear probing, load <= 0.5).
//
// Layout for ray traversal: an empty brick costs one bitmap word (usually in L1/L2), an
// occupied one that word plus its 64-byte mask (one cache line). Measured on the 1.4 M point
// indoor map (bench_map): ~0.7 us per query with the bitmap, ~1.0 us with the hash table.
//
// Coordinates: map-local metres; voxel (i, j, k) of resolution r is [i r, (i + 1) r) x ...
// (floor, mrvs/voxel/voxel_key.h); brick (I, J, K) holds voxels 8 I .. 8 I + 7 on each axis.
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/hash.h"
#include "mrvs/core/status.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::map::detail {

inline constexpr int kBrickShift = 3;              ///< log2 of the brick edge in voxels
inline constexpr std::int32_t kBrickEdge = 8;      ///< voxels per brick edge
inline constexpr std::uint64_t kEmptyKey = ~0ULL;  ///< free hash slot (packed keys have bit 63 clear)
inline constexpr std::uint32_t kNoBrick = ~0U;     ///< "no brick" ordinal

/// Occupancy of one brick: word z, bit x | y << 3.
struct alignas(64) BrickMask {
  std::array<std::uint64_t, 8> words{};

  bool test(int bit) const { return ((words[bit >> 6] >> (bit & 63)) & 1U) != 0; }
  /// Set bits below `bit` (the rank of voxel `bit` among the brick's occupied voxels).
  std::uint32_t rank(int bit) const {
    std::uint32_t count = 0;
    for (int w = 0; w < (bit >> 6); ++w) count += static_cast<std::uint32_t>(__builtin_popcountll(words[w]));
    const std::uint64_t below = (std::uint64_t{1} << (bit & 63)) - 1;
    return count + static_cast<std::uint32_t>(__builtin_popcountll(words[bit >> 6] & below));
  }
};

/// One hash slot (16 bytes: four per cache line).
struct BrickSlot {
  std::uint64_t key = kEmptyKey;   ///< mrvs::voxel::pack of the brick coordinates
  std::uint32_t brick = kNoBrick;  ///< ordinal into LevelIndex::masks / bases
  std::uint32_t unused = 0;
};

/// Brick coordinate of a voxel index (floor division by 8, also for negative indices).
inline std::int32_t brick_of(std::int32_t voxel) { return voxel >> kBrickShift; }
/// Bit of a voxel inside its brick.
inline int bit_of(std::int32_t x, std::int32_t y, std::int32_t z) {
  return (x & 7) | ((y & 7) << 3) | ((z & 7) << 6);
}

class LevelIndex {
 public:
  /// Builds the index of `level` (number `level_number`, for messages). Errors: a resolution
  /// that is not finite and positive, a non-finite point, a voxel index outside the packable
  /// range, two points in one voxel, more than 2^32 - 1 points.
  static StatusOr<LevelIndex> build(const MapLevel& level, int level_number);

  double resolution() const { return resolution_; }
  std::size_t point_count() const { return order_.size(); }
  std::size_t brick_count() const { return masks_.size(); }
  std::size_t memory_bytes() const;
  bool has_dense_bitmap() const { return !dense_.empty(); }

  /// Traversal box: the occupied bricks plus one empty brick on every side, metres
  /// (empty box when the level has no points).
  const Eigen::AlignedBox3d& box() const { return box_; }

  /// Ordinal of brick (bx, by, bz), or kNoBrick when it holds no point.
  std::uint32_t find_brick(std::int32_t bx, std::int32_t by, std::int32_t bz) const {
    if (bx < brick_lo_[0] || by < brick_lo_[1] || bz < brick_lo_[2] || bx > brick_hi_[0] ||
        by > brick_hi_[1] || bz > brick_hi_[2]) {
      return kNoBrick;
    }
    if (dense_.empty()) return probe(pack_brick(bx, by, bz));
    const std::uint64_t cell = cell_of(bx, by, bz);
    const DenseWord& word = dense_[cell >> 6];
    const std::uint64_t bit = std::uint64_t{1} << (cell & 63);
    if ((word.bits & bit) == 0) return kNoBrick;
    return word.rank + static_cast<std::uint32_t>(__builtin_popcountll(word.bits & (bit - 1)));
  }

  const BrickMask& mask(std::uint32_t brick) const { return masks_[brick]; }
  std::uint32_t base(std::uint32_t brick) const { return bases_[brick]; }

  /// Index into the sorted point arrays of voxel (x, y, z), or kNoBrick when it is empty.
  std::uint32_t find_voxel(std::int32_t x, std::int32_t y, std::int32_t z) const {
    const std::uint32_t brick = find_brick(brick_of(x), brick_of(y), brick_of(z));
    if (brick == kNoBrick) return kNoBrick;
    const int bit = bit_of(x, y, z);
    const BrickMask& m = masks_[brick];
    return m.test(bit) ? bases_[brick] + m.rank(bit) : kNoBrick;
  }

  /// Position (map-local, m) of sorted point `sorted`.
  const Eigen::Vector3f& position(std::uint32_t sorted) const { return positions_[sorted]; }
  /// Index into MapLevel::points of sorted point `sorted`.
  std::uint32_t original_index(std::uint32_t sorted) const { return order_[sorted]; }

  static std::uint64_t pack_brick(std::int32_t bx, std::int32_t by, std::int32_t bz);

 private:
  std::uint32_t probe(std::uint64_t key) const {
    std::uint64_t i = mix64(key) & slot_mask_;
    for (;;) {
      const BrickSlot& s = slots_[i];
      if (s.key == key) return s.brick;
      if (s.key == kEmptyKey) return kNoBrick;
      i = (i + 1) & slot_mask_;
    }
  }

  /// Linear index of a brick inside the traversal box (x fastest).
  std::uint64_t cell_of(std::int32_t bx, std::int32_t by, std::int32_t bz) const {
    return (static_cast<std::uint64_t>(bz - brick_lo_[2]) * dims_[1] +
            static_cast<std::uint64_t>(by - brick_lo_[1])) *
               dims_[0] +
           static_cast<std::uint64_t>(bx - brick_lo_[0]);
  }

  /// One point: its brick's box cell, its bit in the brick, its index in MapLevel::points.
  struct Entry {
    std::uint64_t cell;
    std::uint32_t bit;
    std::uint32_t point;
  };
  Status collect(const MapLevel& level, int level_number, std::vector<Entry>& entries);
  Status fill(const MapLevel& level, int level_number, const std::vector<Entry>& entries);
  void build_lookup();

  /// 64 bricks of the dense bitmap and the number of occupied bricks before them.
  struct DenseWord {
    std::uint64_t bits = 0;
    std::uint32_t rank = 0;
    std::uint32_t unused = 0;
  };

  double resolution_ = 0.0;
  std::vector<BrickSlot> slots_;
  std::uint64_t slot_mask_ = 0;
  std::vector<BrickMask> masks_;
  std::vector<std::uint32_t> bases_;
  std::vector<std::uint32_t> order_;
  std::vector<Eigen::Vector3f> positions_;
  Eigen::Vector3i brick_lo_{1, 1, 1};  ///< traversal box in bricks (inclusive), empty by default
  Eigen::Vector3i brick_hi_{0, 0, 0};
  std::vector<Eigen::Vector3i> brick_coords_;  ///< per ordinal (build time only)
  std::array<std::uint64_t, 3> dims_{};        ///< box size in bricks
  std::vector<DenseWord> dense_;
  Eigen::AlignedBox3d box_;
};

}  // namespace mrvs::map::detail
