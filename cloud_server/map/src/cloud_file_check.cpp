#include "cloud_file_check.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include <fmt/format.h>

namespace mrvs::map::detail {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kMaxHeaderBytes = 1 << 20;
constexpr std::size_t kChunkBytes = 1 << 20;

/// The header text (up to kMaxHeaderBytes) and the offset of the first data byte, found
/// after the first line that starts with `last_key` ("end_header" / "DATA").
struct HeaderText {
  std::vector<std::string> lines;
  std::uint64_t data_offset = 0;
};

StatusOr<HeaderText> read_header(const fs::path& path, std::uint64_t file_size, const std::string& last_key,
                                 const char* kind) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(fmt::format("cannot open '{}' for reading", path.string()));
  std::string buffer(static_cast<std::size_t>(std::min<std::uint64_t>(file_size, kMaxHeaderBytes)), '\0');
  in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
  buffer.resize(static_cast<std::size_t>(in.gcount()));
  HeaderText header;
  std::size_t pos = 0;
  while (pos < buffer.size()) {
    const std::size_t eol = buffer.find('\n', pos);
    if (eol == std::string::npos) break;
    std::string line = buffer.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    header.lines.push_back(line);
    if (line.compare(0, last_key.size(), last_key) == 0) {
      header.data_offset = pos;
      return header;
    }
  }
  return absl::InvalidArgumentError(
      fmt::format("'{}' is truncated or not a {} file: no '{}' line in its first {} bytes", path.string(),
                  kind, last_key, buffer.size()));
}

std::vector<std::string> tokens_of(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  std::string t;
  while (in >> t) out.push_back(t);
  return out;
}

bool parse_u64(const std::string& text, std::uint64_t& out) {
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, out);
  return ec == std::errc() && ptr == end;
}

/// Counts whitespace-separated tokens (values) or non-blank lines from `offset` on, stopping
/// once `enough` are found.
std::uint64_t count_ascii(const fs::path& path, std::uint64_t offset, std::uint64_t enough, bool lines) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  std::string chunk(kChunkBytes, '\0');
  std::uint64_t count = 0;
  bool in_token = false;
  while (count < enough && in) {
    in.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    for (std::size_t i = 0; i < n; ++i) {
      const char c = chunk[i];
      const bool space = lines ? (c == '\n') : (std::isspace(static_cast<unsigned char>(c)) != 0);
      if (lines && !space && std::isspace(static_cast<unsigned char>(c)) != 0) continue;
      if (!space && !in_token) ++count;
      in_token = !space;
    }
    if (n == 0) break;
  }
  return count;
}

Status truncated_bytes(const fs::path& path, std::uint64_t expected, std::uint64_t file_size,
                       const std::string& what) {
  return absl::DataLossError(
      fmt::format("'{}' is truncated: its header declares {} ({} bytes with the header) but the file has {} "
                  "bytes ({} bytes missing); re-export or re-copy the file",
                  path.string(), what, expected, file_size, expected - file_size));
}

/// A count that cannot fit in the file whatever the rows hold (each row takes a byte at least).
Status impossible_count(const fs::path& path, std::uint64_t count, const std::string& what,
                        std::uint64_t file_size) {
  return absl::DataLossError(fmt::format(
      "'{}' is truncated or corrupt: its header declares {} {} but the whole file has only {} bytes",
      path.string(), count, what, file_size));
}

// ----------------------------------------------------------------------------- PLY

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_row_bytes = 0;  ///< fixed properties + the count field of each list
  std::uint64_t values = 0;         ///< values per row (a list counts as at least one)
  bool has_list = false;
  std::vector<std::string> properties;
};

int ply_type_size(const std::string& type) {
  static const std::map<std::string, int> kSizes = {
      {"char", 1},   {"int8", 1},    {"uchar", 1},  {"uint8", 1},  {"short", 2}, {"int16", 2},
      {"ushort", 2}, {"uint16", 2},  {"int", 4},    {"int32", 4},  {"uint", 4},  {"uint32", 4},
      {"float", 4},  {"float32", 4}, {"double", 8}, {"float64", 8}};
  const auto it = kSizes.find(type);
  return it == kSizes.end() ? 0 : it->second;
}

Status ply_property(const fs::path& path, const std::vector<std::string>& t,
                    std::vector<PlyElement>& elements) {
  auto bad = [&](const std::string& why) {
    return absl::InvalidArgumentError(fmt::format("'{}': malformed PLY header line 'property {}': {}",
                                                  path.string(), fmt::join(t.begin() + 1, t.end(), " "),
                                                  why));
  };
  if (elements.empty()) return bad("property before any element");
  PlyElement& e = elements.back();
  if (t.size() == 5 && t[1] == "list") {
    const int count_size = ply_type_size(t[2]);
    if (count_size == 0 || ply_type_size(t[3]) == 0) return bad("unknown list type");
    e.min_row_bytes += static_cast<std::uint64_t>(count_size);
    e.has_list = true;
    e.values += 1;
    e.properties.push_back(t[4]);
    return absl::OkStatus();
  }
  if (t.size() != 3) return bad("expected 'property <type> <name>'");
  const int size = ply_type_size(t[1]);
  if (size == 0) return bad(fmt::format("unknown type '{}'", t[1]));
  e.min_row_bytes += static_cast<std::uint64_t>(size);
  e.values += 1;
  e.properties.push_back(t[2]);
  return absl::OkStatus();
}

StatusOr<std::vector<PlyElement>> parse_ply_header(const fs::path& path, const HeaderText& header,
                                                   std::string& format) {
  if (header.lines.empty() || header.lines.front() != "ply") {
    return absl::InvalidArgumentError(
        fmt::format("'{}' is not a PLY file: its first line is not 'ply'", path.string()));
  }
  std::vector<PlyElement> elements;
  for (std::size_t i = 1; i < header.lines.size(); ++i) {
    const std::vector<std::string> t = tokens_of(header.lines[i]);
    if (t.empty() || t[0] == "comment" || t[0] == "obj_info" || t[0] == "end_header") continue;
    if (t[0] == "format" && t.size() == 3) {
      format = t[1];
    } else if (t[0] == "element" && t.size() == 3) {
      PlyElement e;
      e.name = t[1];
      if (!parse_u64(t[2], e.count)) {
        return absl::InvalidArgumentError(
            fmt::format("'{}': PLY element '{}' has an invalid count '{}'", path.string(), t[1], t[2]));
      }
      elements.push_back(e);
    } else if (t[0] == "property") {
      MRVS_RETURN_IF_ERROR(ply_property(path, t, elements));
    } else {
      return absl::InvalidArgumentError(
          fmt::format("'{}': malformed PLY header line {}: '{}'", path.string(), i + 1, header.lines[i]));
    }
  }
  if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian") {
    return absl::InvalidArgumentError(fmt::format(
        "'{}': unsupported PLY format '{}' (expected ascii, binary_little_endian or binary_big_endian)",
        path.string(), format));
  }
  return elements;
}

}  // namespace

StatusOr<CloudFileInfo> check_ply_file(const fs::path& path, std::uint64_t file_size) {
  MRVS_ASSIGN_OR_RETURN(const HeaderText header, read_header(path, file_size, "end_header", "PLY"));
  CloudFileInfo info;
  MRVS_ASSIGN_OR_RETURN(const std::vector<PlyElement> elements,
                        parse_ply_header(path, header, info.encoding));
  const auto vertex =
      std::find_if(elements.begin(), elements.end(), [](const PlyElement& e) { return e.name == "vertex"; });
  if (vertex == elements.end()) {
    return absl::InvalidArgumentError(
        fmt::format("'{}': the PLY header has no 'element vertex'", path.string()));
  }
  info.points = vertex->count;
  info.fields = vertex->properties;
  if (info.points == 0) {
    return absl::InvalidArgumentError(fmt::format("'{}' has zero points (element vertex 0)", path.string()));
  }
  const std::uint64_t body = file_size - header.data_offset;
  std::uint64_t need = 0;  // bytes (binary) or values (ascii), at least
  for (const PlyElement& e : elements) {
    const std::uint64_t per_row = info.encoding == "ascii" ? e.values : e.min_row_bytes;
    // Guard the products against overflow (absurd counts of a corrupt header).
    if (per_row > 0 && e.count > (std::uint64_t{1} << 56) / per_row) {
      return impossible_count(path, e.count, e.name + " rows", file_size);
    }
    need += e.count * per_row;
  }
  if (info.encoding == "ascii") {
    const std::uint64_t found = count_ascii(path, header.data_offset, need, /*lines=*/false);
    if (found < need) {
      return absl::DataLossError(
          fmt::format("'{}' is truncated: its PLY header declares {} vertices ({} values at least) but the "
                      "file holds only "
                      "{} values; re-export or re-copy the file",
                      path.string(), info.points, need, found));
    }
  } else if (need > body) {
    return truncated_bytes(path, header.data_offset + need, file_size,
                           fmt::format("{} vertices", info.points));
  } else if (need < body &&
             std::none_of(elements.begin(), elements.end(), [](const PlyElement& e) { return e.has_list; })) {
    info.warnings.push_back(
        fmt::format("'{}': {} bytes after the declared data were ignored", path.string(), body - need));
  }
  return info;
}

// ----------------------------------------------------------------------------- PCD

namespace {

struct PcdHeader {
  std::vector<std::string> fields;
  std::vector<std::uint64_t> sizes;
  std::vector<std::string> types;
  std::vector<std::uint64_t> counts;
  std::uint64_t width = 0;
  std::uint64_t height = 1;
  std::uint64_t points = 0;
  bool has_points = false;
  std::string data;
};

Status parse_u64_list(const fs::path& path, const std::vector<std::string>& t,
                      std::vector<std::uint64_t>& out) {
  out.clear();
  for (std::size_t i = 1; i < t.size(); ++i) {
    std::uint64_t v = 0;
    if (!parse_u64(t[i], v) || v > 1'000'000) {
      return absl::InvalidArgumentError(
          fmt::format("'{}': PCD header line '{}' has an invalid value '{}'", path.string(), t[0], t[i]));
    }
    out.push_back(v);
  }
  return absl::OkStatus();
}

/// SIZE / TYPE / COUNT consistency (PCL trusts them and can crash on nonsense).
Status check_pcd_fields(const fs::path& path, const PcdHeader& h) {
  if (h.fields.empty() || h.sizes.size() != h.fields.size() || h.types.size() != h.fields.size() ||
      (!h.counts.empty() && h.counts.size() != h.fields.size())) {
    return absl::InvalidArgumentError(
        fmt::format("'{}': malformed PCD header: FIELDS, SIZE, TYPE and COUNT must list one entry per field",
                    path.string()));
  }
  for (std::size_t i = 0; i < h.fields.size(); ++i) {
    const std::string& type = h.types[i];
    const std::uint64_t size = h.sizes[i];
    const bool ok = (type == "F" && (size == 4 || size == 8)) ||
                    ((type == "U" || type == "I") && (size == 1 || size == 2 || size == 4 || size == 8));
    if (!ok || (!h.counts.empty() && h.counts[i] == 0)) {
      return absl::InvalidArgumentError(
          fmt::format("'{}': PCD field '{}' has an invalid TYPE {} / SIZE {} / COUNT", path.string(),
                      h.fields[i], type, size));
    }
  }
  return absl::OkStatus();
}

StatusOr<PcdHeader> parse_pcd_header(const fs::path& path, const HeaderText& header) {
  PcdHeader h;
  for (const std::string& line : header.lines) {
    const std::vector<std::string> t = tokens_of(line);
    if (t.empty() || t[0][0] == '#') continue;
    const auto malformed = [&] {
      return absl::InvalidArgumentError(
          fmt::format("'{}': malformed PCD header line '{}'", path.string(), line));
    };
    auto number = [&](std::uint64_t& out) -> Status {
      return t.size() == 2 && parse_u64(t[1], out) ? absl::OkStatus() : malformed();
    };
    if (t[0] == "VERSION" || t[0] == "VIEWPOINT") {
      continue;
    } else if (t[0] == "FIELDS") {
      h.fields.assign(t.begin() + 1, t.end());
    } else if (t[0] == "SIZE") {
      MRVS_RETURN_IF_ERROR(parse_u64_list(path, t, h.sizes));
    } else if (t[0] == "TYPE") {
      h.types.assign(t.begin() + 1, t.end());
    } else if (t[0] == "COUNT") {
      MRVS_RETURN_IF_ERROR(parse_u64_list(path, t, h.counts));
    } else if (t[0] == "WIDTH") {
      MRVS_RETURN_IF_ERROR(number(h.width));
    } else if (t[0] == "HEIGHT") {
      MRVS_RETURN_IF_ERROR(number(h.height));
    } else if (t[0] == "POINTS") {
      MRVS_RETURN_IF_ERROR(number(h.points));
      h.has_points = true;
    } else if (t[0] == "DATA" && t.size() == 2) {
      h.data = t[1];
    } else {
      return malformed();  // PCL stops reading the header at an unknown line and may crash after
    }
  }
  MRVS_RETURN_IF_ERROR(check_pcd_fields(path, h));
  if (h.width > 0xffffffffull || h.height > 0xffffffffull) {
    return absl::InvalidArgumentError(fmt::format(
        "'{}': PCD header WIDTH {} / HEIGHT {} exceed the 32-bit range", path.string(), h.width, h.height));
  }
  if (h.has_points && h.points != h.width * h.height) {
    return absl::InvalidArgumentError(
        fmt::format("'{}': PCD header WIDTH {} x HEIGHT {} does not match POINTS {}", path.string(), h.width,
                    h.height, h.points));
  }
  if (!h.has_points) h.points = h.width * h.height;
  return h;
}

Status check_pcd_binary_compressed(const fs::path& path, std::uint64_t offset, std::uint64_t file_size,
                                   std::uint64_t raw_bytes) {
  if (offset + 8 > file_size) {
    return truncated_bytes(path, offset + 8, file_size, "binary_compressed data (8-byte size prefix)");
  }
  std::ifstream in(path, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(offset));
  unsigned char b[8] = {};
  in.read(reinterpret_cast<char*>(b), 8);
  auto u32 = [&](int k) {
    return static_cast<std::uint64_t>(b[k]) | static_cast<std::uint64_t>(b[k + 1]) << 8 |
           static_cast<std::uint64_t>(b[k + 2]) << 16 | static_cast<std::uint64_t>(b[k + 3]) << 24;
  };
  const std::uint64_t compressed = u32(0);
  const std::uint64_t uncompressed = u32(4);
  if (uncompressed != raw_bytes) {
    return absl::DataLossError(
        fmt::format("'{}' is corrupt: its binary_compressed block decompresses to {} bytes but the header "
                    "declares {} bytes of points",
                    path.string(), uncompressed, raw_bytes));
  }
  if (offset + 8 + compressed > file_size) {
    return truncated_bytes(path, offset + 8 + compressed, file_size, "a compressed block");
  }
  return absl::OkStatus();
}

}  // namespace

StatusOr<CloudFileInfo> check_pcd_file(const fs::path& path, std::uint64_t file_size) {
  MRVS_ASSIGN_OR_RETURN(const HeaderText header, read_header(path, file_size, "DATA", "PCD"));
  MRVS_ASSIGN_OR_RETURN(const PcdHeader h, parse_pcd_header(path, header));
  CloudFileInfo info;
  info.points = h.points;
  info.fields = h.fields;
  info.encoding = h.data;
  if (h.points == 0) return absl::InvalidArgumentError(fmt::format("'{}' has zero points", path.string()));
  std::uint64_t step = 0;
  for (std::size_t i = 0; i < h.fields.size(); ++i) step += h.sizes[i] * (h.counts.empty() ? 1 : h.counts[i]);
  const std::uint64_t body = file_size - header.data_offset;
  if (h.data == "ascii") {
    const std::uint64_t lines = count_ascii(path, header.data_offset, h.points, /*lines=*/true);
    if (lines < h.points) {
      return absl::DataLossError(fmt::format(
          "'{}' is truncated: its PCD header declares {} points but the file holds {} data lines; "
          "re-export or re-copy the file",
          path.string(), h.points, lines));
    }
  } else if (h.data == "binary" || h.data == "binary_compressed") {
    if (step == 0)
      return absl::InvalidArgumentError(fmt::format("'{}': PCD fields of zero size", path.string()));
    if (h.points > file_size) return impossible_count(path, h.points, "points", file_size);
    if (h.data == "binary" && h.points * step > body) {
      return truncated_bytes(path, header.data_offset + h.points * step, file_size,
                             fmt::format("{} points of {} bytes", h.points, step));
    }
    if (h.data == "binary_compressed") {
      MRVS_RETURN_IF_ERROR(check_pcd_binary_compressed(path, header.data_offset, file_size, h.points * step));
    }
  } else {
    return absl::InvalidArgumentError(
        fmt::format("'{}': unsupported PCD DATA '{}' (expected ascii, binary or binary_compressed)",
                    path.string(), h.data));
  }
  return info;
}

}  // namespace mrvs::map::detail
