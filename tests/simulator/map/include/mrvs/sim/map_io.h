#pragma once
// Files of the prior map: pointcloud0/data.ply (simulator.md section 1.7) and
// sim0/T_map_world.yaml (section 1.8).
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/sim/map_options.h"
#include "mrvs/sim/prior_map.h"

namespace mrvs::sim {

enum class PlyFormat {
  kBinaryLittleEndian,  ///< 16 bytes per point (default)
  kAscii,               ///< "x y z intensity" per line, shortest round-trip decimal form
};

/// The PLY format MapOptions::ply_ascii asks for.
inline PlyFormat ply_format(const MapOptions& options) {
  return options.ply_ascii ? PlyFormat::kAscii : PlyFormat::kBinaryLittleEndian;
}

/// Writes `points` as a PLY with float x, y, z, intensity (MapPoint::face is not written).
/// `comment` becomes one "comment ..." header line per text line, e.g. "synthetic survey
/// scan; generator <ver>; scene <name>; seed <n>; frame world(R)". The file is written to
/// "<path>.tmp" and renamed, so readers never see a partial file. Errors name the path.
Status write_ply(const std::filesystem::path& path, const std::vector<MapPoint>& points,
                 const std::string& comment, PlyFormat format = PlyFormat::kBinaryLittleEndian);

/// Reads a PLY as written by write_ply: ascii or binary_little_endian, one vertex element
/// whose float properties include x, y, z and intensity (other float properties are
/// skipped). MapPoint::face is -1. Errors (naming the path) on a malformed header, other
/// property types or elements, non-numeric or missing values, truncated or oversized data.
StatusOr<std::vector<MapPoint>> read_ply_xyzi(const std::filesystem::path& path);

/// Writes sim0/T_map_world.yaml: the 4x4 matrix of T_map_world (p_map = T_map_world * p_world)
/// in the EuRoC T_BS layout (cols, rows, data) plus its rotation angle (deg) and translation
/// norm (m). Written via a temporary file; errors name the path.
Status write_transform_yaml(const std::filesystem::path& path, const SE3d& T_map_world);

}  // namespace mrvs::sim
