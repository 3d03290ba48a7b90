#include "map_test_util.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace mrvs::map::test {
namespace {

/// Little-endian bytes of `v` converted to `type` (PLY or PCD type names).
std::string encode(const std::string& type, double v) {
  auto bytes_of = [](auto x) {
    std::string s(sizeof(x), '\0');
    std::memcpy(s.data(), &x, sizeof(x));
    return s;
  };
  if (type == "float" || type == "float32" || type == "F4") return bytes_of(static_cast<float>(v));
  if (type == "double" || type == "float64" || type == "F8") return bytes_of(v);
  if (type == "uchar" || type == "uint8" || type == "U1") return bytes_of(static_cast<std::uint8_t>(v));
  if (type == "char" || type == "int8" || type == "I1") return bytes_of(static_cast<std::int8_t>(v));
  if (type == "ushort" || type == "uint16" || type == "U2") return bytes_of(static_cast<std::uint16_t>(v));
  if (type == "short" || type == "int16" || type == "I2") return bytes_of(static_cast<std::int16_t>(v));
  if (type == "uint" || type == "uint32" || type == "U4") return bytes_of(static_cast<std::uint32_t>(v));
  if (type == "int" || type == "int32" || type == "I4") return bytes_of(static_cast<std::int32_t>(v));
  throw std::invalid_argument("unknown type " + type);
}

/// Shortest text of `v` as the field's type.
std::string text_of(const std::string& type, double v) {
  if (type == "float" || type == "float32" || type == "F4") return fmt::format("{}", static_cast<float>(v));
  if (type == "double" || type == "float64" || type == "F8") return fmt::format("{}", v);
  return fmt::format("{}", static_cast<long long>(v));
}

/// LZF stream made of literal runs only (control byte n - 1, then n <= 32 bytes): valid LZF.
std::string lzf_literals(const std::string& raw) {
  std::string out;
  for (std::size_t pos = 0; pos < raw.size(); pos += 32) {
    const std::size_t n = std::min<std::size_t>(32, raw.size() - pos);
    out.push_back(static_cast<char>(n - 1));
    out.append(raw, pos, n);
  }
  return out;
}

std::string u32_le(std::uint32_t v) {
  std::string s(4, '\0');
  for (int b = 0; b < 4; ++b) s[static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xffu);
  return s;
}

}  // namespace

void write_ply(const std::filesystem::path& path, const std::string& format, const std::vector<Field>& fields,
               const std::vector<std::vector<double>>& rows, const std::string& extra_header) {
  std::string out = fmt::format("ply\nformat {} 1.0\ncomment written by the map tests\nelement vertex {}\n",
                                format, rows.size());
  for (const Field& f : fields) out += fmt::format("property {} {}\n", f.type, f.name);
  out += extra_header + "end_header\n";
  for (const std::vector<double>& row : rows) {
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (format == "ascii") {
        out += text_of(fields[k].type, row[k]) + (k + 1 == fields.size() ? "\n" : " ");
      } else {
        std::string bytes = encode(fields[k].type, row[k]);
        if (format == "binary_big_endian") std::reverse(bytes.begin(), bytes.end());
        out += bytes;
      }
    }
  }
  write_bytes(path, out);
}

void write_pcd(const std::filesystem::path& path, const std::string& data, const std::vector<Field>& fields,
               const std::vector<std::vector<double>>& rows) {
  std::string names, sizes, types, counts;
  for (const Field& f : fields) {
    names += " " + f.name;
    sizes += " " + std::string(1, f.type[1]);
    types += " " + std::string(1, f.type[0]);
    counts += " 1";
  }
  std::string out = fmt::format(
      "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS{}\nSIZE{}\nTYPE{}\nCOUNT{}\nWIDTH {}\n"
      "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {}\n",
      names, sizes, types, counts, rows.size(), rows.size(), data);
  if (data == "ascii") {
    for (const std::vector<double>& row : rows) {
      for (std::size_t k = 0; k < fields.size(); ++k) {
        out += text_of(fields[k].type, row[k]) + (k + 1 == fields.size() ? "\n" : " ");
      }
    }
  } else if (data == "binary") {
    for (const std::vector<double>& row : rows) {
      for (std::size_t k = 0; k < fields.size(); ++k) out += encode(fields[k].type, row[k]);
    }
  } else {
    std::string soa;  // binary_compressed: field after field
    for (std::size_t k = 0; k < fields.size(); ++k) {
      for (const std::vector<double>& row : rows) soa += encode(fields[k].type, row[k]);
    }
    const std::string compressed = lzf_literals(soa);
    out += u32_le(static_cast<std::uint32_t>(compressed.size())) +
           u32_le(static_cast<std::uint32_t>(soa.size()));
    out += compressed;
  }
  write_bytes(path, out);
}

std::vector<std::vector<double>> xyzi_rows(const RawCloud& cloud) {
  std::vector<std::vector<double>> rows;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vec3d& p = cloud.positions[i];
    rows.push_back({p.x(), p.y(), p.z(), static_cast<double>(cloud.intensities[i])});
  }
  return rows;
}

RawCloud random_cloud(std::size_t n, std::uint64_t seed, double extent, const Eigen::Vector3d& offset) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  RawCloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    cloud.positions.push_back(offset + extent * Vec3d(x, y, z));
    cloud.intensities.push_back(static_cast<float>(u(rng)));
  }
  return cloud;
}

RawCloud wavy_cloud(std::size_t n, std::uint64_t seed, double extent, double noise) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  RawCloud cloud;
  const double a = 0.1 * extent, l = 0.2 * extent;
  for (std::size_t i = 0; i < n; ++i) {
    const double x = extent * u(rng), y = extent * u(rng);
    const double z = a * std::sin(x / l) * std::cos(y / l) + noise * g(rng);
    cloud.positions.emplace_back(x, y, z);
    cloud.intensities.push_back(static_cast<float>(u(rng)));
  }
  return cloud;
}

std::string read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void write_bytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

bool same_bits(const MapPoint& a, const MapPoint& b) {
  const float fa[5] = {a.position.x(), a.position.y(), a.position.z(), a.intensity, a.saliency};
  const float fb[5] = {b.position.x(), b.position.y(), b.position.z(), b.intensity, b.saliency};
  return std::memcmp(fa, fb, sizeof(fa)) == 0;
}

}  // namespace mrvs::map::test
