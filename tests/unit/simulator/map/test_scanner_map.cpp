// The terrestrial-scanner map (map.model = scanner) against its model, one station in the
// indoor test scene: point density falls with the square of the range (the angular step),
// range noise grows with range along the ray, returns drop out with incidence as set, every
// point is seen from its station above the lowest elevation, the merged scans are no denser
// than scan_min_spacing_m, and the same seed gives the same map for any thread count. Plus
// the surface-coverage measure against a brute-force count.
#include <omp.h>

#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "map_test_support.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/surface_coverage.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::sim::test {
namespace {

constexpr std::uint64_t kSeed = 5;

/// One station, a coarse 3 mrad step, no thinning floor, nothing dropped, noisy or holed.
MapOptions bare_scanner() {
  MapOptions o = test_map_options();
  o.model = MapModel::kScanner;
  o.num_stations = 1;
  o.scan_step_mrad = 3.0;
  o.scan_min_spacing_m = 0.0005;
  o.dropout_start_deg = 90.0;
  o.dropout_full_deg = 90.0;
  o.range_noise_m = 0.0;
  o.range_noise_per_m = 0.0;
  o.noise_normal_sigma_m = 0.0;
  o.noise_tangent_sigma_m = 0.0;
  o.intensity_noise_sigma = 0.0;
  o.holes_fraction = 0.0;
  return o;
}

/// The shipped scanner knobs (noise, dropout, skipping, thinning), one station, 2 mrad.
MapOptions scanner_defaults_for_test() {
  MapOptions o;
  o.model = MapModel::kScanner;
  o.num_stations = 1;
  o.scan_step_mrad = 2.0;
  return o;
}

class ScannerMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    trajectory_ = std::make_unique<std::vector<Vec3d>>(v1_01_positions());
    scene_ = std::make_unique<Scene>(indoor_test_scene(*trajectory_));
  }
  static void TearDownTestSuite() {
    scene_.reset();
    trajectory_.reset();
  }
  static PriorMap scan(const MapOptions& o) {
    auto map = sample_prior_map(*scene_, *trajectory_, o, kSeed);
    EXPECT_TRUE(map.ok()) << map.status();
    return map.ok() ? std::move(map).value() : PriorMap{};
  }
  static Vec3d station(const PriorMap& map) { return map.stations.front().position_w; }
  static inline std::unique_ptr<std::vector<Vec3d>> trajectory_;
  static inline std::unique_ptr<Scene> scene_;
};

TEST_F(ScannerMapTest, DensityFallsWithTheSquareOfTheRange) {
  const MapOptions o = bare_scanner();
  const PriorMap map = scan(o);
  ASSERT_EQ(map.stations.size(), 1u);
  ASSERT_TRUE(map.stations.front().used);
  const Vec3d s = station(map);
  const double step = 1e-3 * o.scan_step_mrad;
  int walls = 0;
  for (int f = 0; f < 4; ++f) {  // the room's walls: axis-aligned, facing in
    const Face& wall = scene_->faces()[static_cast<std::size_t>(f)];
    const Vec3d n = wall.normal.normalized();
    const double range = (s - wall.origin).dot(n);
    const Vec3d foot = s - range * n;         // the wall point at the station's height, straight ahead
    const double half = 25.0 * range * step;  // 50 lattice steps: the count is within 4 % of the area's
    bool clear = true;
    for (double a : {-half, 0.0, half}) {
      for (double b : {-half, 0.0, half}) {
        const Vec3d q = foot + a * wall.axis_u.normalized() + b * wall.axis_v.normalized() + 1e-3 * n;
        clear = clear && !scene_->occluded(s.cast<float>(), q.cast<float>(), Visibility::kSurvey);
      }
    }
    if (!clear) continue;
    int count = 0;
    for (const MapPoint& p : map.clean_points) {
      const Vec3d d = p.position.cast<double>() - foot;
      if (p.face == f && std::abs(d.dot(wall.axis_u.normalized())) < half &&
          std::abs(d.dot(wall.axis_v.normalized())) < half) {
        ++count;
      }
    }
    const double expected = (2.0 * half) * (2.0 * half) / ((range * step) * (range * step));
    ::testing::Test::RecordProperty("wall_" + std::to_string(f) + "_range_m", std::to_string(range));
    EXPECT_NEAR(count, expected, 0.06 * expected) << "wall " << f << " at " << range << " m";
    ++walls;
  }
  EXPECT_GE(walls, 2);
}

TEST_F(ScannerMapTest, RangeNoiseGrowsWithRangeAlongTheRay) {
  MapOptions o = bare_scanner();
  o.range_noise_m = 0.002;
  o.range_noise_per_m = 0.002;
  const PriorMap map = scan(o);
  ASSERT_EQ(map.points.size(), map.clean_points.size());
  const Vec3d s = station(map);
  double near_sq = 0, far_sq = 0, near_r = 0, far_r = 0;
  int near_n = 0, far_n = 0;
  for (std::size_t i = 0; i < map.points.size(); ++i) {
    const Vec3d clean = map.clean_points[i].position.cast<double>();
    const Vec3d ray = (clean - s).normalized();
    const Vec3d error = map.points[i].position.cast<double>() - clean;
    EXPECT_LT((error - error.dot(ray) * ray).norm(), 1e-4) << "noise along the ray only";
    const double r = (clean - s).norm(), e = error.dot(ray);
    if (r < 2.0) near_sq += e * e, near_r += r, ++near_n;
    if (r > 4.0) far_sq += e * e, far_r += r, ++far_n;
  }
  ASSERT_GT(near_n, 5000);
  ASSERT_GT(far_n, 5000);
  // sigma(r) is linear in r: the bin's rms is sigma at about its mean range.
  EXPECT_NEAR(std::sqrt(near_sq / near_n), 0.002 + 0.002 * near_r / near_n,
              0.1 * (0.002 + 0.002 * near_r / near_n));
  EXPECT_NEAR(std::sqrt(far_sq / far_n), 0.002 + 0.002 * far_r / far_n,
              0.1 * (0.002 + 0.002 * far_r / far_n));
}

TEST_F(ScannerMapTest, ReturnsDropOutWithIncidenceAsSet) {
  MapOptions o = bare_scanner();
  const PriorMap all = scan(o);
  o.dropout_start_deg = 30.0;
  o.dropout_full_deg = 80.0;
  const PriorMap kept = scan(o);
  const Vec3d s = station(all);
  const auto incidence_deg = [&](const MapPoint& p) {
    const Face& f = scene_->faces()[static_cast<std::size_t>(p.face)];
    const Vec3d d = (p.position.cast<double>() - s).normalized();
    return std::acos(std::min(1.0, std::abs(d.dot(f.normal.normalized())))) * 180.0 / M_PI;
  };
  const double c30 = std::cos(30.0 * M_PI / 180.0), c80 = std::cos(80.0 * M_PI / 180.0);
  for (const auto& [lo, hi] :
       std::vector<std::pair<double, double>>{{10, 25}, {40, 50}, {60, 70}, {82, 89}}) {
    double candidates = 0.0, expected = 0.0, got = 0.0;
    for (const MapPoint& p : all.clean_points) {
      const double a = incidence_deg(p);
      if (a < lo || a >= hi) continue;
      candidates += 1.0;
      const double c = std::cos(a * M_PI / 180.0);
      expected += c >= c30 ? 1.0 : std::max(0.0, (c - c80) / (c30 - c80));
    }
    for (const MapPoint& p : kept.clean_points) {
      const double a = incidence_deg(p);
      got += (a >= lo && a < hi) ? 1.0 : 0.0;
    }
    ASSERT_GT(candidates, 1000) << lo;
    EXPECT_NEAR(got / candidates, expected / candidates, 0.03) << lo << "-" << hi << " deg";
  }
}

TEST_F(ScannerMapTest, EveryPointIsSeenFromTheStationAboveItsLowestElevation) {
  MapOptions o = bare_scanner();
  o.scan_min_elevation_deg = -20.0;
  const PriorMap map = scan(o);
  const Vec3d s = station(map);
  int checked = 0, unseen = 0;
  for (std::size_t i = 0; i < map.clean_points.size(); ++i) {
    const MapPoint& p = map.clean_points[i];
    const Vec3d d = p.position.cast<double>() - s;
    EXPECT_GE(d.z(), d.norm() * std::sin(-20.0 * M_PI / 180.0) - 1e-6) << i;
    if (i % 97 != 0) continue;
    const Face& f = scene_->faces()[static_cast<std::size_t>(p.face)];
    EXPECT_TRUE(f.in_map);
    ++checked;
    unseen += sees(*scene_, f, s, p.position.cast<double>()) ? 0 : 1;
  }
  // A point right at a box's foot can have its check ray (to 2 mm off the face) graze the box.
  EXPECT_LT(unseen, checked / 500 + 1) << unseen << " of " << checked;
  EXPECT_GT(checked, 1000);
}

TEST_F(ScannerMapTest, TheMergedScansAreNoDenserThanTheMinimumSpacing) {
  MapOptions o = bare_scanner();
  o.scan_step_mrad = 0.5;  // 1.5 mm at 3 m: the floor decides nearly everywhere
  o.scan_min_spacing_m = 0.02;
  const PriorMap map = scan(o);
  std::vector<double> per_face(scene_->faces().size(), 0.0);
  for (const MapPoint& p : map.clean_points) per_face[static_cast<std::size_t>(p.face)] += 1.0;
  int faces = 0;
  for (std::size_t f = 0; f < per_face.size(); ++f) {
    const Face& face = scene_->faces()[f];
    const double area = face.size_u * face.size_v;
    if (area < 2.0 || per_face[f] < 0.5 * area / (0.02 * 0.02)) continue;  // mostly seen
    ++faces;
    EXPECT_LE(per_face[f] / area, 1.1 / (0.02 * 0.02)) << "face " << f;  // + rounding to whole cells per tile
  }
  EXPECT_GE(faces, 3);
}

TEST_F(ScannerMapTest, SameSeedSameMapForAnyThreadCount) {
  MapOptions o = scanner_defaults_for_test();
  const PriorMap a = scan(o);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const PriorMap b = scan(o);
  omp_set_num_threads(threads);
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_GT(a.points.size(), 10000u);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    ASSERT_EQ(a.points[i].position, b.points[i].position) << i;
    ASSERT_EQ(a.points[i].intensity, b.points[i].intensity) << i;
  }
}

TEST_F(ScannerMapTest, TheTrueSurfaceOfAFloorDiskIsItsArea) {
  // A camera 1.5 m above the middle of the open floor: within 2.5 m it sees a floor disk of
  // radius 2 m (and walls or boxes only if they are near).
  const Eigen::AlignedBox3d room = scene_->bounds();
  Vec3d camera = room.center();
  camera.z() = 1.5;
  const auto voxels = true_surface_voxels(*scene_, {camera}, SE3d(), Vec3d(-20, -20, -5), 0.01, 2.5);
  ASSERT_TRUE(voxels.ok()) << voxels.status();
  std::int64_t floor = 0;
  for (const SurfaceVoxel& v : *voxels) {
    const voxel::VoxelIndex i = voxel::unpack(v.key);
    floor += i.z() == 500 ? 1 : 0;  // z = 0 lies in voxel (0 - -5) / 0.01 = 500
    EXPECT_LE(v.distance_m, 2.5f + 1e-4f);
  }
  // Brute force: the 1 cm floor cells whose centre is within reach and seen from the camera.
  std::int64_t brute = 0;
  for (int i = -250; i < 250; ++i) {
    for (int j = -250; j < 250; ++j) {
      const Vec3d c(std::floor(camera.x() / 0.01) * 0.01 + (i + 0.5) * 0.01,
                    std::floor(camera.y() / 0.01) * 0.01 + (j + 0.5) * 0.01, 0.0);
      if ((c - camera).norm() > 2.5) continue;
      brute += scene_->occluded(camera.cast<float>(), Vec3d(c + 1e-3 * Vec3d::UnitZ()).cast<float>(),
                                Visibility::kCamera)
                   ? 0
                   : 1;
    }
  }
  const double disk = M_PI * (2.5 * 2.5 - 1.5 * 1.5) / 1e-4;
  ::testing::Test::RecordProperty("floor_voxels", static_cast<int>(floor));
  EXPECT_GT(brute, 0.3 * disk);
  EXPECT_NEAR(static_cast<double>(floor), static_cast<double>(brute), 0.01 * static_cast<double>(brute));
  EXPECT_FALSE(true_surface_voxels(*scene_, {}, SE3d(), Vec3d::Zero(), 0.01, 2.5).ok());
}

}  // namespace
}  // namespace mrvs::sim::test
