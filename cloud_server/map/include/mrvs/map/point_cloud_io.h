#pragma once
// Reading the raw LiDAR cloud the offline map is built from (PLY or PCD, with intensity).
//
// Positions are kept in double: a survey cloud in UTM (easting ~3e5 m, northing ~4e6 m)
// loses its millimetres in float32, so the x/y/z fields are converted from FLOAT32 or
// FLOAT64 straight into double (PCL's PCLPointCloud2 is used only as a byte container).
//
// Intensity is taken from the first field present among (in this order) intensity,
// scalar_intensity, scalar_Intensity, reflectance, i; failing that from red/green/blue
// (PLY, or a packed PCD rgb/rgba field) as gray = (r + g + b) / 3 in [0, 255]. A cloud
// with none of these is an error naming the file and the fields it has.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"

namespace mrvs::map {

/// A raw point cloud: finite points only.
struct RawCloud {
  std::vector<Vec3d> positions;       ///< metres, in the cloud's own frame (e.g. UTM)
  std::vector<float> intensities;     ///< one per position, in the file's units
  std::string source;                 ///< file it was read from ("" when built in memory)
  std::string intensity_field;        ///< field the intensity came from ("intensity", "rgb (gray)", ...)
  std::vector<std::string> warnings;  ///< e.g. how many non-finite points were dropped

  std::size_t size() const { return positions.size(); }
};

/// Reads a .ply (ascii, binary_little_endian, binary_big_endian; float or double x, y, z)
/// or a .pcd (ascii, binary, binary_compressed) file. Points with a non-finite coordinate
/// or intensity are dropped and counted in RawCloud::warnings. Errors (each naming the
/// file): missing or unreadable file, unknown extension, malformed or truncated file,
/// missing x/y/z or intensity-like fields, no finite point.
StatusOr<RawCloud> read_point_cloud(const std::filesystem::path& path);

/// The intensity-like field names read_point_cloud accepts, in priority order.
const std::vector<std::string>& intensity_field_names();

}  // namespace mrvs::map
