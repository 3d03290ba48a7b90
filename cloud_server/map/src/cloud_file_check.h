#pragma once
// Checks a PLY or PCD file's header against the file's length BEFORE PCL reads it, so that
// a truncated file or a corrupt point count is an error that says what is missing instead
// of a PCL crash, a huge allocation or a silently shortened cloud (internal).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/status.h"

namespace mrvs::map::detail {

/// What the header declares.
struct CloudFileInfo {
  std::uint64_t points = 0;           ///< vertices (PLY) / POINTS (PCD)
  std::string encoding;               ///< "ascii", "binary_little_endian", "binary", ...
  std::vector<std::string> fields;    ///< vertex property / PCD field names, in file order
  std::vector<std::string> warnings;  ///< e.g. trailing bytes after the data
};

/// Parses the PLY header of `path` (file length `file_size` bytes) and checks that the data
/// the header declares fits in the file: binary -> byte count, ascii -> number of values.
/// Errors name the file: not a PLY, malformed header, no vertex element, zero vertices,
/// truncated data (with the number of bytes or values missing).
StatusOr<CloudFileInfo> check_ply_file(const std::filesystem::path& path, std::uint64_t file_size);

/// Same for a PCD file (DATA ascii, binary or binary_compressed).
StatusOr<CloudFileInfo> check_pcd_file(const std::filesystem::path& path, std::uint64_t file_size);

}  // namespace mrvs::map::detail
