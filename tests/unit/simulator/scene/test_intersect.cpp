// Scene::intersect() and occluded() against a brute-force test of every face.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "scene_test_util.h"

namespace mrvs::sim {
namespace {

using test::brute_force;
using test::RefHit;

/// Tolerance on a hit distance / hit point: 1e-4 m for ordinary rays, looser only as the
/// problem itself gets ill-conditioned (float inputs, |n . d| -> 0).
double tolerance(double t, double cos_incidence) {
  return 1e-4 + 4e-7 * (1.0 + t) / std::max(cos_incidence, 1e-9);
}

struct Stats {
  int rays = 0;
  int hits = 0;
  int ambiguous = 0;  ///< edge or grazing ties where the two casters may pick different faces
  int failures = 0;
  double max_dt = 0.0;
  double max_uv = 0.0;
};

/// Compares one ray; prints the first few failures.
void compare(const Scene& scene, const Vec3f& o, const Vec3f& d, float max_t, Visibility who, Stats& st) {
  const std::vector<Face>& faces = scene.faces();
  const std::optional<Hit> hit = scene.intersect(o, d, max_t, who);
  const RefHit ref = brute_force(faces, o, d, max_t, who);
  ++st.rays;
  const Vec3d od = o.cast<double>();
  const Vec3d dd = d.cast<double>();
  const auto near_edge = [&](int face, double t) {
    return test::edge_distance(faces[face], od + t * dd) < 1e-3 ||
           std::abs(faces[face].normal.dot(dd)) < 1e-3;
  };
  bool ok = true;
  if (hit.has_value() != (ref.face >= 0)) {
    const bool amb = hit ? near_edge(hit->face, hit->distance) : near_edge(ref.face, ref.t);
    st.ambiguous += amb ? 1 : 0;
    ok = amb;
  } else if (hit) {
    ++st.hits;
    const double dt = std::abs(hit->distance - ref.t);
    const double tol = tolerance(ref.t, ref.cos_incidence);
    if (hit->face != ref.face) {
      const bool amb = near_edge(hit->face, hit->distance) && near_edge(ref.face, ref.t);
      st.ambiguous += amb ? 1 : 0;
      ok = amb && dt <= tol + 1e-3;
    } else {
      const Face& f = faces[hit->face];
      const Vec3d p_uv = f.origin + hit->u * f.axis_u + hit->v * f.axis_v;
      const double duv = (p_uv - (od + ref.t * dd)).norm();
      st.max_dt = std::max(st.max_dt, dt);
      st.max_uv = std::max(st.max_uv, duv);
      ok = dt <= tol && duv <= tol && hit->u >= 0.0f && hit->u <= f.size_u + 1e-5 && hit->v >= 0.0f &&
           hit->v <= f.size_v + 1e-5;
    }
  }
  if (!ok && ++st.failures <= 5) {
    ADD_FAILURE() << "ray o = (" << o.transpose() << ") d = (" << d.transpose() << "): caster "
                  << (hit ? hit->face : -1) << " t = " << (hit ? hit->distance : -1.0f) << ", reference "
                  << ref.face << " t = " << ref.t;
  }
}

void expect_agreement(const Stats& st, const char* what) {
  std::printf("%s: %d rays, %d hits, %d ambiguous, max |dt| %.3g m, max uv error %.3g m\n", what, st.rays,
              st.hits, st.ambiguous, st.max_dt, st.max_uv);
  EXPECT_EQ(st.failures, 0) << what;
  EXPECT_LE(st.ambiguous, st.rays / 1000 + 1) << what;
}

Scene indoor_scene(int unmapped = 0, int removed = 0) {
  SceneOptions o;
  o.unmapped_objects = unmapped;
  o.removed_objects = removed;
  o.texel_size_m = 0.02;  // geometry tests do not need fine textures
  auto scene = make_scene(SceneProfile::kIndoor, o, test::indoor_path(), 7);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return std::move(scene).value();
}

/// A random point in the room that is not inside any box.
std::optional<Vec3f> free_point(const Scene& scene, const CounterRng& rng, std::uint64_t i) {
  const auto boxes = test::faces_by_object(scene.faces());
  const Eigen::AlignedBox3d room = scene.bounds();
  const Vec3d lo = room.min() + Vec3d::Constant(0.01);
  const Vec3d hi = room.max() - Vec3d::Constant(0.01);
  const Vec3d p(rng.uniform(lo.x(), hi.x(), i, 10), rng.uniform(lo.y(), hi.y(), i, 11),
                rng.uniform(lo.z(), hi.z(), i, 12));
  for (const auto& [id, faces] : boxes) {
    if (test::inside_box(faces, p, 1e-3)) return std::nullopt;
  }
  return p.cast<float>();
}

TEST(SceneIntersect, IndoorRandomRaysMatchBruteForce) {
  const Scene scene = indoor_scene();
  const CounterRng rng(1, Stream::kScene);
  Stats st;
  for (std::uint64_t i = 0; st.rays < 100000; ++i) {
    const auto o = free_point(scene, rng, i);
    if (o) compare(scene, *o, test::random_direction(rng, i), 100.0f, Visibility::kCamera, st);
  }
  expect_agreement(st, "indoor random");
  EXPECT_GT(st.hits, 99000);  // inside a closed room every ray hits
}

TEST(SceneIntersect, IndoorAxisRaysMatchBruteForce) {
  const Scene scene = indoor_scene();
  const CounterRng rng(2, Stream::kScene);
  Stats st;
  for (std::uint64_t i = 0; st.rays < 18000; ++i) {
    const auto o = free_point(scene, rng, i);
    if (!o) continue;
    for (int a = 0; a < 3; ++a) {
      for (const float s : {1.0f, -1.0f}) {
        compare(scene, *o, Vec3f::Unit(a) * s, 100.0f, Visibility::kCamera, st);
      }
    }
  }
  expect_agreement(st, "indoor axis");
}

/// Rays skimming a face at grazing angles (and exactly parallel to it).
TEST(SceneIntersect, IndoorGrazingRaysMatchBruteForce) {
  const Scene scene = indoor_scene();
  const std::vector<Face>& faces = scene.faces();
  const CounterRng rng(3, Stream::kScene);
  Stats st;
  for (std::uint64_t i = 0; st.rays < 20000; ++i) {
    const Face& f = faces[rng.bits(i, 20) % faces.size()];
    const Vec3d p = f.origin + rng.uniform(0.0, f.size_u, i, 21) * f.axis_u +
                    rng.uniform(0.0, f.size_v, i, 22) * f.axis_v;
    const double a = rng.uniform(0.0, 2.0 * M_PI, i, 23);
    const Vec3d tangent = std::cos(a) * f.axis_u + std::sin(a) * f.axis_v;
    const double h = rng.uniform(1e-3, 0.05, i, 24);
    const double back = rng.uniform(0.1, 3.0, i, 25);
    const bool parallel = rng.uniform(i, 26) < 0.2;
    const Vec3d o = p + h * f.normal - back * tangent;
    const Vec3d d =
        parallel ? tangent : (back * tangent - (h + rng.uniform(-1e-3, 1e-3, i, 27)) * f.normal).normalized();
    if (!scene.bounds().contains(o)) continue;
    bool inside = false;
    for (const auto& [id, bf] : test::faces_by_object(faces))
      inside = inside || test::inside_box(bf, o, 1e-4);
    if (!inside) compare(scene, o.cast<float>(), d.cast<float>(), 100.0f, Visibility::kCamera, st);
  }
  expect_agreement(st, "indoor grazing");
}

TEST(SceneIntersect, VisibilityFiltersRemovedAndUnmappedObjects) {
  const Scene scene = indoor_scene(3, 3);
  const std::vector<Face>& faces = scene.faces();
  int unmapped_boxes = 0;
  int removed_boxes = 0;
  for (const auto& [id, bf] : test::faces_by_object(faces)) {
    unmapped_boxes += bf[0].in_map ? 0 : 1;
    removed_boxes += bf[0].rendered ? 0 : 1;
    for (const Face& f : bf) {
      EXPECT_EQ(f.in_map, bf[0].in_map);
      EXPECT_EQ(f.rendered, bf[0].rendered);
      EXPECT_TRUE(f.in_map || f.rendered) << "a box both unmapped and removed";
    }
  }
  EXPECT_EQ(unmapped_boxes, 3);
  EXPECT_EQ(removed_boxes, 3);
  const CounterRng rng(4, Stream::kScene);
  Stats cam;
  Stats survey;
  int camera_on_removed = 0, camera_on_unmapped = 0, survey_on_removed = 0, survey_on_unmapped = 0;
  for (std::uint64_t i = 0; cam.rays < 30000; ++i) {
    const auto o = free_point(scene, rng, i);
    if (!o) continue;
    const Vec3f d = test::random_direction(rng, i);
    compare(scene, *o, d, 100.0f, Visibility::kCamera, cam);
    compare(scene, *o, d, 100.0f, Visibility::kSurvey, survey);
    if (const auto h = scene.intersect(*o, d, 100.0f, Visibility::kCamera)) {
      camera_on_removed += faces[h->face].rendered ? 0 : 1;
      camera_on_unmapped += faces[h->face].in_map ? 0 : 1;
    }
    if (const auto h = scene.intersect(*o, d, 100.0f, Visibility::kSurvey)) {
      survey_on_removed += faces[h->face].rendered ? 0 : 1;
      survey_on_unmapped += faces[h->face].in_map ? 0 : 1;
    }
  }
  expect_agreement(cam, "camera visibility");
  expect_agreement(survey, "survey visibility");
  EXPECT_EQ(camera_on_removed, 0);
  EXPECT_EQ(survey_on_unmapped, 0);
  EXPECT_GT(camera_on_unmapped, 0);
  EXPECT_GT(survey_on_removed, 0);
}

TEST(SceneIntersect, OccludedAgreesWithBruteForce) {
  const Scene scene = indoor_scene(2, 2);
  const std::vector<Face>& faces = scene.faces();
  const CounterRng rng(5, Stream::kScene);
  int checked = 0, blocked = 0, mismatches = 0, on_face_blocked = 0, on_face_clear = 0;
  for (std::uint64_t i = 0; checked < 20000; ++i) {
    const auto a = free_point(scene, rng, 2 * i);
    const auto b = free_point(scene, rng, 2 * i + 1);
    if (!a || !b) continue;
    ++checked;
    for (const Visibility who : {Visibility::kCamera, Visibility::kSurvey}) {
      const Vec3f d = *b - *a;
      const float len = d.norm();
      // occluded() ignores hits within 1 mm (+1e-4 of the length at the far end).
      const RefHit ref = brute_force(faces, *a, d / len, len - 1e-3 - 1e-4 * len, who, 1e-3);
      const bool occ = scene.occluded(*a, *b, who);
      blocked += occ ? 1 : 0;
      mismatches += occ != (ref.face >= 0) ? 1 : 0;
      // The segment from `a` to its own first hit point is never occluded by that face.
      if (const auto h = scene.intersect(*a, d / len, 100.0f, who)) {
        const bool self = scene.occluded(*a, *a + h->distance * d / len, who);
        (self ? on_face_blocked : on_face_clear) += 1;
      }
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(blocked, 1000);
  EXPECT_EQ(on_face_blocked, 0);
  EXPECT_GT(on_face_clear, 30000);
}

TEST(SceneIntersect, OutdoorStreetRaysMatchBruteForce) {
  const std::vector<Vec3d> route = test::car_route();
  SceneOptions o;
  o.unmapped_objects = 2;
  o.removed_objects = 2;
  auto scene = make_scene(SceneProfile::kOutdoor, o, route, 11);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const CounterRng rng(6, Stream::kScene);
  Stats st;
  Stats survey;
  for (std::uint64_t i = 0; st.rays < 100000; ++i) {
    const Vec3d& c = route[rng.bits(i, 30) % route.size()];
    const Vec3f origin = (c + Vec3d(rng.uniform(-5.0, 5.0, i, 31), rng.uniform(-5.0, 5.0, i, 32),
                                    rng.uniform(-1.4, 1.5, i, 33)))
                             .cast<float>();
    const Vec3f d = test::random_direction(rng, i);
    compare(*scene, origin, d, 300.0f, Visibility::kCamera, st);
    if (i % 4 == 0) compare(*scene, origin, d, 300.0f, Visibility::kSurvey, survey);
  }
  expect_agreement(st, "outdoor random");
  expect_agreement(survey, "outdoor survey");
  EXPECT_GT(st.hits, 50000);
}

TEST(SceneIntersect, OutdoorAxisRaysMatchBruteForce) {
  const std::vector<Vec3d> route = test::car_route();
  auto scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 12);
  ASSERT_TRUE(scene.ok()) << scene.status();
  Stats st;
  for (std::size_t i = 0; i < route.size(); i += 2) {
    for (int a = 0; a < 3; ++a) {
      for (const float s : {1.0f, -1.0f})
        compare(*scene, route[i].cast<float>(), Vec3f::Unit(a) * s, 300.0f, Visibility::kCamera, st);
    }
  }
  expect_agreement(st, "outdoor axis");
}

TEST(SceneIntersect, DegenerateQueries) {
  const Scene scene = indoor_scene();
  const Vec3f o = test::indoor_path()[0].cast<float>();
  EXPECT_FALSE(scene.intersect(o, Vec3f::UnitX(), 0.0f).has_value());
  EXPECT_FALSE(scene.intersect(o, Vec3f::UnitX(), -1.0f).has_value());
  EXPECT_FALSE(scene.occluded(o, o, Visibility::kCamera));
  // The maximum distance is inclusive and limits the hit.
  const RefHit ref = brute_force(scene.faces(), o, -Vec3f::UnitZ(), 100.0, Visibility::kCamera);
  const auto h = scene.intersect(o, -Vec3f::UnitZ(), 100.0f);
  ASSERT_TRUE(h.has_value());
  EXPECT_EQ(h->face, ref.face);
  EXPECT_NEAR(h->distance, ref.t, 1e-5);
  EXPECT_TRUE(scene.intersect(o, -Vec3f::UnitZ(), h->distance).has_value());
  EXPECT_FALSE(scene.intersect(o, -Vec3f::UnitZ(), 0.99f * h->distance).has_value());
}

}  // namespace
}  // namespace mrvs::sim
