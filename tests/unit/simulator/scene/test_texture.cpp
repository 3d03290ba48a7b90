// Scene::albedo(): range, continuity, mip chain, determinism, textureless faces, bake time.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

#include <gtest/gtest.h>
#include <omp.h>

#include "scene_test_util.h"

namespace mrvs::sim {
namespace {

/// The default indoor scene (4 mm texels), baked once for the suite.
class SceneTexture : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto start = std::chrono::steady_clock::now();
    auto scene = make_scene(SceneProfile::kIndoor, SceneOptions{}, test::indoor_path(), 17);
    bake_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(scene.ok()) << scene.status();
    scene_ = std::make_unique<Scene>(std::move(scene).value());
  }
  static void TearDownTestSuite() { scene_.reset(); }

  static std::unique_ptr<Scene> scene_;
  static double bake_seconds_;
};
std::unique_ptr<Scene> SceneTexture::scene_;
double SceneTexture::bake_seconds_ = 0.0;

/// Number of texels of level k along a face side of `size` metres.
int level_size(double size, double texel, int k) {
  int n = static_cast<int>(std::ceil(size / texel - 1e-6));
  for (int i = 0; i < k; ++i) n = (n + 1) / 2;
  return n;
}

/// Byte of texel (i, j) of level k, read back through albedo() at the texel centre.
int texel_byte(const Scene& s, int face, int k, int i, int j) {
  const double t = s.texel_size(face) * std::ldexp(1.0, k);
  const float a = s.albedo(face, static_cast<float>((i + 0.5) * t), static_cast<float>((j + 0.5) * t),
                           static_cast<float>(k));
  return static_cast<int>(std::lround(a * 255.0f));
}

TEST_F(SceneTexture, BakeTime) {
  std::printf("indoor scene with %zu faces built in %.2f s (4 mm texels, incl. layout)\n",
              scene_->faces().size(), bake_seconds_);
  EXPECT_LT(bake_seconds_, 4.0);
  EXPECT_FLOAT_EQ(scene_->texel_size(0), 0.004f);
}

TEST_F(SceneTexture, AlbedoRangeAndRichness) {
  const CounterRng rng(1, Stream::kTexture);
  double sum = 0.0, sum2 = 0.0;
  float lo = 1.0f, hi = 0.0f;
  constexpr int kN = 200000;
  for (int i = 0; i < kN; ++i) {
    const Face& f = scene_->faces()[rng.bits(i, 0) % scene_->faces().size()];
    const float a = scene_->albedo(f.id, static_cast<float>(rng.uniform(-0.1, f.size_u + 0.1, i, 1)),
                                   static_cast<float>(rng.uniform(-0.1, f.size_v + 0.1, i, 2)),
                                   static_cast<float>(rng.uniform(-1.0, 14.0, i, 3)));
    lo = std::min(lo, a);
    hi = std::max(hi, a);
    sum += a;
    sum2 += a * a;
  }
  const double mean = sum / kN;
  const double sd = std::sqrt(sum2 / kN - mean * mean);
  std::printf("albedo range [%.4f, %.4f], mean %.3f, std %.3f\n", lo, hi, mean, sd);
  EXPECT_GE(lo, 0.03f);
  EXPECT_LE(hi, 0.97f);
  EXPECT_GT(sd, 0.12);  // rich texture: noise, posters and black/white blobs
  EXPECT_LT(lo, 0.06f);
  EXPECT_GT(hi, 0.94f);
  EXPECT_EQ(scene_->albedo(-1, 0, 0), 0.5f);
  EXPECT_EQ(scene_->albedo(100000, 0, 0), 0.5f);
}

TEST_F(SceneTexture, BilinearWithinALevelIsContinuous) {
  const CounterRng rng(2, Stream::kTexture);
  const float texel = scene_->texel_size(0);
  constexpr float kStep = 2e-5f;
  float worst = 0.0f;
  for (int i = 0; i < 100000; ++i) {
    const Face& f = scene_->faces()[rng.bits(i, 0) % scene_->faces().size()];
    const auto u = static_cast<float>(rng.uniform(0.01, f.size_u - 0.01, i, 1));
    const auto v = static_cast<float>(rng.uniform(0.01, f.size_v - 0.01, i, 2));
    const float a = scene_->albedo(f.id, u, v);
    worst = std::max({worst, std::abs(scene_->albedo(f.id, u + kStep, v) - a),
                      std::abs(scene_->albedo(f.id, u, v + kStep) - a)});
    // Trilinear: continuous in lod as well.
    const auto lod = static_cast<float>(rng.uniform(0.0, 6.0, i, 3));
    EXPECT_LE(std::abs(scene_->albedo(f.id, u, v, lod + 1e-3f) - scene_->albedo(f.id, u, v, lod)), 1e-3f);
  }
  // A bilinear step of kStep changes the albedo by at most (0.94 / texel) * kStep.
  EXPECT_LE(worst, 0.94f / texel * kStep * 1.05f + 1e-5f);
  // Between two texel centres the value is their mean.
  for (int i = 0; i < 200; ++i) {
    const int b0 = texel_byte(*scene_, 0, 0, i, 7);
    const int b1 = texel_byte(*scene_, 0, 0, i + 1, 7);
    const float mid = scene_->albedo(0, static_cast<float>((i + 1) * texel), static_cast<float>(7.5 * texel));
    EXPECT_NEAR(mid, 0.5f * (b0 + b1) / 255.0f, 1e-4f);
  }
}

TEST_F(SceneTexture, MipLevelIsTheBoxFilterOfTheLevelBelow) {
  const CounterRng rng(3, Stream::kTexture);
  int checked = 0;
  for (const int face : {0, 4, 6, 11, 30, 40}) {
    const Face& f = scene_->faces()[face];
    const double texel = scene_->texel_size(face);
    for (int k = 1; k <= 8; ++k) {
      const int w = level_size(f.size_u, texel, k - 1);
      const int h = level_size(f.size_v, texel, k - 1);
      const double tk = texel * std::ldexp(1.0, k - 1);
      // Parents whose four children have their centres on the face.
      const int pw = static_cast<int>(std::floor((f.size_u / tk - 0.5 - 1.0) / 2.0)) + 1;
      const int ph = static_cast<int>(std::floor((f.size_v / tk - 0.5 - 1.0) / 2.0)) + 1;
      for (int s = 0; s < 300 && pw > 0 && ph > 0; ++s) {
        const int i = s < 2 ? pw - 1 : static_cast<int>(rng.bits(face, k, 2 * s) % pw);
        const int j = s < 1 ? ph - 1 : static_cast<int>(rng.bits(face, k, 2 * s + 1) % ph);
        const int i1 = std::min(2 * i + 1, w - 1);
        const int j1 = std::min(2 * j + 1, h - 1);
        const int sum =
            texel_byte(*scene_, face, k - 1, 2 * i, 2 * j) + texel_byte(*scene_, face, k - 1, i1, 2 * j) +
            texel_byte(*scene_, face, k - 1, 2 * i, j1) + texel_byte(*scene_, face, k - 1, i1, j1);
        EXPECT_NEAR(texel_byte(*scene_, face, k, i, j), (sum + 2) / 4, 1)
            << "face " << face << " level " << k;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 5000);
}

/// albedo() at fixed random points of every face.
std::vector<float> fingerprint(const Scene& s) {
  std::vector<float> out;
  const CounterRng rng(4, Stream::kTexture);
  for (const Face& f : s.faces()) {
    for (int i = 0; i < 200; ++i) {
      out.push_back(s.albedo(f.id, static_cast<float>(rng.uniform(0.0, f.size_u, f.id, i, 1)),
                             static_cast<float>(rng.uniform(0.0, f.size_v, f.id, i, 2)),
                             static_cast<float>(rng.uniform(0.0, 3.0, f.id, i, 3))));
    }
  }
  return out;
}

TEST(SceneTextureDeterminism, SameSeedSameBytesAnyThreadCount) {
  SceneOptions o;
  o.texel_size_m = 0.008;
  const std::vector<Vec3d> path = test::indoor_path();
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  auto one = make_scene(SceneProfile::kIndoor, o, path, 23);
  omp_set_num_threads(std::max(2, threads));
  auto two = make_scene(SceneProfile::kIndoor, o, path, 23);
  auto other = make_scene(SceneProfile::kIndoor, o, path, 24);
  omp_set_num_threads(threads);
  ASSERT_TRUE(one.ok() && two.ok() && other.ok());
  const std::vector<float> a = fingerprint(*one);
  EXPECT_EQ(a, fingerprint(*two));
  // Another seed gives another layout and other textures: compare the room faces.
  const std::vector<float> b = fingerprint(*other);
  int differ = 0;
  for (int i = 0; i < 6 * 200; ++i) differ += a[i] != b[i] ? 1 : 0;
  EXPECT_GT(differ, 6 * 200 * 9 / 10);
}

TEST(SceneTextureDeterminism, TexturelessFacesAreNearlyConstant) {
  SceneOptions o;
  o.texel_size_m = 0.01;
  o.textureless_fraction = 1.0;
  auto flat = make_scene(SceneProfile::kIndoor, o, test::indoor_path(), 25);
  ASSERT_TRUE(flat.ok());
  const CounterRng rng(5, Stream::kTexture);
  for (const Face& f : flat->faces()) {
    EXPECT_TRUE(f.textureless);
    float lo = 1.0f, hi = 0.0f;
    for (int i = 0; i < 2000; ++i) {
      const float a = flat->albedo(f.id, static_cast<float>(rng.uniform(0.0, f.size_u, f.id, i, 1)),
                                   static_cast<float>(rng.uniform(0.0, f.size_v, f.id, i, 2)));
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    // +-1 % shading plus 8-bit rounding.
    EXPECT_LE(hi - lo, 0.02f * hi + 1.0f / 255.0f) << "face " << f.id;
  }
  o.textureless_fraction = 0.3;
  auto some = make_scene(SceneProfile::kIndoor, o, test::indoor_path(), 25);
  ASSERT_TRUE(some.ok());
  int count = 0;
  for (const Face& f : some->faces()) count += f.textureless ? 1 : 0;
  EXPECT_EQ(count, static_cast<int>(std::lround(0.3 * some->faces().size())));
}

TEST(SceneTextureOutdoor, RangeContinuityAndRoad) {
  const std::vector<Vec3d> route = test::car_route();
  auto scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 26);
  ASSERT_TRUE(scene.ok()) << scene.status();
  auto again = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 26);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(fingerprint(*scene), fingerprint(*again));
  EXPECT_FLOAT_EQ(scene->texel_size(0), 0.02f);
  const CounterRng rng(6, Stream::kTexture);
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  float worst = 0.0f;
  for (int i = 0; i < 100000; ++i) {
    const Face& f = scene->faces()[rng.bits(i, 0) % scene->faces().size()];
    const auto u = static_cast<float>(rng.uniform(0.0, f.size_u, i, 1));
    const auto v = static_cast<float>(rng.uniform(0.0, f.size_v, i, 2));
    const auto lod = static_cast<float>(rng.uniform(0.0, 8.0, i, 3));
    const float a = scene->albedo(f.id, u, v, lod);
    ASSERT_GE(a, 0.03f);
    ASSERT_LE(a, 0.97f);
    worst = std::max(worst, std::abs(scene->albedo(f.id, u + 1e-4f, v, lod) - a));
    sum += a;
    sum2 += a * a;
    ++n;
  }
  const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  std::printf("outdoor albedo mean %.3f std %.3f, max change over 0.1 mm %.4f\n", sum / n, sd, worst);
  EXPECT_GT(sd, 0.08);
  // Filtered over >= 2 cm: a 0.1 mm step changes the albedo by at most ~1/200 of a full edge.
  EXPECT_LT(worst, 0.02f);
  // Every point of the ground (road, arcs, crosswalks, pavement) at several lods.
  const Face& ground = scene->faces()[0];
  for (float u = 0.0f; u <= ground.size_u; u += 0.37f) {
    for (float v = 0.0f; v <= ground.size_v; v += 0.41f) {
      const float a = scene->albedo(0, u, v, std::fmod(u + v, 9.0f) - 1.0f);
      ASSERT_TRUE(a >= 0.03f && a <= 0.97f) << u << ", " << v;
    }
  }
  // Under the route: asphalt (0.15-0.30) or a lane marking (0.85).
  for (std::size_t i = 0; i < route.size(); i += 7) {
    const auto h = scene->intersect(route[i].cast<float>(), -Vec3f::UnitZ(), 10.0f);
    ASSERT_TRUE(h.has_value());
    const float a = scene->albedo(h->face, h->u, h->v);
    EXPECT_TRUE((a >= 0.14f && a <= 0.31f) || a >= 0.8f) << a;
  }
}

}  // namespace
}  // namespace mrvs::sim
