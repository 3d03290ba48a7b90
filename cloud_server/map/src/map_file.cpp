// The .mrvm file: encoding, decoding and validation (layout in map_file.h).
#include "mrvs/map/map_file.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <system_error>

#include <fmt/format.h>

#include "mrvs/core/file.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::map {
namespace {

// ---------------------------------------------------------------- little-endian encoding

void put_u32(std::string& out, std::uint32_t v) {
  for (int b = 0; b < 4; ++b) out.push_back(static_cast<char>((v >> (8 * b)) & 0xffu));
}
void put_u64(std::string& out, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) out.push_back(static_cast<char>((v >> (8 * b)) & 0xffu));
}
void put_f32(std::string& out, float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  put_u32(out, bits);
}
void put_f64(std::string& out, double v) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &v, sizeof(bits));
  put_u64(out, bits);
}

/// Sequential little-endian reads; the caller has checked the length beforehand.
class Reader {
 public:
  Reader(std::string_view bytes, std::size_t offset) : bytes_(bytes), pos_(offset) {}
  std::uint64_t uint(int size) {
    std::uint64_t v = 0;
    for (int b = 0; b < size; ++b) {
      v |= static_cast<std::uint64_t>(static_cast<unsigned char>(bytes_[pos_ + static_cast<std::size_t>(b)]))
           << (8 * b);
    }
    pos_ += static_cast<std::size_t>(size);
    return v;
  }
  std::uint32_t u32() { return static_cast<std::uint32_t>(uint(4)); }
  std::uint64_t u64() { return uint(8); }
  float f32() {
    const std::uint32_t bits = u32();
    float v = 0.0f;
    std::memcpy(&v, &bits, sizeof(v));
    return v;
  }
  double f64() {
    const std::uint64_t bits = u64();
    double v = 0.0;
    std::memcpy(&v, &bits, sizeof(v));
    return v;
  }
  std::string_view take(std::size_t n) {
    const std::string_view s = bytes_.substr(pos_, n);
    pos_ += n;
    return s;
  }
  std::size_t position() const { return pos_; }

 private:
  std::string_view bytes_;
  std::size_t pos_;
};

Status corrupt(const std::string& name, const std::string& what) {
  return absl::DataLossError(fmt::format("'{}': {}", name, what));
}

Status truncated(const std::string& name, std::uint64_t needed, std::uint64_t size, const std::string& part) {
  return absl::DataLossError(fmt::format(
      "'{}' is truncated: {} needs {} bytes but the file has {} ({} bytes missing); re-copy or rebuild "
      "the map",
      name, part, needed, size, needed - size));
}

// ---------------------------------------------------------------- validation

Status check_values(const MapLevel& level, std::size_t l, const std::string& name) {
  for (std::size_t i = 0; i < level.points.size(); ++i) {
    const MapPoint& p = level.points[i];
    const char* what = !p.position.allFinite()       ? "position"
                       : !std::isfinite(p.intensity) ? "intensity"
                       : !std::isfinite(p.saliency)  ? "saliency"
                       : p.saliency < 0.0f           ? "saliency (negative)"
                                                     : nullptr;
    if (what != nullptr) {
      return corrupt(name,
                     fmt::format("level {} ({} m) point {}: invalid {} (x {}, y {}, z {}, intensity {}, "
                                 "saliency {})",
                                 l, level.resolution, i, what, p.position.x(), p.position.y(), p.position.z(),
                                 p.intensity, p.saliency));
    }
  }
  return absl::OkStatus();
}

Status check_one_point_per_voxel(const MapLevel& level, std::size_t l, const std::string& name) {
  std::vector<std::pair<std::uint64_t, std::size_t>> keys(level.points.size());
  for (std::size_t i = 0; i < level.points.size(); ++i) {
    const auto index = voxel_of(level.points[i].position, level.resolution);
    if (!index) {
      return corrupt(name, fmt::format("level {} ({} m) point {} lies outside the packable voxel range", l,
                                       level.resolution, i));
    }
    keys[i] = {voxel::pack(*index), i};
  }
  std::sort(keys.begin(), keys.end());
  for (std::size_t i = 1; i < keys.size(); ++i) {
    if (keys[i].first == keys[i - 1].first) {
      const voxel::VoxelIndex v = voxel::unpack(keys[i].first);
      return corrupt(name,
                     fmt::format("level {} ({} m) has two points in voxel ({}, {}, {}): points {} and {}", l,
                                 level.resolution, v.x(), v.y(), v.z(), keys[i - 1].second, keys[i].second));
    }
  }
  return absl::OkStatus();
}

Status check_structure(const VoxelMap& map, const std::string& name) {
  if (map.levels.empty() || map.levels.size() > kMaxLevels) {
    return corrupt(name, fmt::format("{} levels; a map has 1 to {}", map.levels.size(), kMaxLevels));
  }
  if (!map.origin.allFinite()) {
    return corrupt(name, fmt::format("origin ({}, {}, {}) is not finite", map.origin.x(), map.origin.y(),
                                     map.origin.z()));
  }
  if (map.description.size() > kMaxDescriptionBytes) {
    return corrupt(name, fmt::format("description of {} bytes exceeds {}", map.description.size(),
                                     kMaxDescriptionBytes));
  }
  for (std::size_t l = 0; l < map.levels.size(); ++l) {
    const MapLevel& level = map.levels[l];
    if (!std::isfinite(level.resolution) || !(level.resolution > 0.0)) {
      return corrupt(name,
                     fmt::format("level {} resolution {} is not a positive number", l, level.resolution));
    }
    if (l > 0 && !(level.resolution > map.levels[l - 1].resolution)) {
      return corrupt(name, fmt::format("resolutions must increase strictly (finest first): level {} has {} m "
                                       "after {} m",
                                       l, level.resolution, map.levels[l - 1].resolution));
    }
    if (level.points.size() > kMaxPointsPerLevel || level.points.size() > map.raw_point_count) {
      return corrupt(name, fmt::format("level {} has {} points, more than the raw cloud ({}) or the limit {}",
                                       l, level.points.size(), map.raw_point_count, kMaxPointsPerLevel));
    }
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------- decoding

struct FileHeader {
  std::uint32_t level_count = 0;
  std::uint32_t description_bytes = 0;
  Vec3d origin = Vec3d::Zero();
  std::uint64_t raw_point_count = 0;
};

/// Magic, version, flags and the fixed part of the header.
StatusOr<FileHeader> parse_fixed_header(std::string_view bytes, const std::string& name) {
  const std::size_t magic_n = std::min<std::size_t>(bytes.size(), sizeof(kMapFileMagic));
  if (bytes.empty() || std::memcmp(bytes.data(), kMapFileMagic, magic_n) != 0) {
    return absl::InvalidArgumentError(fmt::format(
        "'{}' is not a .mrvm map file (its first bytes are not the magic \"MRVMAP\\r\\n\"); build "
        "one with map_builder",
        name));
  }
  if (bytes.size() < 12) return truncated(name, 12, bytes.size(), "the magic and version");
  Reader r(bytes, sizeof(kMapFileMagic));
  const std::uint32_t version = r.u32();
  if (version != kMapFileVersion) {
    return absl::FailedPreconditionError(fmt::format(
        "'{}': unsupported .mrvm format version {}; this build reads version {} only (rebuild the map "
        "with this map_builder)",
        name, version, kMapFileVersion));
  }
  if (bytes.size() < kMapFileFixedHeaderBytes) {
    return truncated(name, kMapFileFixedHeaderBytes, bytes.size(), "the fixed header");
  }
  const std::uint32_t flags = r.u32();
  if (flags != 0)
    return corrupt(name, fmt::format("unknown header flags 0x{:x} (version 1 has none)", flags));
  FileHeader h;
  h.level_count = r.u32();
  h.description_bytes = r.u32();
  for (int k = 0; k < 3; ++k) h.origin[k] = r.f64();
  h.raw_point_count = r.u64();
  if (h.level_count == 0 || h.level_count > kMaxLevels) {
    return corrupt(name, fmt::format("level count {} is out of range [1, {}]; the header is corrupt",
                                     h.level_count, kMaxLevels));
  }
  if (h.description_bytes > kMaxDescriptionBytes) {
    return corrupt(name, fmt::format("description length {} exceeds {} bytes; the header is corrupt",
                                     h.description_bytes, kMaxDescriptionBytes));
  }
  return h;
}

/// Level table; checks the total length against the file before anything is allocated.
Status parse_level_table(std::string_view bytes, const std::string& name, const FileHeader& h, VoxelMap& map,
                         std::vector<std::uint64_t>& counts) {
  const std::uint64_t table_end =
      kMapFileFixedHeaderBytes + std::uint64_t{kMapFileLevelEntryBytes} * h.level_count;
  if (bytes.size() < table_end) return truncated(name, table_end, bytes.size(), "the level table");
  Reader r(bytes, kMapFileFixedHeaderBytes);
  std::uint64_t total_points = 0;
  for (std::uint32_t l = 0; l < h.level_count; ++l) {
    MapLevel level;
    level.resolution = r.f64();
    counts.push_back(r.u64());
    if (counts.back() > kMaxPointsPerLevel) {
      return corrupt(name, fmt::format("level {} declares {} points (limit {}); the header is corrupt", l,
                                       counts.back(), kMaxPointsPerLevel));
    }
    total_points += counts.back();
    map.levels.push_back(std::move(level));
  }
  const std::uint64_t expected =
      table_end + h.description_bytes + total_points * kMapFilePointBytes + kMapFileChecksumBytes;
  if (bytes.size() < expected) {
    return truncated(name, expected, bytes.size(),
                     fmt::format("a map of {} points in {} levels", total_points, h.level_count));
  }
  if (bytes.size() > expected) {
    return corrupt(name,
                   fmt::format("{} unexpected bytes after the checksum (the header describes {} bytes, the "
                               "file has {}); the file is corrupt or has data appended",
                               bytes.size() - expected, expected, bytes.size()));
  }
  return absl::OkStatus();
}

}  // namespace

std::uint64_t fnv1a_64(const void* data, std::size_t size, std::uint64_t hash) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= p[i];
    hash *= 0x100000001b3ull;
  }
  return hash;
}

Status validate_voxel_map(const VoxelMap& map, const std::string& name, const MapCheckOptions& options) {
  MRVS_RETURN_IF_ERROR(check_structure(map, name));
  for (std::size_t l = 0; l < map.levels.size(); ++l) {
    MRVS_RETURN_IF_ERROR(check_values(map.levels[l], l, name));
    if (options.check_one_point_per_voxel)
      MRVS_RETURN_IF_ERROR(check_one_point_per_voxel(map.levels[l], l, name));
  }
  return absl::OkStatus();
}

std::uint64_t map_file_size(const VoxelMap& map) {
  return kMapFileFixedHeaderBytes + kMapFileLevelEntryBytes * map.levels.size() + map.description.size() +
         kMapFilePointBytes * map.point_count() + kMapFileChecksumBytes;
}

StatusOr<std::string> serialize_voxel_map(const VoxelMap& map, const std::string& name) {
  MRVS_RETURN_IF_ERROR(validate_voxel_map(map, name));
  std::string out;
  out.reserve(static_cast<std::size_t>(map_file_size(map)));
  out.append(kMapFileMagic, sizeof(kMapFileMagic));
  put_u32(out, kMapFileVersion);
  put_u32(out, 0);
  put_u32(out, static_cast<std::uint32_t>(map.levels.size()));
  put_u32(out, static_cast<std::uint32_t>(map.description.size()));
  for (int k = 0; k < 3; ++k) put_f64(out, map.origin[k]);
  put_u64(out, map.raw_point_count);
  for (const MapLevel& level : map.levels) {
    put_f64(out, level.resolution);
    put_u64(out, level.points.size());
  }
  out += map.description;
  for (const MapLevel& level : map.levels) {
    for (const MapPoint& p : level.points) {
      for (int k = 0; k < 3; ++k) put_f32(out, p.position[k]);
      put_f32(out, p.intensity);
      put_f32(out, p.saliency);
    }
  }
  put_u64(out, fnv1a_64(out.data(), out.size()));
  return out;
}

StatusOr<VoxelMap> parse_voxel_map(std::string_view bytes, const std::string& name,
                                   const MapCheckOptions& options) {
  MRVS_ASSIGN_OR_RETURN(const FileHeader h, parse_fixed_header(bytes, name));
  VoxelMap map;
  std::vector<std::uint64_t> counts;
  MRVS_RETURN_IF_ERROR(parse_level_table(bytes, name, h, map, counts));
  const std::size_t body = bytes.size() - kMapFileChecksumBytes;
  const std::uint64_t stored = Reader(bytes, body).u64();
  const std::uint64_t computed = fnv1a_64(bytes.data(), body);
  if (stored != computed) {
    return corrupt(name, fmt::format("checksum mismatch (stored 0x{:016x}, computed 0x{:016x}): the file is "
                                     "corrupt; re-copy or rebuild the map",
                                     stored, computed));
  }
  map.origin = h.origin;
  map.raw_point_count = h.raw_point_count;
  Reader r(bytes, kMapFileFixedHeaderBytes + kMapFileLevelEntryBytes * h.level_count);
  map.description = std::string(r.take(h.description_bytes));
  for (std::size_t l = 0; l < map.levels.size(); ++l) {
    std::vector<MapPoint>& points = map.levels[l].points;
    points.resize(static_cast<std::size_t>(counts[l]));
    for (MapPoint& p : points) {
      for (int k = 0; k < 3; ++k) p.position[k] = r.f32();
      p.intensity = r.f32();
      p.saliency = r.f32();
    }
  }
  MRVS_RETURN_IF_ERROR(validate_voxel_map(map, name, options));
  return map;
}

Status save_voxel_map(const std::filesystem::path& path, const VoxelMap& map) {
  MRVS_ASSIGN_OR_RETURN(const std::string bytes, serialize_voxel_map(map, path.string()));
  return write_file_atomically(path, bytes);
}

StatusOr<VoxelMap> load_voxel_map(const std::filesystem::path& path, const MapCheckOptions& options) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    return absl::NotFoundError(fmt::format(
        "map file '{}' does not exist or is not a file; build it with map_builder", path.string()));
  }
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  std::ifstream in(path, std::ios::binary);
  if (ec || !in)
    return absl::UnavailableError(fmt::format("cannot open map file '{}' for reading", path.string()));
  std::string bytes(static_cast<std::size_t>(size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) {
    return absl::DataLossError(
        fmt::format("cannot read map file '{}': {} of {} bytes read", path.string(), in.gcount(), size));
  }
  return parse_voxel_map(bytes, path.string(), options);
}

}  // namespace mrvs::map
