#include "mrvs/tools/request_dump.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

namespace mrvs::tools {

namespace {

void print_rows(std::FILE* f, const char* key, const SE3d& T) {
  const Eigen::Matrix4d m = T.matrix();
  for (int i = 0; i < 4; ++i)
    fmt::print(f, "{} {:.17g} {:.17g} {:.17g} {:.17g}\n", key, m(i, 0), m(i, 1), m(i, 2), m(i, 3));
}

}  // namespace

Status write_request_dump(const std::string& dir, const localisation::Request& q, const SE3d& answer,
                          const SE3d& truth) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  const std::string path = fmt::format("{}/req_{}.txt", dir, q.seq);
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return absl::UnavailableError(fmt::format("{}: cannot be written (check the folder)", path));
  print_rows(f, "TRUE", truth);
  print_rows(f, "ANSWER", answer);
  fmt::print(f, "ANCHOR {:.17g} {:.17g} {:.17g}\n", q.anchor_o.x(), q.anchor_o.y(), q.anchor_o.z());
  fmt::print(f, "GRAVITY {:.17g} {:.17g} {:.17g}\n", q.gravity_o.x(), q.gravity_o.y(), q.gravity_o.z());
  if (q.prior)
    fmt::print(f, "PRIOR {:.17g} {:.17g} {:.17g} {:.17g}\n", q.prior->centre_m.x(), q.prior->centre_m.y(),
               q.prior->centre_m.z(), q.prior->radius_m);
  const bool bright = q.brightness.size() == q.points.size();
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    const Eigen::Vector3f& p = q.points[i];
    if (bright) {
      fmt::print(f, "P {} {} {} {}\n", p.x(), p.y(), p.z(), q.brightness[i]);
    } else {
      fmt::print(f, "P {} {} {}\n", p.x(), p.y(), p.z());
    }
  }
  for (const auto& v : q.viewpoints)
    fmt::print(f, "V {} {} {} {}\n", v.position.x(), v.position.y(), v.position.z(), v.count);
  const bool ok = std::fclose(f) == 0;
  return ok ? Status() : absl::DataLossError(fmt::format("{}: writing failed (disk full?)", path));
}

StatusOr<DumpedRequest> read_request_dump(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(fmt::format("{}: cannot be opened", path));
  DumpedRequest d;
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity(), a = Eigen::Matrix4d::Identity();
  int true_rows = 0, answer_rows = 0, line_no = 0;
  std::string line, key;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ls(line);
    if (!(ls >> key)) continue;
    double x = 0, y = 0, z = 0, w = 0;
    if (!(ls >> x >> y >> z))
      return absl::DataLossError(fmt::format("{}:{}: '{}' needs three numbers", path, line_no, key));
    const bool has_w = static_cast<bool>(ls >> w);
    if ((key == "TRUE" || key == "ANSWER" || key == "PRIOR") && !has_w)
      return absl::DataLossError(fmt::format("{}:{}: '{}' needs four numbers", path, line_no, key));
    if (key == "TRUE" && true_rows < 4) {
      t.row(true_rows++) << x, y, z, w;
    } else if (key == "ANSWER" && answer_rows < 4) {
      a.row(answer_rows++) << x, y, z, w;
    } else if (key == "ANCHOR") {
      d.request.anchor_o = {x, y, z};
    } else if (key == "GRAVITY") {
      d.request.gravity_o = {x, y, z};
    } else if (key == "PRIOR") {
      d.request.prior = localisation::PriorRegion{{x, y, z}, w};
    } else if (key == "P") {
      d.request.points.emplace_back(x, y, z);
      if (has_w) d.request.brightness.push_back(static_cast<std::uint8_t>(std::clamp(w, 0.0, 255.0)));
    } else if (key == "V") {
      d.request.viewpoints.push_back({Eigen::Vector3f(x, y, z), has_w ? static_cast<std::uint32_t>(w) : 0u});
    }
  }
  if (true_rows != 4) return absl::DataLossError(fmt::format("{}: no TRUE pose (4 rows)", path));
  if (d.request.points.empty()) return absl::DataLossError(fmt::format("{}: no points (P lines)", path));
  if (!d.request.brightness.empty() && d.request.brightness.size() != d.request.points.size())
    return absl::DataLossError(fmt::format("{}: {} of {} P lines have a brightness (all or none)", path,
                                           d.request.brightness.size(), d.request.points.size()));
  d.truth = SE3d::from_matrix(t);
  d.answer = answer_rows == 4 ? SE3d::from_matrix(a) : SE3d();
  return d;
}

std::vector<std::string> request_dump_files(const std::string& dir) {
  std::vector<std::string> files;
  std::error_code ec;
  for (auto it = std::filesystem::recursive_directory_iterator(dir, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    if (it->path().filename().string().rfind("req_", 0) == 0) files.push_back(it->path().string());
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace mrvs::tools
