// Prior-map sampling (simulator.md sections 5 and 6 item 12) on the indoor test scene around
// the real V1_01 trajectory, at the 3 cm test spacing unless a test says otherwise.
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <map>
#include <set>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "map_test_support.h"
#include "mrvs/config/options.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/rng.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim::test {
namespace {

constexpr std::uint64_t kSeed = 11;

/// Options of the test preset with every kind of noise off.
MapOptions noiseless_test_options() {
  MapOptions o = test_map_options();
  o.noise_normal_sigma_m = 0.0;
  o.noise_tangent_sigma_m = 0.0;
  o.intensity_noise_sigma = 0.0;
  return o;
}

/// Bitwise key of a point position (maps sampled with the same seed share positions exactly).
std::tuple<float, float, float> position_key(const MapPoint& p) {
  return {p.position.x(), p.position.y(), p.position.z()};
}

std::vector<std::int64_t> points_per_face(const Scene& scene, const std::vector<MapPoint>& points) {
  std::vector<std::int64_t> count(scene.faces().size(), 0);
  for (const MapPoint& p : points) ++count[static_cast<std::size_t>(p.face)];
  return count;
}

/// True when some used station is on the front side of face `f`.
bool some_station_faces(const Face& f, const std::vector<SurveyStation>& stations) {
  for (const SurveyStation& s : stations) {
    if (s.used && (s.position_w - f.origin).dot(f.normal) > 0.0) return true;
  }
  return false;
}

class PriorMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    trajectory_ = std::make_unique<std::vector<Vec3d>>(v1_01_positions());
    ASSERT_FALSE(trajectory_->empty());
    scene_ = std::make_unique<Scene>(indoor_test_scene(*trajectory_));
    auto map = sample_prior_map(*scene_, *trajectory_, test_map_options(), kSeed);
    ASSERT_TRUE(map.ok()) << map.status();
    map_ = std::make_unique<PriorMap>(std::move(map).value());
  }
  static void TearDownTestSuite() {
    map_.reset();
    scene_.reset();
    trajectory_.reset();
  }

  static PriorMap sample(const MapOptions& options, std::uint64_t seed = kSeed) {
    auto map = sample_prior_map(*scene_, *trajectory_, options, seed);
    EXPECT_TRUE(map.ok()) << map.status();
    return map.ok() ? std::move(map).value() : PriorMap{};
  }

  static inline std::unique_ptr<std::vector<Vec3d>> trajectory_;
  static inline std::unique_ptr<Scene> scene_;
  static inline std::unique_ptr<PriorMap> map_;
};

TEST(MapOptionsTest, PresetsAreValidAndDifferWhereSection5Says) {
  EXPECT_TRUE(config::validate_options(indoor_map_options()).ok());
  EXPECT_TRUE(config::validate_options(outdoor_map_options()).ok());
  EXPECT_TRUE(config::validate_options(test_map_options()).ok());
  EXPECT_EQ(indoor_map_options(), MapOptions{});
  const MapOptions out = outdoor_map_options();
  EXPECT_DOUBLE_EQ(out.spacing_near_m, 0.10);
  EXPECT_DOUBLE_EQ(out.spacing_far_m, 0.25);
  EXPECT_DOUBLE_EQ(out.near_distance_m, 15.0);
  EXPECT_DOUBLE_EQ(out.station_spacing_m, 10.0);
  EXPECT_DOUBLE_EQ(out.station_height_m, 2.0);
  EXPECT_DOUBLE_EQ(test_map_options().spacing_near_m, 0.03);
  EXPECT_DOUBLE_EQ(test_map_options().spacing_far_m, 0.03);
}

TEST(MapOptionsTest, YamlRoundTripAndEnumNames) {
  MapOptions o;
  o.intensity_model = IntensityModel::kAffineGamma;
  o.holes_mode = HoleMode::kFaces;
  o.misalignment_deg = 0.5;
  const std::string text = config::options_to_yaml(o, "map");
  EXPECT_NE(text.find("affine_gamma"), std::string::npos) << text;
  auto doc = config::parse_yaml_string(text);
  ASSERT_TRUE(doc.ok()) << doc.status();
  auto back = config::load_options<MapOptions>(*doc, "map");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(*back, o);
}

TEST(MapOptionsTest, TileSpacingFollowsTheClampFormula) {
  const MapOptions o;  // 1 cm within 2.5 m, 2 cm far
  EXPECT_DOUBLE_EQ(tile_spacing(o, 0.0, 1.0), 0.01);
  EXPECT_DOUBLE_EQ(tile_spacing(o, 2.5, 1.0), 0.01);
  EXPECT_DOUBLE_EQ(tile_spacing(o, 3.75, 1.0), 0.015);
  EXPECT_DOUBLE_EQ(tile_spacing(o, 10.0, 1.0), 0.02);
  const MapOptions out = outdoor_map_options();
  EXPECT_DOUBLE_EQ(tile_spacing(out, 5.0, 10.0), 0.10);
  EXPECT_DOUBLE_EQ(tile_spacing(out, 30.0, 10.0), 0.20);
  EXPECT_DOUBLE_EQ(tile_spacing(out, 5.0, 25.0), 0.25);  // facade above 20 m
}

TEST(MapOptionsTest, IntensityModels) {
  MapOptions o;
  EXPECT_DOUBLE_EQ(model_intensity(o, 0.4, 0.25), 0.4);
  o.intensity_model = IntensityModel::kAlbedoCos;
  EXPECT_DOUBLE_EQ(model_intensity(o, 0.4, 0.25), 0.2);
  o.intensity_model = IntensityModel::kAffineGamma;
  o.intensity_gain = 0.8;
  o.intensity_gamma = 2.0;
  o.intensity_offset = 0.1;
  EXPECT_DOUBLE_EQ(model_intensity(o, 0.5, 0.25), 0.8 * 0.25 + 0.1);
}

TEST_F(PriorMapTest, RejectsBadInputs) {
  EXPECT_EQ(sample_prior_map(*scene_, {}, test_map_options(), 1).status().code(),
            absl::StatusCode::kInvalidArgument);
  MapOptions o = test_map_options();
  o.spacing_far_m = 0.01;  // < spacing_near_m
  EXPECT_EQ(sample_prior_map(*scene_, *trajectory_, o, 1).status().code(),
            absl::StatusCode::kInvalidArgument);
  o = test_map_options();
  o.holes_fraction = 1.5;
  const auto bad = sample_prior_map(*scene_, *trajectory_, o, 1);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("holes_fraction"), std::string::npos) << bad.status();
  o = test_map_options();
  o.spacing_near_m = o.spacing_far_m = 0.001;  // ~370 M samples
  EXPECT_EQ(sample_prior_map(*scene_, *trajectory_, o, 1).status().code(),
            absl::StatusCode::kResourceExhausted);
}

TEST_F(PriorMapTest, StationsFollowTheTrajectoryAtTheirHeight) {
  ASSERT_EQ(map_->stations.size(), 4u);
  EXPECT_EQ(map_->counts.stations_used, 4);
  for (const SurveyStation& s : map_->stations) {
    EXPECT_DOUBLE_EQ(s.position_w.z(), 1.5);
    double nearest_xy = 1e9;
    for (const Vec3d& p : *trajectory_)
      nearest_xy = std::min(nearest_xy, (p - s.position_w).head<2>().norm());
    EXPECT_LT(nearest_xy, 0.05);
  }
  // One station per 10 m of path when station_spacing_m is set.
  MapOptions o = test_map_options();
  o.station_spacing_m = 10.0;
  double length = 0.0;
  for (std::size_t i = 1; i < trajectory_->size(); ++i)
    length += ((*trajectory_)[i] - (*trajectory_)[i - 1]).norm();
  auto stations = survey_stations(*scene_, *trajectory_, o);
  ASSERT_TRUE(stations.ok());
  EXPECT_EQ(static_cast<double>(stations->size()), std::round(length / 10.0));
}

TEST_F(PriorMapTest, StationInsideABoxOrOutsideTheRoomIsUnused) {
  // Centre of box 0 (mean of its face centres).
  Vec3d centre = Vec3d::Zero();
  int n = 0;
  for (const Face& f : scene_->faces()) {
    if (f.object_id != 0) continue;
    centre += f.origin + 0.5 * f.size_u * f.axis_u + 0.5 * f.size_v * f.axis_v;
    ++n;
  }
  ASSERT_GT(n, 0);
  centre /= n;
  MapOptions o = test_map_options();
  o.num_stations = 1;
  o.station_height_m = centre.z();
  auto inside = survey_stations(*scene_, {centre}, o);
  ASSERT_TRUE(inside.ok());
  EXPECT_FALSE(inside->front().used);
  const Vec3d outside = scene_->bounds().max() + Vec3d(1.0, 1.0, 0.0);
  o.station_height_m = 1.5;
  auto out = survey_stations(*scene_, {outside}, o);
  ASSERT_TRUE(out.ok());
  EXPECT_FALSE(out->front().used);
  // A survey with only unusable stations is empty.
  auto empty = sample_prior_map(*scene_, {outside}, o, 1);
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->points.size(), 0u);
}

TEST_F(PriorMapTest, CountsAndSizeMatchSection5) {
  const MapCounts& c = map_->counts;
  EXPECT_EQ(c.points, static_cast<std::int64_t>(map_->points.size()));
  EXPECT_EQ(map_->clean_points.size(), map_->points.size());
  EXPECT_EQ(c.points, c.visible - c.hole_removed);
  EXPECT_EQ(c.hole_removed, 0);
  // simulator.md: about 340 m^2 visible of 365 m^2 -> 380 k points at 3 cm.
  std::cout << "test map: " << c.points << " points, " << c.samples << " samples, visible "
            << c.visible_area_m2 << " of " << c.in_map_area_m2 << " m^2 in " << c.tiles << " tiles\n";
  EXPECT_GT(c.points, 200'000);
  EXPECT_LT(c.points, 600'000);
  EXPECT_LT(c.visible_area_m2, c.in_map_area_m2);
}

TEST_F(PriorMapTest, CleanPointsLieOnTheirFaceAndInsideIt) {
  const std::vector<Face>& faces = scene_->faces();
  double worst_plane = 0.0;
  double worst_outside = 0.0;
  for (const MapPoint& p : map_->clean_points) {
    ASSERT_GE(p.face, 0);
    const Face& f = faces[static_cast<std::size_t>(p.face)];
    const Vec3d c = face_coordinates(f, p.position.cast<double>());
    worst_plane = std::max(worst_plane, std::abs(c.z()));
    worst_outside = std::max({worst_outside, -c.x(), c.x() - f.size_u, -c.y(), c.y() - f.size_v});
  }
  EXPECT_LT(worst_plane, 1e-4);
  EXPECT_LT(worst_outside, 1e-4);
}

TEST_F(PriorMapTest, NoisyPointsStayWithinFiveSigmaAndHaveTheSetNoise) {
  const MapOptions o = test_map_options();
  const double sigma = std::sqrt(o.noise_normal_sigma_m * o.noise_normal_sigma_m +
                                 2.0 * o.noise_tangent_sigma_m * o.noise_tangent_sigma_m);
  const std::vector<Face>& faces = scene_->faces();
  double worst = 0.0;
  double sum_n2 = 0.0;
  double sum_t2 = 0.0;
  for (std::size_t i = 0; i < map_->points.size(); ++i) {
    const MapPoint& p = map_->points[i];
    const Face& f = faces[static_cast<std::size_t>(p.face)];
    worst = std::max(worst, distance_to_face(f, p.position.cast<double>()));
    const Vec3d d = (p.position - map_->clean_points[i].position).cast<double>();
    const double dn = d.dot(f.normal.normalized());
    sum_n2 += dn * dn;
    sum_t2 += (d - dn * f.normal.normalized()).squaredNorm();
  }
  const auto n = static_cast<double>(map_->points.size());
  EXPECT_LT(worst, 5.0 * sigma);
  // Standard errors ~0.1 %; float rounding of 5 m coordinates adds ~1e-7 m.
  EXPECT_NEAR(std::sqrt(sum_n2 / n), o.noise_normal_sigma_m, 0.02 * o.noise_normal_sigma_m);
  EXPECT_NEAR(std::sqrt(sum_t2 / (2.0 * n)), o.noise_tangent_sigma_m, 0.02 * o.noise_tangent_sigma_m);
}

TEST_F(PriorMapTest, MedianNearestNeighbourSpacingAndDensityMatchTheSetSpacing) {
  const double s = test_map_options().spacing_near_m;
  const double median = median_nn_distance(map_->clean_points, 2.0 * s, every_nth(map_->clean_points, 7));
  std::cout << "median NN " << median << " m at spacing " << s << " m (ratio " << median / s << ")\n";
  // A jittered grid's median NN distance is 0.635 cell; the cell is the set spacing.
  EXPECT_NEAR(median, kJitteredGridMedianNn * s, 0.25 * kJitteredGridMedianNn * s);
  // Density on the largest faces that every station sees whole: one point per s^2 (the
  // per-tile cell count is rounded, so the cell differs from s by a few percent).
  const std::vector<std::int64_t> count = points_per_face(*scene_, map_->clean_points);
  double best_density = 0.0;
  for (const Face& f : scene_->faces()) {
    const double area = f.size_u * f.size_v;
    if (area > 4.0) best_density = std::max(best_density, count[static_cast<std::size_t>(f.id)] / area);
  }
  EXPECT_NEAR(best_density * s * s, 1.0, 0.10);
}

TEST_F(PriorMapTest, NoPointsOnFacesNoStationSeesNorOnUnmappedFaces) {
  const std::vector<std::int64_t> count = points_per_face(*scene_, map_->points);
  int unseen = 0;
  int unmapped = 0;
  for (const Face& f : scene_->faces()) {
    if (!f.in_map) {
      ++unmapped;
      EXPECT_EQ(count[static_cast<std::size_t>(f.id)], 0) << "unmapped face " << f.id;
    } else if (!some_station_faces(f, map_->stations)) {
      ++unseen;
      EXPECT_EQ(count[static_cast<std::size_t>(f.id)], 0)
          << "face " << f.id << " faces away from every station";
    }
  }
  EXPECT_GE(unmapped, 2);  // two unmapped boxes
  EXPECT_GT(unseen, 0);    // e.g. box bottoms
  // Floor under the in-map boxes: a floor point lifted by 3 mm must not be more than 2 mm
  // inside a box (Scene::occluded ignores hits within ~1.3 mm of the segment's end, so
  // samples within about a millimetre of a box's foot may be kept).
  std::map<int, std::vector<const Face*>> boxes;
  for (const Face& f : scene_->faces()) {
    if (f.object_id >= 0 && f.in_map) boxes[f.object_id].push_back(&f);
  }
  int floor_points = 0;
  for (const MapPoint& p : map_->clean_points) {
    const Face& f = scene_->faces()[static_cast<std::size_t>(p.face)];
    if (f.object_id >= 0 || f.normal.z() < 0.99 || std::abs(p.position.z()) > 1e-3) continue;
    ++floor_points;
    const Vec3d lifted = p.position.cast<double>() + Vec3d(0.0, 0.0, 3e-3);
    for (const auto& box : boxes) {
      bool inside = true;
      for (const Face* bf : box.second) inside = inside && (lifted - bf->origin).dot(bf->normal) < -2e-3;
      EXPECT_FALSE(inside) << "floor point under box " << box.first << " at " << p.position.transpose();
    }
  }
  EXPECT_GT(floor_points, 10000);
}

TEST_F(PriorMapTest, EveryClearlyVisibleSurfacePointIsCovered) {
  // Random points on in-map faces that one station sees together with their +-4 cm
  // neighbourhood must have a map point within 5 cm (3 cm cells: at most 4.3 cm away).
  const PointGrid grid(map_->clean_points, 0.05);
  const std::vector<Face>& faces = scene_->faces();
  const CounterRng rng(99, Stream::kMapSampling);
  int checked = 0;
  int missed = 0;
  for (std::uint64_t k = 0; k < 20000 && checked < 1500; ++k) {
    const Face& f = faces[static_cast<std::size_t>(rng.bits(k, 0) % faces.size())];
    if (!f.in_map || f.size_u < 0.2 || f.size_v < 0.2) continue;
    const double u = rng.uniform(0.05, f.size_u - 0.05, k, 1);
    const double v = rng.uniform(0.05, f.size_v - 0.05, k, 2);
    const Vec3d au = f.axis_u.normalized();
    const Vec3d av = f.axis_v.normalized();
    const Vec3d p = f.origin + u * au + v * av;
    bool visible = false;
    for (const SurveyStation& s : map_->stations) {
      bool all = true;
      const std::array<Vec3d, 5> neighbourhood = {p, p + 0.04 * au, p - 0.04 * au, p + 0.04 * av,
                                                  p - 0.04 * av};
      for (const Vec3d& q : neighbourhood) {
        all = all && sees(*scene_, f, s.position_w, q);
      }
      visible = visible || (s.used && all);
    }
    if (!visible) continue;
    ++checked;
    if (grid.nearest(p) > 0.05) ++missed;
  }
  EXPECT_GT(checked, 1000);
  EXPECT_LE(missed, checked / 200) << missed << " of " << checked << " visible points have no map point";
}

TEST_F(PriorMapTest, RemovedObjectsAreInTheMap) {
  const std::vector<std::int64_t> count = points_per_face(*scene_, map_->points);
  std::map<int, std::int64_t> per_removed_object;
  for (const Face& f : scene_->faces()) {
    if (!f.rendered && f.in_map) per_removed_object[f.object_id] += count[static_cast<std::size_t>(f.id)];
  }
  EXPECT_EQ(per_removed_object.size(), 2u);
  for (const auto& object : per_removed_object)
    EXPECT_GT(object.second, 50) << "removed object " << object.first;
}

TEST_F(PriorMapTest, MisalignmentIsUndoneByTheInverseTransform) {
  MapOptions o = noiseless_test_options();
  o.misalignment_deg = 0.5;
  o.misalignment_m = 0.05;
  const PriorMap map = sample(o);
  const double angle = so3::log<double>(map.T_map_world.quaternion()).norm();
  EXPECT_NEAR(angle, 0.5 * M_PI / 180.0, 1e-12);
  EXPECT_NEAR(map.T_map_world.translation().norm(), 0.05, 1e-12);
  ASSERT_EQ(map.points.size(), map_->points.size());
  const SE3d T_world_map = map.T_map_world.inverse();
  double worst = 0.0;
  double moved = 0.0;
  for (std::size_t i = 0; i < map.points.size(); ++i) {
    const Vec3d p_map = map.points[i].position.cast<double>();
    const Vec3d clean = map.clean_points[i].position.cast<double>();
    worst = std::max(worst, (T_world_map * p_map - clean).norm());
    moved = std::max(moved, (p_map - clean).norm());
    ASSERT_EQ(map.clean_points[i].position, map_->clean_points[i].position);  // same samples
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_GT(moved, 0.05);
  // Without misalignment the noiseless map is the clean map.
  const PriorMap plain = sample(noiseless_test_options());
  EXPECT_TRUE(plain.T_map_world.matrix().isIdentity(0.0));
  for (std::size_t i = 0; i < plain.points.size(); ++i) {
    ASSERT_EQ(plain.points[i].position, plain.clean_points[i].position);
  }
}

TEST_F(PriorMapTest, IntensityEqualsAlbedoWithoutNoise) {
  const PriorMap map = sample(noiseless_test_options());
  std::size_t close = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < map.points.size(); ++i) {
    const MapPoint& p = map.points[i];
    ASSERT_EQ(p.intensity, map.clean_points[i].intensity);
    const Face& f = scene_->faces()[static_cast<std::size_t>(p.face)];
    const Vec3d c = face_coordinates(f, p.position.cast<double>());
    const double albedo = scene_->albedo(p.face, static_cast<float>(c.x()), static_cast<float>(c.y()), 0.0f);
    const double e = std::abs(p.intensity - albedo);
    worst = std::max(worst, e);
    if (e < 1e-3) ++close;
  }
  // (u, v) recomputed from float positions differ by ~1e-7 m from the sampled ones.
  EXPECT_GE(static_cast<double>(close), 0.999 * static_cast<double>(map.points.size())) << "worst " << worst;
}

TEST_F(PriorMapTest, IntensityNoiseHasTheSetSigma) {
  const double sigma = test_map_options().intensity_noise_sigma;
  double sum = 0.0;
  double sum2 = 0.0;
  double n = 0.0;
  for (std::size_t i = 0; i < map_->points.size(); ++i) {
    const double clean = map_->clean_points[i].intensity;
    if (clean < 0.1 || clean > 0.9) continue;  // away from the clipping at 0 and 1
    const double d = map_->points[i].intensity - clean;
    sum += d;
    sum2 += d * d;
    n += 1.0;
  }
  ASSERT_GT(n, 10000.0);
  EXPECT_NEAR(std::sqrt(sum2 / n), sigma, 0.05 * sigma);
  EXPECT_NEAR(sum / n, 0.0, 4.0 * sigma / std::sqrt(n));
  for (const MapPoint& p : map_->points) {
    ASSERT_GE(p.intensity, 0.0f);
    ASSERT_LE(p.intensity, 1.0f);
  }
}

TEST_F(PriorMapTest, AlbedoCosAndAffineGammaIntensityModels) {
  MapOptions o = noiseless_test_options();
  o.intensity_model = IntensityModel::kAlbedoCos;
  const PriorMap cos_map = sample(o);
  o.intensity_model = IntensityModel::kAffineGamma;
  o.intensity_gain = 0.8;
  o.intensity_gamma = 0.7;
  o.intensity_offset = 0.1;
  const PriorMap affine_map = sample(o);
  ASSERT_EQ(cos_map.points.size(), map_->points.size());
  ASSERT_EQ(affine_map.points.size(), map_->points.size());
  std::size_t cos_ok = 0;
  std::size_t affine_ok = 0;
  for (std::size_t i = 0; i < cos_map.points.size(); i += 3) {
    const MapPoint& p = cos_map.clean_points[i];
    const Face& f = scene_->faces()[static_cast<std::size_t>(p.face)];
    const Vec3d c = face_coordinates(f, p.position.cast<double>());
    const double albedo = scene_->albedo(p.face, static_cast<float>(c.x()), static_cast<float>(c.y()), 0.0f);
    // albedo * sqrt(cos) for the incidence at one of the stations that see the point.
    bool match = false;
    for (const SurveyStation& s : cos_map.stations) {
      const Vec3d d = s.position_w - p.position.cast<double>();
      const double cos_inc = d.dot(f.normal.normalized()) / d.norm();
      match = match || (cos_inc > 0.0 && std::abs(p.intensity - albedo * std::sqrt(cos_inc)) < 1e-3);
    }
    cos_ok += match ? 1 : 0;
    const double expected = std::clamp(0.8 * std::pow(albedo, 0.7) + 0.1, 0.0, 1.0);
    affine_ok += std::abs(affine_map.clean_points[i].intensity - expected) < 1e-3 ? 1 : 0;
  }
  const double checked = static_cast<double>((cos_map.points.size() + 2) / 3);
  EXPECT_GE(static_cast<double>(cos_ok), 0.999 * checked);
  EXPECT_GE(static_cast<double>(affine_ok), 0.999 * checked);
}

/// Share of the points of `full` missing from `holed`; also checks that holed is a subset.
double removed_share(const PriorMap& full, const PriorMap& holed) {
  std::set<std::tuple<float, float, float>> all;
  for (const MapPoint& p : full.clean_points) all.insert(position_key(p));
  for (const MapPoint& p : holed.clean_points) EXPECT_EQ(all.count(position_key(p)), 1u);
  return 1.0 - static_cast<double>(holed.points.size()) / static_cast<double>(full.points.size());
}

TEST_F(PriorMapTest, TileHolesRemoveTheConfiguredShareOfArea) {
  MapOptions o = test_map_options();
  o.holes_fraction = 0.2;
  const PriorMap holed = sample(o);
  const double share = removed_share(*map_, holed);
  std::cout << "tile holes: removed share " << share << "\n";
  EXPECT_NEAR(share, 0.2, 0.05);
  EXPECT_NEAR(holed.counts.hole_area_m2 / holed.counts.visible_area_m2, 0.2, 0.01);
}

TEST_F(PriorMapTest, FaceHolesRemoveWholeFacesAndTheConfiguredShare) {
  MapOptions o = test_map_options();
  o.holes_mode = HoleMode::kFaces;
  o.holes_fraction = 0.2;
  const PriorMap holed = sample(o);
  const double share = removed_share(*map_, holed);
  std::cout << "face holes: removed share " << share << "\n";
  EXPECT_NEAR(share, 0.2, 0.05);
  const std::vector<std::int64_t> full_count = points_per_face(*scene_, map_->points);
  const std::vector<std::int64_t> holed_count = points_per_face(*scene_, holed.points);
  int removed_faces = 0;
  for (std::size_t i = 0; i < full_count.size(); ++i) {
    EXPECT_TRUE(holed_count[i] == 0 || holed_count[i] == full_count[i]) << "face " << i << " partly removed";
    removed_faces += (full_count[i] > 0 && holed_count[i] == 0) ? 1 : 0;
  }
  EXPECT_GT(removed_faces, 1);
}

TEST_F(PriorMapTest, SpacingIsFineNearTheTrajectoryAndCoarseFar) {
  // 2 cm up to 1.5 m from the trajectory (nothing is nearer than ~0.7 m), growing to 4 cm
  // at 3 m and beyond (about 15 % of the surface).
  MapOptions o = noiseless_test_options();
  o.spacing_near_m = 0.02;
  o.spacing_far_m = 0.04;
  o.near_distance_m = 1.5;
  const PriorMap map = sample(o);
  // A point is at most half a tile diagonal (0.36 m) from its tile centre.
  const double near_limit = o.near_distance_m - 0.36;
  const double far_limit = o.near_distance_m * o.spacing_far_m / o.spacing_near_m + 0.36;
  std::vector<Vec3d> thinned;
  for (std::size_t i = 0; i < trajectory_->size(); i += 4) thinned.push_back((*trajectory_)[i]);
  std::vector<std::size_t> near_points;
  std::vector<std::size_t> far_points;
  for (std::size_t i = 0; i < map.clean_points.size(); i += 3) {
    const Vec3d p = map.clean_points[i].position.cast<double>();
    double d = 1e9;
    for (const Vec3d& q : thinned) d = std::min(d, (q - p).norm());
    if (d < near_limit) near_points.push_back(i);
    if (d > far_limit) far_points.push_back(i);
  }
  ASSERT_GT(near_points.size(), 1000u);
  ASSERT_GT(far_points.size(), 1000u);
  const double near_nn = median_nn_distance(map.clean_points, 0.1, near_points);
  const double far_nn = median_nn_distance(map.clean_points, 0.1, far_points);
  std::cout << "near NN " << near_nn << " far NN " << far_nn << " (" << near_points.size() << ", "
            << far_points.size() << " points)\n";
  EXPECT_NEAR(far_nn / near_nn, 2.0, 0.25 * 2.0);
  EXPECT_NEAR(near_nn, kJitteredGridMedianNn * 0.02, 0.25 * kJitteredGridMedianNn * 0.02);
  EXPECT_NEAR(far_nn, kJitteredGridMedianNn * 0.04, 0.25 * kJitteredGridMedianNn * 0.04);
}

/// A small map exercising every random stream (5 cm, noise, holes, misalignment).
MapOptions all_streams_options() {
  MapOptions o = test_map_options();
  o.spacing_near_m = 0.05;
  o.spacing_far_m = 0.08;
  o.holes_fraction = 0.1;
  o.misalignment_deg = 0.3;
  o.misalignment_m = 0.02;
  return o;
}

bool same_points(const std::vector<MapPoint>& a, const std::vector<MapPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].position != b[i].position || a[i].intensity != b[i].intensity || a[i].face != b[i].face)
      return false;
  }
  return true;
}

TEST_F(PriorMapTest, SameSeedGivesIdenticalBytesAndThreadCountDoesNotMatter) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const PriorMap one = sample(all_streams_options());
  omp_set_num_threads(2);
  const PriorMap two = sample(all_streams_options());
  omp_set_num_threads(threads);
  ASSERT_GT(one.points.size(), 10000u);
  EXPECT_TRUE(same_points(one.points, two.points));
  EXPECT_TRUE(same_points(one.clean_points, two.clean_points));
  EXPECT_TRUE(one.T_map_world.matrix() == two.T_map_world.matrix());

  const mrvs::test::TempDir dir;
  ASSERT_TRUE(write_ply(dir / "a.ply", one.points, "seed 11").ok());
  ASSERT_TRUE(write_ply(dir / "b.ply", two.points, "seed 11").ok());
  const std::string bytes_a = read_bytes(dir / "a.ply");
  const std::string bytes_b = read_bytes(dir / "b.ply");
  EXPECT_EQ(bytes_a.size(), bytes_b.size());
  EXPECT_TRUE(bytes_a == bytes_b);

  const PriorMap other = sample(all_streams_options(), kSeed + 1);
  EXPECT_FALSE(same_points(one.points, other.points));
}

TEST_F(PriorMapTest, TimingOfTheDefaultIndoorMap) {
  const auto t0 = std::chrono::steady_clock::now();
  auto map = sample_prior_map(*scene_, *trajectory_, indoor_map_options(), kSeed);
  const auto t1 = std::chrono::steady_clock::now();
  ASSERT_TRUE(map.ok()) << map.status();
  const mrvs::test::TempDir dir;
  ASSERT_TRUE(write_ply(dir / "data.ply", map->points, "timing").ok());
  const auto t2 = std::chrono::steady_clock::now();
  const double sample_s = std::chrono::duration<double>(t1 - t0).count();
  const double write_s = std::chrono::duration<double>(t2 - t1).count();
  const double mb = static_cast<double>(std::filesystem::file_size(dir / "data.ply")) / 1e6;
  std::cout << "default indoor map: " << map->points.size() << " points (" << map->counts.samples
            << " samples, " << map->counts.stations_used << " stations), sampling " << sample_s
            << " s, PLY write " << write_s << " s, " << mb << " MB, " << omp_get_max_threads()
            << " threads\n";
  RecordProperty("points", static_cast<int>(map->points.size()));
  EXPECT_GT(map->points.size(), 1'000'000u);
  EXPECT_LT(sample_s, 20.0);  // generous: the machine is shared
}

}  // namespace
}  // namespace mrvs::sim::test
