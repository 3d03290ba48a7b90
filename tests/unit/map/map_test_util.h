#pragma once
// Writers of PLY / PCD test files (byte by byte, independent of PCL) and random clouds for
// the map tests.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/map/point_cloud_io.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::map::test {

/// One PLY vertex property / PCD field.
struct Field {
  std::string type;  ///< PLY: float, double, uchar, ushort, int, ...; PCD: F4, F8, U1, U2, U4, I4
  std::string name;
};

/// Writes a PLY with one vertex element. `format`: ascii, binary_little_endian or
/// binary_big_endian. `rows[i][k]` is the value of field k of vertex i (converted to the
/// field's type). `extra_header` lines (e.g. another element) go before end_header.
void write_ply(const std::filesystem::path& path, const std::string& format, const std::vector<Field>& fields,
               const std::vector<std::vector<double>>& rows, const std::string& extra_header = "");

/// Writes a PCD v0.7 file. `data`: ascii, binary or binary_compressed (LZF literal runs).
void write_pcd(const std::filesystem::path& path, const std::string& data, const std::vector<Field>& fields,
               const std::vector<std::vector<double>>& rows);

/// x, y, z, intensity rows of a cloud.
std::vector<std::vector<double>> xyzi_rows(const RawCloud& cloud);

/// `n` points uniformly in [0, extent)^3 + offset, intensities uniform in [0, 1).
RawCloud random_cloud(std::size_t n, std::uint64_t seed, double extent, const Eigen::Vector3d& offset);

/// `n` points on the wavy surface z = a sin(x / l) cos(y / l) in [0, extent)^2 with
/// `noise` m of normal noise and random intensities (well-defined normals everywhere).
RawCloud wavy_cloud(std::size_t n, std::uint64_t seed, double extent, double noise);

std::string read_bytes(const std::filesystem::path& path);
void write_bytes(const std::filesystem::path& path, const std::string& bytes);

/// Bit-exact comparison of two map points.
bool same_bits(const MapPoint& a, const MapPoint& b);

}  // namespace mrvs::map::test
