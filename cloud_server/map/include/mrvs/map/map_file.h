#pragma once
// The .mrvm map file (version 1): a VoxelMap, little-endian, with a checksum.
//
//   offset  size      field
//   0       8         magic "MRVMAP\r\n" (4d 52 56 4d 41 50 0d 0a; CR LF catch text-mode copies)
//   8       4   u32   format version (1)
//   12      4   u32   flags (0; reserved)
//   16      4   u32   level count L (1 .. kMaxLevels)
//   20      4   u32   description length D, bytes (<= kMaxDescriptionBytes)
//   24      24  3xf64 origin x, y, z, metres (map frame)
//   48      8   u64   raw point count (points of the cloud the map was built from)
//   56      16L       per level: f64 resolution (metres), u64 point count N_l
//   ..      D         description text (UTF-8, no terminator)
//   ..      20 N_l    per level, per point: f32 x, y, z (metres, relative to origin),
//                     f32 intensity, f32 saliency
//   end-8   8   u64   checksum: FNV-1a 64 (fnv1a_64 below) of every byte before it
//
// So the file length is exactly 56 + 16 L + D + 20 sum(N_l) + 8.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::map {

inline constexpr char kMapFileMagic[8] = {'M', 'R', 'V', 'M', 'A', 'P', '\r', '\n'};
inline constexpr std::uint32_t kMapFileVersion = 1;
inline constexpr std::uint32_t kMaxLevels = 64;
inline constexpr std::uint32_t kMaxDescriptionBytes = 1 << 20;
/// At most this many points per level (QueryEngine's point indices are 32-bit).
inline constexpr std::uint64_t kMaxPointsPerLevel = 0xffffffffull;
inline constexpr std::size_t kMapFileFixedHeaderBytes = 56;
inline constexpr std::size_t kMapFileLevelEntryBytes = 16;
inline constexpr std::size_t kMapFilePointBytes = 20;
inline constexpr std::size_t kMapFileChecksumBytes = 8;

/// FNV-1a, 64 bit: h = 0xcbf29ce484222325; for each byte b: h = (h ^ b) * 0x100000001b3.
/// Pass the previous result as `hash` to continue over more bytes.
std::uint64_t fnv1a_64(const void* data, std::size_t size, std::uint64_t hash = 0xcbf29ce484222325ull);

/// What the loader checks beyond the format.
struct MapCheckOptions {
  bool check_one_point_per_voxel = true;  ///< every level: distinct voxels (O(n log n))
};

/// Checks that `map` is a valid map: 1 .. kMaxLevels levels with finite, positive, strictly
/// increasing resolutions, finite origin, finite positions and intensities, finite
/// non-negative saliencies, at most kMaxPointsPerLevel points per level and raw_point_count
/// points, description <= kMaxDescriptionBytes, optionally one point per voxel (voxel_of).
/// `name` (a file name) prefixes every message.
Status validate_voxel_map(const VoxelMap& map, const std::string& name, const MapCheckOptions& options = {});

/// Exact size in bytes of the .mrvm encoding of `map`.
std::uint64_t map_file_size(const VoxelMap& map);

/// The .mrvm bytes of `map` (validated first; `name` is used in error messages).
StatusOr<std::string> serialize_voxel_map(const VoxelMap& map, const std::string& name = "<map>");

/// Parses .mrvm bytes. Every check of load_voxel_map; `name` (a file name) prefixes messages.
StatusOr<VoxelMap> parse_voxel_map(std::string_view bytes, const std::string& name,
                                   const MapCheckOptions& options = {});

/// Validates and writes `map` to `path` atomically (write_file_atomically).
Status save_voxel_map(const std::filesystem::path& path, const VoxelMap& map);

/// Reads and validates a .mrvm file. Errors name the file and say what is wrong: not a .mrvm
/// file (magic), unsupported version (the supported ones named), truncated (how many bytes
/// are missing) or trailing bytes, absurd counts, checksum mismatch, non-finite values,
/// resolutions not positive and increasing, two points in one voxel.
StatusOr<VoxelMap> load_voxel_map(const std::filesystem::path& path, const MapCheckOptions& options = {});

}  // namespace mrvs::map
