// PLY and YAML files of the prior map.
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <fmt/format.h>

#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/map_io.h"

namespace mrvs::sim {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kChunkPoints = 65536;
constexpr std::size_t kMaxHeaderBytes = 65536;

std::string errno_text(int err) { return std::generic_category().message(err); }

/// Writes a file through "<path>.tmp" + rename. `body` writes the content with
/// write(const char*, size) and returns false on a write error.
template <class Body>
Status write_atomically(const fs::path& path, Body&& body) {
  const fs::path tmp = path.string() + ".tmp";
  std::FILE* file = std::fopen(tmp.c_str(), "wb");
  if (file == nullptr) {
    return absl::UnavailableError(
        fmt::format("cannot open '{}' for writing: {}", tmp.string(), errno_text(errno)));
  }
  bool ok = true;
  auto write = [&](const char* data, std::size_t size) {
    if (ok && size > 0 && std::fwrite(data, 1, size, file) != size) ok = false;
    return ok;
  };
  body(write);
  int err = ok ? 0 : errno;
  if (std::fclose(file) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return absl::DataLossError(fmt::format("cannot write '{}': {}", path.string(), errno_text(err)));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    return absl::UnavailableError(
        fmt::format("cannot rename '{}' to '{}': {}", tmp.string(), path.string(), ec.message()));
  }
  return absl::OkStatus();
}

std::string ply_header(std::size_t count, const std::string& comment, PlyFormat format) {
  std::string header = "ply\n";
  header += format == PlyFormat::kAscii ? "format ascii 1.0\n" : "format binary_little_endian 1.0\n";
  std::istringstream lines(comment);
  std::string line;
  while (std::getline(lines, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    header += line.empty() ? "comment\n" : "comment " + line + "\n";
  }
  header += fmt::format("element vertex {}\n", count);
  header += "property float x\nproperty float y\nproperty float z\nproperty float intensity\nend_header\n";
  return header;
}

void put_float_le(float value, char* out) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &value, sizeof(bits));
  for (int b = 0; b < 4; ++b) out[b] = static_cast<char>((bits >> (8 * b)) & 0xFFu);
}

float get_float_le(const char* in) {
  std::uint32_t bits = 0;
  for (int b = 0; b < 4; ++b)
    bits |= static_cast<std::uint32_t>(static_cast<unsigned char>(in[b])) << (8 * b);
  float value = 0.0f;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

/// Appends the body of points [begin, end) in `format` to `out`.
void encode_points(const std::vector<MapPoint>& points, std::size_t begin, std::size_t end, PlyFormat format,
                   std::string& out) {
  out.clear();
  if (format == PlyFormat::kAscii) {
    for (std::size_t i = begin; i < end; ++i) {
      const MapPoint& p = points[i];
      fmt::format_to(std::back_inserter(out), "{} {} {} {}\n", p.position.x(), p.position.y(), p.position.z(),
                     p.intensity);
    }
    return;
  }
  out.resize((end - begin) * 16);
  char* dst = out.data();
  for (std::size_t i = begin; i < end; ++i, dst += 16) {
    const MapPoint& p = points[i];
    put_float_le(p.position.x(), dst);
    put_float_le(p.position.y(), dst + 4);
    put_float_le(p.position.z(), dst + 8);
    put_float_le(p.intensity, dst + 12);
  }
}

// ---- reading ------------------------------------------------------------------------------

StatusOr<std::string> read_file(const fs::path& path) {
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) {
    return absl::NotFoundError(fmt::format("cannot open '{}': {}", path.string(), errno_text(errno)));
  }
  std::string data;
  std::array<char, 1 << 16> buffer{};
  std::size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), file)) > 0) data.append(buffer.data(), n);
  const bool failed = std::ferror(file) != 0;
  std::fclose(file);
  if (failed) return absl::DataLossError(fmt::format("cannot read '{}'", path.string()));
  return data;
}

/// What the header of a PLY file says.
struct PlyHeader {
  bool ascii = false;
  std::size_t count = 0;
  std::vector<std::string> properties;  ///< float properties of the vertex element, in order
  std::size_t data_offset = 0;          ///< first byte after "end_header\n"
};

std::vector<std::string> split_words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> words;
  std::string w;
  while (in >> w) words.push_back(w);
  return words;
}

/// One header line (after "ply"); `error` is set on a problem.
void parse_header_line(const std::vector<std::string>& w, PlyHeader& h, bool& have_format, bool& have_vertex,
                       std::string& error) {
  if (w.empty() || w[0] == "comment" || w[0] == "obj_info") return;
  if (w[0] == "format") {
    if (w.size() != 3 || w[2] != "1.0") {
      error = "malformed 'format' line";
    } else if (w[1] == "ascii" || w[1] == "binary_little_endian") {
      h.ascii = w[1] == "ascii";
      have_format = true;
    } else {
      error = fmt::format("unsupported format '{}' (expected ascii or binary_little_endian)", w[1]);
    }
  } else if (w[0] == "element") {
    std::uint64_t n = 0;
    const bool number = w.size() == 3 &&
                        std::from_chars(w[2].data(), w[2].data() + w[2].size(), n).ec == std::errc() &&
                        std::to_string(n) == w[2];
    if (w.size() != 3 || w[1] != "vertex" || have_vertex || !number) {
      error = "expected exactly one 'element vertex <count>' element";
    } else {
      h.count = static_cast<std::size_t>(n);
      have_vertex = true;
    }
  } else if (w[0] == "property") {
    if (!have_vertex) {
      error = "'property' before 'element vertex'";
    } else if (w.size() != 3 || (w[1] != "float" && w[1] != "float32")) {
      error = "only 'property float <name>' is supported";
    } else {
      h.properties.push_back(w[2]);
    }
  } else {
    error = fmt::format("unexpected header line starting with '{}'", w[0]);
  }
}

StatusOr<PlyHeader> parse_header(const std::string& data, const fs::path& path) {
  auto fail = [&](const std::string& what) {
    return absl::InvalidArgumentError(fmt::format("{}: not a supported PLY file: {}", path.string(), what));
  };
  PlyHeader h;
  bool have_format = false;
  bool have_vertex = false;
  std::size_t pos = 0;
  for (int line_no = 1;; ++line_no) {
    const std::size_t eol = data.find('\n', pos);
    if (eol == std::string::npos || eol > kMaxHeaderBytes) return fail("no 'end_header' line");
    std::string line = data.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    if (line_no == 1) {
      if (line != "ply") return fail("first line is not 'ply'");
      continue;
    }
    if (line == "end_header") break;
    std::string error;
    parse_header_line(split_words(line), h, have_format, have_vertex, error);
    if (!error.empty()) return fail(fmt::format("header line {}: {}", line_no, error));
  }
  if (!have_format) return fail("no 'format' line");
  if (!have_vertex) return fail("no 'element vertex' line");
  for (const char* name : {"x", "y", "z", "intensity"}) {
    if (std::count(h.properties.begin(), h.properties.end(), name) != 1) {
      return fail(fmt::format("the vertex element needs exactly one float property '{}'", name));
    }
  }
  h.data_offset = pos;
  return h;
}

/// Column of x, y, z, intensity among the properties.
std::array<std::size_t, 4> xyzi_columns(const PlyHeader& h) {
  std::array<std::size_t, 4> col{};
  const std::array<const char*, 4> names = {"x", "y", "z", "intensity"};
  for (std::size_t k = 0; k < 4; ++k) {
    col[k] = static_cast<std::size_t>(std::find(h.properties.begin(), h.properties.end(), names[k]) -
                                      h.properties.begin());
  }
  return col;
}

MapPoint make_point(const float* values, const std::array<std::size_t, 4>& col) {
  MapPoint p;
  p.position = Eigen::Vector3f(values[col[0]], values[col[1]], values[col[2]]);
  p.intensity = values[col[3]];
  return p;
}

StatusOr<std::vector<MapPoint>> read_binary(const std::string& data, const PlyHeader& h,
                                            const fs::path& path) {
  const std::size_t stride = 4 * h.properties.size();
  const std::size_t available = data.size() - h.data_offset;
  if (h.count > available / stride) {
    return absl::DataLossError(
        fmt::format("{}: truncated file: {} vertices of {} bytes declared, only {} bytes of data",
                    path.string(), h.count, stride, available));
  }
  if (h.count * stride != available) {
    return absl::DataLossError(fmt::format("{}: {} unexpected bytes after the {} vertices", path.string(),
                                           available - h.count * stride, h.count));
  }
  const std::array<std::size_t, 4> col = xyzi_columns(h);
  std::vector<MapPoint> points(h.count);
  std::vector<float> values(h.properties.size());
  const char* src = data.data() + h.data_offset;
  for (std::size_t i = 0; i < h.count; ++i) {
    for (std::size_t k = 0; k < values.size(); ++k, src += 4) values[k] = get_float_le(src);
    points[i] = make_point(values.data(), col);
  }
  return points;
}

StatusOr<std::vector<MapPoint>> read_ascii(const std::string& data, const PlyHeader& h,
                                           const fs::path& path) {
  const std::size_t p = h.properties.size();
  if (h.count > (data.size() - h.data_offset) / (2 * p)) {
    return absl::DataLossError(fmt::format("{}: truncated file: {} vertices declared, the data is too short",
                                           path.string(), h.count));
  }
  const std::array<std::size_t, 4> col = xyzi_columns(h);
  std::vector<MapPoint> points(h.count);
  std::vector<float> values(p);
  const char* cur = data.data() + h.data_offset;
  const char* end = data.data() + data.size();
  auto skip_space = [&] {
    while (cur < end && std::isspace(static_cast<unsigned char>(*cur))) ++cur;
  };
  for (std::size_t i = 0; i < h.count; ++i) {
    for (std::size_t k = 0; k < p; ++k) {
      skip_space();
      const auto [next, ec] = std::from_chars(cur, end, values[k]);
      if (cur == end || ec != std::errc() ||
          (next < end && !std::isspace(static_cast<unsigned char>(*next)))) {
        return absl::DataLossError(fmt::format("{}: vertex {} value {}: {}", path.string(), i, k,
                                               cur == end ? "truncated file" : "not a number"));
      }
      cur = next;
    }
    points[i] = make_point(values.data(), col);
  }
  skip_space();
  if (cur != end)
    return absl::DataLossError(fmt::format("{}: unexpected data after the vertices", path.string()));
  return points;
}

}  // namespace

Status write_ply(const fs::path& path, const std::vector<MapPoint>& points, const std::string& comment,
                 PlyFormat format) {
  const std::string header = ply_header(points.size(), comment, format);
  return write_atomically(path, [&](auto&& write) {
    if (!write(header.data(), header.size())) return;
    std::string chunk;
    for (std::size_t begin = 0; begin < points.size(); begin += kChunkPoints) {
      encode_points(points, begin, std::min(points.size(), begin + kChunkPoints), format, chunk);
      if (!write(chunk.data(), chunk.size())) return;
    }
  });
}

StatusOr<std::vector<MapPoint>> read_ply_xyzi(const fs::path& path) {
  MRVS_ASSIGN_OR_RETURN(const std::string data, read_file(path));
  MRVS_ASSIGN_OR_RETURN(const PlyHeader header, parse_header(data, path));
  return header.ascii ? read_ascii(data, header, path) : read_binary(data, header, path);
}

Status write_transform_yaml(const fs::path& path, const SE3d& T_map_world) {
  const Mat4d m = T_map_world.matrix();
  std::string text =
      "# Synthetic prior-map misalignment (simulator ground truth, never given to the estimator).\n"
      "# p_map = T_map_world * p_world; the points of pointcloud0/data.ply are in the map frame.\n"
      "T_map_world:\n  cols: 4\n  rows: 4\n  data: [";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      const bool last = r == 3 && c == 3;
      text += fmt::format("{:.17g}{}", m(r, c), last ? "]\n" : (c == 3 ? ",\n         " : ", "));
    }
  }
  const double angle_deg = so3::log<double>(T_map_world.quaternion()).norm() * 180.0 / kPi;
  text += fmt::format("rotation_angle_deg: {:.17g}\n", angle_deg);
  text += fmt::format("translation_norm_m: {:.17g}\n", T_map_world.translation().norm());
  return write_atomically(path, [&](auto&& write) { write(text.data(), text.size()); });
}

}  // namespace mrvs::sim
