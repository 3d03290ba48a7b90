// PLY / PCD input through PCL's PCLPointCloud2 (fields converted here, positions in double).
#include "mrvs/map/point_cloud_io.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstring>
#include <exception>
#include <optional>
#include <system_error>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <pcl/PCLPointCloud2.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <Eigen/Geometry>

#include "cloud_file_check.h"

namespace mrvs::map {
namespace {

namespace fs = std::filesystem;

/// Reads one value of a numeric PCL field as double (nullopt for an unknown datatype).
std::optional<double> field_value(const std::uint8_t* p, std::uint8_t datatype) {
  auto get = [p](auto v) {
    std::memcpy(&v, p, sizeof(v));
    return static_cast<double>(v);
  };
  switch (datatype) {
    case pcl::PCLPointField::INT8:
      return get(std::int8_t{});
    case pcl::PCLPointField::UINT8:
      return get(std::uint8_t{});
    case pcl::PCLPointField::INT16:
      return get(std::int16_t{});
    case pcl::PCLPointField::UINT16:
      return get(std::uint16_t{});
    case pcl::PCLPointField::INT32:
      return get(std::int32_t{});
    case pcl::PCLPointField::UINT32:
      return get(std::uint32_t{});
    case pcl::PCLPointField::FLOAT32:
      return get(float{});
    case pcl::PCLPointField::FLOAT64:
      return get(double{});
    default:
      return std::nullopt;
  }
}

const pcl::PCLPointField* find_field(const pcl::PCLPointCloud2& cloud, const std::string& name) {
  for (const pcl::PCLPointField& f : cloud.fields) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

std::string field_list(const pcl::PCLPointCloud2& cloud) {
  std::string out;
  for (const pcl::PCLPointField& f : cloud.fields) out += (out.empty() ? "" : ", ") + f.name;
  return out.empty() ? "none" : out;
}

/// How the intensity of a point is obtained.
struct IntensitySource {
  std::string name;                                                ///< for RawCloud::intensity_field
  const pcl::PCLPointField* scalar = nullptr;                      ///< an intensity-like field
  const pcl::PCLPointField* packed_rgb = nullptr;                  ///< rgb / rgba packed in 32 bits
  const pcl::PCLPointField* rgb[3] = {nullptr, nullptr, nullptr};  ///< separate red/green/blue
};

StatusOr<IntensitySource> intensity_source(const pcl::PCLPointCloud2& cloud, const fs::path& path) {
  IntensitySource src;
  for (const std::string& name : intensity_field_names()) {
    if ((src.scalar = find_field(cloud, name)) != nullptr) {
      src.name = name;
      return src;
    }
  }
  for (const char* name : {"rgb", "rgba"}) {
    const pcl::PCLPointField* f = find_field(cloud, name);
    if (f != nullptr &&
        (f->datatype == pcl::PCLPointField::FLOAT32 || f->datatype == pcl::PCLPointField::UINT32 ||
         f->datatype == pcl::PCLPointField::INT32)) {
      src.packed_rgb = f;
      src.name = std::string(name) + " (gray = (r + g + b) / 3)";
      return src;
    }
  }
  src.rgb[0] = find_field(cloud, "red");
  src.rgb[1] = find_field(cloud, "green");
  src.rgb[2] = find_field(cloud, "blue");
  if (src.rgb[0] != nullptr && src.rgb[1] != nullptr && src.rgb[2] != nullptr) {
    src.name = "red/green/blue (gray = (r + g + b) / 3)";
    return src;
  }
  return absl::InvalidArgumentError(fmt::format(
      "'{}' has no intensity: expected a field named {} or red/green/blue colours; the file has: {}",
      path.string(), fmt::join(intensity_field_names(), ", "), field_list(cloud)));
}

double intensity_of(const IntensitySource& src, const std::uint8_t* point) {
  if (src.scalar != nullptr)
    return field_value(point + src.scalar->offset, src.scalar->datatype).value_or(NAN);
  if (src.packed_rgb != nullptr) {
    std::uint32_t v = 0;
    std::memcpy(&v, point + src.packed_rgb->offset, sizeof(v));
    return (static_cast<double>((v >> 16) & 0xffu) + static_cast<double>((v >> 8) & 0xffu) +
            static_cast<double>(v & 0xffu)) /
           3.0;
  }
  double sum = 0.0;
  for (const pcl::PCLPointField* f : src.rgb)
    sum += field_value(point + f->offset, f->datatype).value_or(NAN);
  return sum / 3.0;
}

/// Checks the x/y/z fields: present, FLOAT32 or FLOAT64, inside the point.
StatusOr<std::array<const pcl::PCLPointField*, 3>> xyz_fields(const pcl::PCLPointCloud2& cloud,
                                                              const fs::path& path) {
  std::array<const pcl::PCLPointField*, 3> xyz{};
  const char* names[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    xyz[k] = find_field(cloud, names[k]);
    if (xyz[k] == nullptr) {
      return absl::InvalidArgumentError(fmt::format("'{}' has no '{}' field; the file has: {}", path.string(),
                                                    names[k], field_list(cloud)));
    }
    if (xyz[k]->datatype != pcl::PCLPointField::FLOAT32 && xyz[k]->datatype != pcl::PCLPointField::FLOAT64) {
      return absl::InvalidArgumentError(
          fmt::format("'{}': field '{}' must be float or double (PCL datatype {})", path.string(), names[k],
                      static_cast<int>(xyz[k]->datatype)));
    }
  }
  return xyz;
}

/// PCLPointCloud2 -> RawCloud, dropping non-finite points.
StatusOr<RawCloud> convert(const pcl::PCLPointCloud2& cloud, const fs::path& path) {
  MRVS_ASSIGN_OR_RETURN(const auto xyz, xyz_fields(cloud, path));
  MRVS_ASSIGN_OR_RETURN(const IntensitySource src, intensity_source(cloud, path));
  const std::size_t n = static_cast<std::size_t>(cloud.width) * cloud.height;
  const std::size_t step = cloud.point_step;
  std::uint32_t field_end = 0;
  for (const pcl::PCLPointField& f : cloud.fields) {
    field_end =
        std::max<std::uint32_t>(field_end, f.offset + pcl::getFieldSize(f.datatype) * std::max(f.count, 1u));
  }
  if (field_end > step || cloud.data.size() < n * step) {
    return absl::DataLossError(
        fmt::format("'{}': PCL returned {} bytes for {} points of {} bytes; the file is "
                    "corrupt",
                    path.string(), cloud.data.size(), n, step));
  }
  RawCloud out;
  out.source = path.string();
  out.intensity_field = src.name;
  out.positions.reserve(n);
  out.intensities.reserve(n);
  std::size_t dropped = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* p = cloud.data.data() + i * step;
    const Vec3d pos(*field_value(p + xyz[0]->offset, xyz[0]->datatype),
                    *field_value(p + xyz[1]->offset, xyz[1]->datatype),
                    *field_value(p + xyz[2]->offset, xyz[2]->datatype));
    const double intensity = intensity_of(src, p);
    const auto intensity_f = static_cast<float>(intensity);
    if (!pos.allFinite() || !std::isfinite(intensity_f)) {
      ++dropped;
      continue;
    }
    out.positions.push_back(pos);
    out.intensities.push_back(intensity_f);
  }
  if (dropped > 0) {
    out.warnings.push_back(
        fmt::format("'{}': dropped {} of {} points with a non-finite coordinate or intensity", path.string(),
                    dropped, n));
  }
  if (out.positions.empty()) {
    return absl::InvalidArgumentError(
        fmt::format("'{}' has no finite point ({} points read, all non-finite)", path.string(), n));
  }
  return out;
}

std::string lower_extension(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext;
}

/// Reads the file with PCL once the header check passed. PCL errors become statuses.
StatusOr<pcl::PCLPointCloud2> read_with_pcl(const fs::path& path, bool ply, std::uint64_t declared_points) {
  pcl::PCLPointCloud2 cloud;
  int rc = -1;
  try {
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    if (ply) {
      pcl::PLYReader reader;
      int ply_version = 0;
      rc = reader.read(path.string(), cloud, origin, orientation, ply_version, 0);
    } else {
      pcl::PCDReader reader;
      int pcd_version = 0;
      rc = reader.read(path.string(), cloud, origin, orientation, pcd_version, 0);
    }
  } catch (const std::exception& e) {
    return absl::DataLossError(fmt::format("cannot read '{}': {}", path.string(), e.what()));
  }
  if (rc < 0) {
    return absl::DataLossError(
        fmt::format("cannot read '{}': PCL's {} reader failed (code {}); the file is "
                    "malformed or corrupt",
                    path.string(), ply ? "PLY" : "PCD", rc));
  }
  const std::uint64_t got = static_cast<std::uint64_t>(cloud.width) * cloud.height;
  if (got != declared_points) {
    return absl::DataLossError(
        fmt::format("'{}': the header declares {} points but {} could be read; the file "
                    "is truncated or corrupt",
                    path.string(), declared_points, got));
  }
  return cloud;
}

}  // namespace

const std::vector<std::string>& intensity_field_names() {
  static const std::vector<std::string> kNames = {"intensity", "scalar_intensity", "scalar_Intensity",
                                                  "reflectance", "i"};
  return kNames;
}

StatusOr<RawCloud> read_point_cloud(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) {
    return absl::NotFoundError(fmt::format("point cloud '{}' does not exist; check the path", path.string()));
  }
  if (!fs::is_regular_file(path, ec)) {
    return absl::InvalidArgumentError(fmt::format("point cloud '{}' is not a regular file", path.string()));
  }
  const std::string ext = lower_extension(path);
  if (ext != ".ply" && ext != ".pcd") {
    return absl::InvalidArgumentError(
        fmt::format("point cloud '{}': unknown extension '{}'; expected .ply or .pcd", path.string(), ext));
  }
  const std::uint64_t file_size = fs::file_size(path, ec);
  if (ec) return absl::UnavailableError(fmt::format("cannot stat '{}': {}", path.string(), ec.message()));
  const bool ply = ext == ".ply";
  MRVS_ASSIGN_OR_RETURN(const detail::CloudFileInfo info, ply ? detail::check_ply_file(path, file_size)
                                                              : detail::check_pcd_file(path, file_size));
  MRVS_ASSIGN_OR_RETURN(const pcl::PCLPointCloud2 cloud, read_with_pcl(path, ply, info.points));
  MRVS_ASSIGN_OR_RETURN(RawCloud raw, convert(cloud, path));
  raw.warnings.insert(raw.warnings.begin(), info.warnings.begin(), info.warnings.end());
  for (const std::string& w : raw.warnings) spdlog::warn("{}", w);
  return raw;
}

}  // namespace mrvs::map
