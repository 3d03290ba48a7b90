// Throughput of the scene ray caster and albedo lookups (not a unit test; build/bin/bench_sim_scene).
// Rays are camera-like: 752x480-style frusta (93 x 60 degrees) from points of a path, random yaw.
#include <cmath>
#include <cstdio>
#include <vector>

#include <benchmark/benchmark.h>
#include <omp.h>

#include "mrvs/sim/rng.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim {
namespace {

constexpr int kRays = 1 << 20;

std::vector<Vec3d> room_path() {
  std::vector<Vec3d> p;
  for (int k = 0; k < 400; ++k) {
    const double t = 2.0 * M_PI * k / 400.0;
    p.emplace_back(-0.3 + 2.0 * std::cos(t), 0.8 + 2.2 * std::sin(t), 1.4 + 0.5 * std::sin(3.0 * t));
  }
  return p;
}

std::vector<Vec3d> car_route() {
  std::vector<Vec3d> p;
  for (double s = 0.0; s <= 180.0; s += 0.5) p.emplace_back(s, 0.0, 1.7);
  for (int k = 1; k < 56; ++k) {
    const double a = 0.5 * M_PI * k / 56.0;
    p.emplace_back(180.0 + 18.0 * std::sin(a), -18.0 + 18.0 * std::cos(a), 1.7);
  }
  for (double s = 0.0; s <= 120.0; s += 0.5) p.emplace_back(198.0, -18.0 - s, 1.7);
  return p;
}

struct Rays {
  std::vector<Vec3f> origin;
  std::vector<Vec3f> direction;
};

/// kRays rays in 64 camera frusta placed along `path` (camera z axis horizontal, random yaw).
/// Each frame is a band of 752-pixel rows.
Rays camera_rays(const std::vector<Vec3d>& path, std::uint64_t seed) {
  const CounterRng rng(seed, Stream::kScene);
  Rays r;
  const int per_frame = kRays / 64;
  for (int f = 0; f < 64; ++f) {
    const Vec3f o = path[rng.bits(f, 0) % path.size()].cast<float>();
    const double yaw = rng.uniform(0.0, 2.0 * M_PI, f, 1);
    const Vec3f fwd(static_cast<float>(std::cos(yaw)), static_cast<float>(std::sin(yaw)), 0.0f);
    const Vec3f right(fwd.y(), -fwd.x(), 0.0f);
    const Vec3f down(0.0f, 0.0f, -1.0f);
    // Raster order at EuRoC resolution (752 x 480 over the frustum): a band of whole rows
    // at a random height, as a renderer walks the image.
    const int row0 = static_cast<int>(rng.bits(f, 4) % (480 - per_frame / 752));
    for (int i = 0; i < per_frame; ++i) {
      const auto x = static_cast<float>(-1.05 + 2.1 * ((i % 752) + 0.5) / 752.0);
      const auto y = static_cast<float>(-0.58 + 1.16 * (row0 + i / 752 + 0.5) / 480.0);
      r.origin.push_back(o);
      r.direction.push_back((fwd + x * right + y * down).normalized());
    }
  }
  return r;
}

const Scene& indoor_scene() {
  static const Scene scene = make_scene(SceneProfile::kIndoor, SceneOptions{}, room_path(), 1).value();
  return scene;
}

const Scene& street_scene() {
  static const Scene scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, car_route(), 1).value();
  return scene;
}

void run_rays(benchmark::State& state, const Scene& scene, const Rays& rays, float max_t) {
  const int threads = static_cast<int>(state.range(0));
  long long hits = 0;
  for (auto _ : state) {
    long long h = 0;
#pragma omp parallel for schedule(dynamic, 4096) num_threads(threads) reduction(+ : h)
    for (int i = 0; i < kRays; ++i) h += scene.intersect(rays.origin[i], rays.direction[i], max_t) ? 1 : 0;
    hits = h;
    benchmark::DoNotOptimize(hits);
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kRays, benchmark::Counter::kIsRate);
  state.counters["hit_share"] = static_cast<double>(hits) / kRays;
}

void BM_IndoorIntersect(benchmark::State& state) {
  static const Rays rays = camera_rays(room_path(), 2);
  run_rays(state, indoor_scene(), rays, 100.0f);
}
BENCHMARK(BM_IndoorIntersect)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_StreetIntersect(benchmark::State& state) {
  static const Rays rays = camera_rays(car_route(), 3);
  run_rays(state, street_scene(), rays, 300.0f);
}
BENCHMARK(BM_StreetIntersect)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

/// Ray + trilinear albedo, as the renderer's first pass does.
void BM_IndoorIntersectAndAlbedo(benchmark::State& state) {
  static const Rays rays = camera_rays(room_path(), 2);
  const Scene& scene = indoor_scene();
  const int threads = static_cast<int>(state.range(0));
  for (auto _ : state) {
    double sum = 0.0;
#pragma omp parallel for schedule(dynamic, 4096) num_threads(threads) reduction(+ : sum)
    for (int i = 0; i < kRays; ++i) {
      if (const auto h = scene.intersect(rays.origin[i], rays.direction[i], 100.0f)) {
        sum += scene.albedo(h->face, h->u, h->v, std::log2(std::max(1e-6f, h->distance * 0.0022f / 0.004f)));
      }
    }
    benchmark::DoNotOptimize(sum);
  }
  state.counters["rays_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kRays, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_IndoorIntersectAndAlbedo)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

void BM_IndoorBake(benchmark::State& state) {
  const std::vector<Vec3d> path = room_path();
  for (auto _ : state) {
    auto scene = make_scene(SceneProfile::kIndoor, SceneOptions{}, path, 5);
    benchmark::DoNotOptimize(scene);
  }
}
BENCHMARK(BM_IndoorBake)->Iterations(3)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mrvs::sim

BENCHMARK_MAIN();
