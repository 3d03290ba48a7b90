#pragma once
// Shared helpers of the prior-map tests: the real V1_01 trajectory, the indoor test scene,
// and brute-force geometry (point-to-face distance, nearest-neighbour spacing).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/io/trajectory_io.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/scene.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::sim::test {

/// The bytes of a file ("" when it cannot be read).
inline std::string read_bytes(const std::filesystem::path& path) {
  std::string data;
  std::FILE* file = std::fopen(path.c_str(), "rb");
  if (file == nullptr) return data;
  char buffer[65536];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), file)) > 0) data.append(buffer, n);
  std::fclose(file);
  return data;
}

/// Body positions of the real EuRoC V1_01 ground truth at 20 Hz (every 10th row).
inline std::vector<Vec3d> v1_01_positions() {
  const auto trajectory = io::read_tum_trajectory(mrvs::test::euroc_groundtruth_file("V1_01_easy.txt"));
  EXPECT_TRUE(trajectory.ok()) << trajectory.status();
  std::vector<Vec3d> positions;
  if (!trajectory.ok()) return positions;
  for (std::size_t i = 0; i < trajectory->size(); i += 10)
    positions.push_back((*trajectory)[i].T_w_b.translation());
  return positions;
}

/// The indoor test scene around `trajectory`: 20 boxes, 2 unmapped and 2 removed, textures
/// baked at 16 mm instead of 4 mm (0.15 s instead of 0.9 s; the map only reads albedo()).
inline Scene indoor_test_scene(const std::vector<Vec3d>& trajectory) {
  SceneOptions options;
  options.unmapped_objects = 2;
  options.removed_objects = 2;
  options.texel_size_m = 0.016;
  auto scene = make_scene(SceneProfile::kIndoor, options, trajectory, 7);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return std::move(scene).value();
}

/// Independent visibility: `station` sees point `p` of face `f` (front side, shadow ray to a
/// point 2 mm in front of the face).
inline bool sees(const Scene& scene, const Face& f, const Vec3d& station, const Vec3d& p) {
  if ((station - f.origin).dot(f.normal) <= 0.0) return false;
  const Vec3d target = p + 0.002 * f.normal.normalized();
  return !scene.occluded(station.cast<float>(), target.cast<float>(), Visibility::kSurvey);
}

/// (u, v, w) of `p` in the face frame: w is the signed distance along the normal.
inline Vec3d face_coordinates(const Face& f, const Vec3d& p) {
  const Vec3d d = p - f.origin;
  return {d.dot(f.axis_u.normalized()), d.dot(f.axis_v.normalized()), d.dot(f.normal.normalized())};
}

/// Euclidean distance from `p` to the rectangle of face `f`.
inline double distance_to_face(const Face& f, const Vec3d& p) {
  const Vec3d c = face_coordinates(f, p);
  const double du = std::max({0.0, -c.x(), c.x() - f.size_u});
  const double dv = std::max({0.0, -c.y(), c.y() - f.size_v});
  return std::sqrt(du * du + dv * dv + c.z() * c.z());
}

/// Uniform hash grid over points for nearest-neighbour queries.
class PointGrid {
 public:
  PointGrid(const std::vector<MapPoint>& points, double cell) : points_(points), cell_(cell) {
    for (std::size_t i = 0; i < points.size(); ++i)
      cells_[key(points[i].position.cast<double>())].push_back(i);
  }

  /// Distance from point `i` to its nearest other point, searching +-1 cell (infinity if none).
  double nearest_other(std::size_t i) const { return nearest(points_[i].position.cast<double>(), i); }

  /// Distance from `p` to the nearest point other than `skip`, searching +-1 cell.
  double nearest(const Vec3d& p, std::size_t skip = static_cast<std::size_t>(-1)) const {
    double best = std::numeric_limits<double>::infinity();
    const Eigen::Vector3i c = cell(p);
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(pack(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (std::size_t j : it->second) {
            if (j != skip) best = std::min(best, (points_[j].position.cast<double>() - p).norm());
          }
        }
      }
    }
    return best;
  }

 private:
  Eigen::Vector3i cell(const Vec3d& p) const { return (p / cell_).array().floor().cast<int>(); }
  static std::int64_t pack(const Eigen::Vector3i& c) {
    return ((static_cast<std::int64_t>(c.x()) + 100000) * 200000 + (c.y() + 100000)) * 200000 +
           (c.z() + 100000);
  }
  std::int64_t key(const Vec3d& p) const { return pack(cell(p)); }

  const std::vector<MapPoint>& points_;
  double cell_;
  std::unordered_map<std::int64_t, std::vector<std::size_t>> cells_;
};

/// Median nearest-neighbour distance (neighbours among all `points`, searched within +-1
/// cell of size `cell`) over the query points `queries` (indices into `points`).
inline double median_nn_distance(const std::vector<MapPoint>& points, double cell,
                                 const std::vector<std::size_t>& queries) {
  const PointGrid grid(points, cell);
  std::vector<double> d;
  for (std::size_t i : queries) {
    const double nn = grid.nearest_other(i);
    if (std::isfinite(nn)) d.push_back(nn);
  }
  if (d.empty()) return 0.0;
  std::nth_element(d.begin(), d.begin() + static_cast<std::ptrdiff_t>(d.size() / 2), d.end());
  return d[d.size() / 2];
}

/// Every `stride`-th index of `points`.
inline std::vector<std::size_t> every_nth(const std::vector<MapPoint>& points, std::size_t stride) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < points.size(); i += stride) out.push_back(i);
  return out;
}

/// Median nearest-neighbour distance of a stratified jittered grid of cell size 1 with one
/// uniform sample per cell (Monte Carlo, 25 600 points: 0.635); the expected "spacing" of
/// our maps in units of the cell size.
inline constexpr double kJitteredGridMedianNn = 0.635;

}  // namespace mrvs::sim::test
