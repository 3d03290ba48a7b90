// Scene layout: keep-clear, overlap rule, room growth, street canyon, option errors, YAML.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/shared_data.h"
#include "scene_test_util.h"

namespace mrvs::sim {
namespace {

SceneOptions fast_options() {
  SceneOptions o;
  o.texel_size_m = 0.02;
  return o;
}

struct BoxFrame {
  Vec3d corner, ex, ey, ez;  ///< box = corner + [0,1]^3 spanned by ex, ey, ez
  double volume() const { return ex.norm() * ey.norm() * ez.norm(); }
};

/// Box frame rebuilt from the faces (order -x, +x, -y, +y, -z, +z).
BoxFrame frame_of(const std::vector<Face>& f) {
  const Face& bottom = f[4];
  return BoxFrame{bottom.origin, bottom.axis_v * bottom.size_v, bottom.axis_u * bottom.size_u,
                  Vec3d::UnitZ() * f[0].size_v};
}

Eigen::AlignedBox3d aabb_of(const BoxFrame& b) {
  Eigen::AlignedBox3d box;
  for (int k = 0; k < 8; ++k)
    box.extend(b.corner + (k & 1) * b.ex + ((k >> 1) & 1) * b.ey + ((k >> 2) & 1) * b.ez);
  return box;
}

/// Monte-Carlo overlap volume: 100k uniform points in box a tested against box b.
double sampled_overlap(const BoxFrame& a, const std::vector<Face>& b) {
  constexpr int kN = 100000;
  const CounterRng rng(99, Stream::kScene);
  int inside = 0;
  for (int i = 0; i < kN; ++i) {
    const Vec3d p = a.corner + rng.uniform(i, 1) * a.ex + rng.uniform(i, 2) * a.ey + rng.uniform(i, 3) * a.ez;
    inside += test::inside_box(b, p) ? 1 : 0;
  }
  return a.volume() * inside / kN;
}

void expect_layout_rules(const Scene& scene, const std::vector<Vec3d>& keep_clear, double clearance) {
  const auto boxes = test::faces_by_object(scene.faces());
  const Eigen::AlignedBox3d bounds = scene.bounds();
  for (const auto& [id, faces] : boxes) {
    ASSERT_EQ(faces.size(), 6u);
    double nearest = 1e9;
    for (const Vec3d& p : keep_clear) nearest = std::min(nearest, test::box_distance(faces, p));
    EXPECT_GE(nearest, clearance - 1e-6) << "box " << id;
    for (const Face& f : faces) {
      for (const Vec3d& c : {f.origin, Vec3d(f.origin + f.size_u * f.axis_u + f.size_v * f.axis_v)}) {
        EXPECT_LT(bounds.exteriorDistance(c), 1e-5) << "box " << id;
      }
    }
  }
  int overlapping_pairs = 0;
  for (auto a = boxes.begin(); a != boxes.end(); ++a) {
    for (auto b = std::next(a); b != boxes.end(); ++b) {
      const BoxFrame fa = frame_of(a->second);
      const BoxFrame fb = frame_of(b->second);
      if (!(aabb_of(fa).intersection(aabb_of(fb)).sizes().minCoeff() > 0.0)) continue;
      const bool a_small = fa.volume() <= fb.volume();
      const double small = std::min(fa.volume(), fb.volume());
      const double overlap = a_small ? sampled_overlap(fa, b->second) : sampled_overlap(fb, a->second);
      overlapping_pairs += overlap > 0.0 ? 1 : 0;
      // 10 % rule; the Monte-Carlo estimate has sigma <= 0.001 of the smaller volume.
      EXPECT_LE(overlap, 0.104 * small) << "boxes " << a->first << ", " << b->first;
    }
  }
  std::printf("%zu boxes, %d overlapping pairs\n", boxes.size(), overlapping_pairs);
}

TEST(SceneLayout, IndoorBoxesKeepClearAndDoNotOverlap) {
  const std::vector<Vec3d> path = test::indoor_path();
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    auto scene = make_scene(SceneProfile::kIndoor, fast_options(), path, seed);
    ASSERT_TRUE(scene.ok()) << scene.status();
    EXPECT_EQ(scene->faces().size(), 6u + 6u * 20u);
    EXPECT_EQ(scene->profile(), SceneProfile::kIndoor);
    expect_layout_rules(*scene, path, 0.6);
  }
}

TEST(SceneLayout, RoomIsTheV1RoomGrownAroundTheKeepClearPoints) {
  auto empty = make_scene(SceneProfile::kIndoor, fast_options(), {}, 1);
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_TRUE(empty->bounds().min().isApprox(Vec3d(-4.73, -3.49, 0.0), 1e-6));
  EXPECT_TRUE(empty->bounds().max().isApprox(Vec3d(4.10, 5.16, 4.13), 1e-6));
  // A V2-like path reaching x = -3.8 and z = 2.9 pushes the walls out by the 1.5 m margin.
  const std::vector<Vec3d> path = {Vec3d(-3.8, 0.0, 1.0), Vec3d(2.3, 3.4, 2.9), Vec3d(0.0, -2.1, 0.6)};
  auto grown = make_scene(SceneProfile::kIndoor, fast_options(), path, 1);
  ASSERT_TRUE(grown.ok()) << grown.status();
  EXPECT_NEAR(grown->bounds().min().x(), -5.3, 1e-6);
  EXPECT_NEAR(grown->bounds().max().z(), 4.4, 1e-6);
  EXPECT_NEAR(grown->bounds().min().z(), 0.0, 1e-9);
  EXPECT_NEAR(grown->bounds().max().x(), 4.10, 1e-6);
}

TEST(SceneLayout, RealV1TrajectoryAndCameraCentres) {
  auto traj = io::read_trajectory(mrvs::test::euroc_groundtruth_file("V1_01_easy.txt"));
  ASSERT_TRUE(traj.ok()) << traj.status();
  std::vector<Vec3d> keep;
  for (std::size_t i = 0; i < traj->size(); i += 10) {  // 0.05 s at 200 Hz
    const SE3d& T = (*traj)[i].T_w_b;
    keep.push_back(T.translation());
    for (const double y : {-0.065, 0.045}) keep.push_back(T * Vec3d(-0.02, y, 0.01));  // cam0 / cam1 centres
  }
  SceneOptions o = fast_options();
  o.num_boxes = 25;
  auto scene = make_scene(SceneProfile::kIndoor, o, keep, 5);
  ASSERT_TRUE(scene.ok()) << scene.status();
  expect_layout_rules(*scene, keep, 0.6);
}

TEST(SceneLayout, BoxKindsAndRotations) {
  SceneOptions o = fast_options();
  o.rotated_fraction = 1.0;
  auto scene = make_scene(SceneProfile::kIndoor, o, test::indoor_path(), 9);
  ASSERT_TRUE(scene.ok());
  const YAML::Node y = YAML::Load(scene->to_yaml());
  int rotated = 0, slabs = 0, floor = 0, panels = 0, stacked = 0;
  for (const auto& b : y["boxes"]) {
    const std::string kind = b["kind"].as<std::string>();
    rotated += std::abs(b["yaw_rad"].as<double>()) > 1e-6 ? 1 : 0;
    slabs += kind == "wall_slab";
    floor += kind == "floor";
    panels += kind == "wall_panel";
    stacked += kind == "stacked";
  }
  EXPECT_EQ(slabs, 2);
  EXPECT_GT(floor, panels + stacked);  // mostly on the floor
  EXPECT_GT(rotated, 5);
}

/// Street rules: buildings >= 10 m and sidewalks >= 6 m from the route (horizontally),
/// heights 8-45 m and 0.15 m, enough of both.
void expect_street_rules(const Scene& scene, const std::vector<Vec3d>& route) {
  expect_layout_rules(scene, route, 0.6);
  const YAML::Node y = YAML::Load(scene.to_yaml());
  int buildings = 0;
  int sidewalks = 0;
  for (const auto& b : y["boxes"]) {
    const std::string kind = b["kind"].as<std::string>();
    const Vec3d lo(b["lo"][0].as<double>(), b["lo"][1].as<double>(), b["lo"][2].as<double>());
    const Vec3d hi(b["hi"][0].as<double>(), b["hi"][1].as<double>(), b["hi"][2].as<double>());
    double nearest = 1e9;
    for (const Vec3d& p : route) {
      nearest = std::min(
          nearest, (lo.head<2>() - p.head<2>()).cwiseMax(p.head<2>() - hi.head<2>()).cwiseMax(0.0).norm());
    }
    if (kind == "building") {
      ++buildings;
      EXPECT_GE(nearest, 10.0 - 1e-6);
      EXPECT_GE(hi.z() - lo.z(), 8.0 - 1e-6);
      EXPECT_LE(hi.z() - lo.z(), 45.0 + 1e-6);
    } else {
      ++sidewalks;
      EXPECT_EQ(kind, "sidewalk");
      EXPECT_GE(nearest, 6.0 - 1e-6);
      EXPECT_NEAR(hi.z(), 0.15, 1e-6);
    }
  }
  EXPECT_GE(buildings, 20);
  EXPECT_GE(sidewalks, 40);
  std::printf("street canyon: %d buildings, %d sidewalk pieces, %zu faces\n", buildings, sidewalks,
              scene.faces().size());
}

TEST(SceneLayout, StreetCanyonAlongTheRoute) {
  const std::vector<Vec3d> route = test::car_route();
  auto legs = infer_street_legs(route);
  ASSERT_TRUE(legs.ok()) << legs.status();
  ASSERT_EQ(legs->size(), 2u);
  EXPECT_NEAR((*legs)[0].start.x(), 0.0, 1e-9);
  EXPECT_NEAR((*legs)[0].start.y(), 0.0, 1e-6);
  EXPECT_NEAR((*legs)[0].end.x(), 180.0, 1.5);
  EXPECT_NEAR((*legs)[1].start.x(), 198.0, 1e-3);
  EXPECT_NEAR((*legs)[1].start.y(), -18.0, 1.5);
  EXPECT_NEAR((*legs)[1].end.y(), -138.0, 1e-6);
  auto scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 3);
  ASSERT_TRUE(scene.ok()) << scene.status();
  EXPECT_EQ(scene->profile(), SceneProfile::kOutdoor);
  expect_street_rules(*scene, route);
  // The road surface under the route is the ground face at z = 0.
  for (std::size_t i = 0; i < route.size(); i += 25) {
    const auto h = scene->intersect(route[i].cast<float>(), -Vec3f::UnitZ(), 10.0f);
    ASSERT_TRUE(h.has_value());
    EXPECT_EQ(h->face, 0);
    EXPECT_NEAR(h->distance, 1.7f, 1e-5);
  }
}

TEST(SceneLayout, StreetCanyonAlongAWanderingRoute) {
  // The car wanders +-0.4 m around its lane line (a spline never follows the legs exactly).
  std::vector<Vec3d> route = test::car_route();
  for (std::size_t i = 0; i < route.size(); ++i) {
    const double w = 0.4 * std::sin(0.05 * static_cast<double>(i));
    route[i] += std::abs(route[i].y()) < 1e-9 ? Vec3d(0, w, 0) : Vec3d(w, 0, 0);
  }
  auto legs = infer_street_legs(route);
  ASSERT_TRUE(legs.ok()) << legs.status();
  EXPECT_EQ(legs->size(), 2u);
  auto scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 3);
  ASSERT_TRUE(scene.ok()) << scene.status();
  expect_street_rules(*scene, route);
}

TEST(SceneLayout, OutdoorSkyForUpwardRays) {
  const std::vector<Vec3d> route = test::car_route();
  auto scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 4);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const double top = scene->bounds().max().z();
  EXPECT_GE(top, 8.0);
  EXPECT_LE(top, 45.0 + 1e-6);
  const CounterRng rng(8, Stream::kScene);
  double low_sum = 0.0, high_sum = 0.0;
  int low_n = 0, high_n = 0;
  for (std::uint64_t i = 0; i < 5000; ++i) {
    const Vec3f o = route[rng.bits(i, 1) % route.size()].cast<float>();
    EXPECT_FALSE(scene->intersect(o, Vec3f::UnitZ(), 300.0f).has_value());
    Vec3f d = test::random_direction(rng, i);
    d.z() = std::abs(d.z());
    // Above the tallest building and pointing up: always sky.
    EXPECT_FALSE(scene->intersect(o + Vec3f(0, 0, static_cast<float>(top)), d, 300.0f).has_value());
    const float sky = scene->background(d);
    EXPECT_GE(sky, 200.0f / 255.0f - 0.035f);
    EXPECT_LE(sky, 240.0f / 255.0f + 0.035f);
    (d.z() < 0.2f ? low_sum : high_sum) += sky;
    (d.z() < 0.2f ? low_n : high_n) += 1;
  }
  EXPECT_LT(low_sum / low_n + 0.05, high_sum / high_n);  // brighter towards the zenith
}

TEST(SceneLayout, ExplicitLegsMatchInferredLegs) {
  const std::vector<Vec3d> route = test::car_route();
  auto legs = infer_street_legs(route);
  ASSERT_TRUE(legs.ok());
  auto a = make_street_scene(SceneOptions{}, *legs, route, 21);
  auto b = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 21);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->to_yaml(), b->to_yaml());
  // Legs alone (no samples) also work: the legs and arcs themselves are kept clear.
  auto c = make_street_scene(SceneOptions{}, *legs, {}, 21);
  ASSERT_TRUE(c.ok()) << c.status();
}

TEST(SceneLayout, EmptyRoomAndStraightStreet) {
  SceneOptions o = fast_options();
  o.num_boxes = 0;
  auto room = make_scene(SceneProfile::kIndoor, o, {}, 1);
  ASSERT_TRUE(room.ok()) << room.status();
  EXPECT_EQ(room->faces().size(), 6u);
  const auto h = room->intersect(Vec3f(0, 0, 1), Vec3f::UnitX(), 100.0f);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->face, 1);  // x-hi wall
  EXPECT_NEAR(h->distance, 4.10f, 1e-5);
  EXPECT_NEAR(h->u, 5.16f, 1e-5);  // x-hi wall: u runs along -y from y = 5.16
  EXPECT_NEAR(h->v, 1.0f, 1e-5);
  // One straight leg: a canyon without turns.
  auto street = make_street_scene(SceneOptions{}, {StreetLeg{Vec2d(0, 0), Vec2d(0, 150)}}, {}, 2);
  ASSERT_TRUE(street.ok()) << street.status();
  EXPECT_GT(street->faces().size(), 60u);
  expect_layout_rules(*street, {Vec3d(0, 0, 1.7), Vec3d(0, 75, 1.7), Vec3d(0, 150, 1.7)}, 6.9);
}

TEST(SceneLayout, ImpossibleOptionsAreErrors) {
  const std::vector<Vec3d> path = test::indoor_path();
  const auto fails = [&](SceneOptions o, SceneProfile profile = SceneProfile::kIndoor) {
    auto s = make_scene(profile, o, profile == SceneProfile::kIndoor ? path : test::car_route(), 1);
    if (s.ok()) return false;
    std::printf("  expected error: %s\n", std::string(s.status().message()).c_str());
    return true;
  };
  SceneOptions o = fast_options();
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.num_boxes = -1;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.texel_size_m = -0.004;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.texel_size_m = 0.0;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.clearance_m = -0.1;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.room_margin_m = -1.0;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.textureless_fraction = 1.5;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.textureless_fraction = -0.1;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.textureless_fraction = std::nan("");
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.rotated_fraction = 2.0;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.unmapped_objects = -1;
    return x;
  }()));
  EXPECT_TRUE(fails([&] {
    auto x = o;
    x.unmapped_objects = 12;
    x.removed_objects = 9;
    return x;
  }()));
  EXPECT_TRUE(fails(
      [&] {
        auto x = o;
        x.unmapped_objects = 500;
        return x;
      }(),
      SceneProfile::kOutdoor));
  // Keep-clear points everywhere: no room for boxes.
  std::vector<Vec3d> dense;
  for (double x = -4.5; x < 4.0; x += 0.5) {
    for (double y = -3.3; y < 5.0; y += 0.5) {
      for (double z = 0.2; z < 4.0; z += 0.5) dense.emplace_back(x, y, z);
    }
  }
  SceneOptions tight = fast_options();
  tight.room_margin_m = 0.0;
  EXPECT_FALSE(make_scene(SceneProfile::kIndoor, tight, dense, 1).ok());
  EXPECT_FALSE(make_scene(SceneProfile::kIndoor, o, {Vec3d(0, 0, std::nan(""))}, 1).ok());
  // Outdoor needs a route of perpendicular axis-aligned legs.
  EXPECT_FALSE(make_scene(SceneProfile::kOutdoor, o, {}, 1).ok());
  std::vector<Vec3d> diagonal;
  for (int k = 0; k < 200; ++k) diagonal.emplace_back(k, k, 1.7);
  EXPECT_FALSE(make_scene(SceneProfile::kOutdoor, o, diagonal, 1).ok());
  EXPECT_FALSE(make_street_scene(
                   o, {StreetLeg{Vec2d(0, 0), Vec2d(100, 0)}, StreetLeg{Vec2d(120, 5), Vec2d(200, 5)}}, {}, 1)
                   .ok());
  EXPECT_FALSE(make_street_scene(o, {StreetLeg{Vec2d(0, 0), Vec2d(100, 30)}}, {}, 1).ok());
  EXPECT_FALSE(make_street_scene(o, {}, {}, 1).ok());
}

TEST(SceneLayout, YamlIsDeterministicAndComplete) {
  const std::vector<Vec3d> path = test::indoor_path();
  SceneOptions o = fast_options();
  o.unmapped_objects = 2;
  o.removed_objects = 1;
  o.textureless_fraction = 0.25;
  auto a = make_scene(SceneProfile::kIndoor, o, path, 31);
  auto b = make_scene(SceneProfile::kIndoor, o, path, 31);
  auto c = make_scene(SceneProfile::kIndoor, o, path, 32);
  ASSERT_TRUE(a.ok() && b.ok() && c.ok());
  const std::string ya = a->to_yaml();
  EXPECT_EQ(ya, b->to_yaml());
  EXPECT_NE(ya, c->to_yaml());
  const YAML::Node y = YAML::Load(ya);
  EXPECT_EQ(y["profile"].as<std::string>(), "indoor");
  EXPECT_EQ(y["seed"].as<std::uint64_t>(), 31u);
  EXPECT_DOUBLE_EQ(y["texel_size_m"].as<double>(), 0.02);
  EXPECT_EQ(y["boxes"].size(), 20u);
  EXPECT_EQ(y["faces"].size(), a->faces().size());
  EXPECT_EQ(y["counts"]["unmapped"].as<int>(), 2);
  EXPECT_EQ(y["counts"]["removed"].as<int>(), 1);
  EXPECT_EQ(y["counts"]["textureless_faces"].as<int>(),
            static_cast<int>(std::lround(0.25 * a->faces().size())));
  EXPECT_NEAR(y["room"]["min"][0].as<double>(), a->bounds().min().x(), 1e-6);
  // Every box's lo/hi/yaw reproduce its faces.
  for (const auto& node : y["boxes"]) {
    const int first = node["first_face"].as<int>();
    const Face& bottom = a->faces()[first + 4];
    const Vec3d lo(node["lo"][0].as<double>(), node["lo"][1].as<double>(), node["lo"][2].as<double>());
    const Vec3d hi(node["hi"][0].as<double>(), node["hi"][1].as<double>(), node["hi"][2].as<double>());
    const double yaw = node["yaw_rad"].as<double>();
    const Vec3d centre = 0.5 * (lo + hi);
    const Vec3d h = 0.5 * (hi - lo);
    const Vec3d ex(std::cos(yaw), std::sin(yaw), 0.0);
    const Vec3d ey(-std::sin(yaw), std::cos(yaw), 0.0);
    EXPECT_LT((bottom.origin - (centre - h.x() * ex - h.y() * ey - h.z() * Vec3d::UnitZ())).norm(), 1e-5);
    EXPECT_NEAR(bottom.size_v, 2.0 * h.x(), 1e-6);
    EXPECT_NEAR(bottom.size_u, 2.0 * h.y(), 1e-6);
    EXPECT_EQ(node["in_map"].as<bool>(), bottom.in_map);
    EXPECT_EQ(node["rendered"].as<bool>(), bottom.rendered);
  }
  auto street = make_scene(SceneProfile::kOutdoor, SceneOptions{}, test::car_route(), 5);
  ASSERT_TRUE(street.ok());
  const YAML::Node ys = YAML::Load(street->to_yaml());
  EXPECT_EQ(ys["profile"].as<std::string>(), "outdoor");
  EXPECT_EQ(ys["legs"].size(), 2u);
  EXPECT_EQ(ys["arcs"].size(), 1u);
  EXPECT_NEAR(ys["arcs"][0]["radius"].as<double>(), 18.0, 1.5);
}

}  // namespace
}  // namespace mrvs::sim
