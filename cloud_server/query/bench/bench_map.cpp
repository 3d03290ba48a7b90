// Map benchmarks (not a unit test; build/bin/bench_map):
//  (a) ray queries per second on one thread: rays through random pixels of the cameras of a
//      generated indoor sequence (V1_01_easy trajectory, easy preset, map spacing 1.5 cm),
//      cast in the synthetic scene for their true distance d*, queried with d = d* (1 + 2 %
//      noise) at R0 = 0.75 m; the level forced to 0.01 m, or chosen by select_level;
//  (b) build_voxel_map time and peak memory on that ~1.5 M point cloud, and the query
//      engine's index build.
// Counters: hit / reject / miss rates, passes, bricks and voxels visited per ray.
//
// Usage: bench_map [--benchmark_filter=...] (env MRVS_BENCH_WINDOW_S: trajectory window,
// default 2 s; MRVS_BENCH_SPACING_M: map spacing, default 0.015).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "mrvs/map/map_builder.h"
#include "mrvs/map/query_engine.h"
#include "mrvs/sim/generator.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/voxel/resolution.h"

namespace mrvs::map {
namespace {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kRays = 1 << 18;

double env_or(const char* name, double fallback) {
  const char* value = std::getenv(name);
  return value != nullptr ? std::atof(value) : fallback;
}

std::uint64_t peak_rss_bytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<std::uint64_t>(usage.ru_maxrss) * 1024U;
}

/// Everything the benchmarks share, built once.
struct Bench {
  std::string error;
  sim::World world;
  RawCloud cloud;
  std::shared_ptr<const VoxelMap> map;
  BuildReport build_report;
  double seconds_world = 0.0;
  double seconds_build = 0.0;
  std::uint64_t rss_before_build = 0;
  std::uint64_t rss_after_build = 0;
  std::vector<RayQuery> rays_fixed;          ///< resolution 0.01 m
  std::vector<RayQuery> rays_selected;       ///< resolution from select_level
  std::vector<Eigen::Vector3f> true_points;  ///< map-local surface point each ray really meets
  double true_hit_fraction = 0.0;            ///< pixels whose ray hits a face
};

sim::GeneratorRequest indoor_request() {
  sim::GeneratorRequest r;
  r.profile = sim::SceneProfile::kIndoor;
  r.trajectory = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
  r.preset = "easy";
  r.options = sim::default_options(sim::SceneProfile::kIndoor);
  (void)sim::apply_preset("easy", r.profile, r.options);
  r.options.trajectory.window_start_s = 20.0;
  r.options.trajectory.window_duration_s = env_or("MRVS_BENCH_WINDOW_S", 2.0);
  r.options.map.spacing_near_m = env_or("MRVS_BENCH_SPACING_M", 0.015);
  r.options.map.spacing_far_m = r.options.map.spacing_near_m;
  return r;
}

/// Rays through random pixels of cam0 at random frames, map-local.
void make_rays(Bench& b) {
  const auto& cam = b.world.calibration.cameras[0];
  const double focal = 0.5 * (cam.model->fx() + cam.model->fy());
  const std::vector<double> resolutions = b.map->resolutions();
  std::mt19937_64 rng(7);
  std::uniform_int_distribution<std::size_t> frame(0, b.world.grid.camera_true_ns.size() - 1);
  std::uniform_real_distribution<double> u(0.0, cam.model->width() - 1.0);
  std::uniform_real_distribution<double> v(0.0, cam.model->height() - 1.0);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::size_t tried = 0;
  while (b.rays_fixed.size() < kRays && tried < 20 * kRays) {
    ++tried;
    const SE3d T_w_c = b.world.frame_pose(frame(rng)) * cam.T_b_c;
    const StatusOr<Vec3d> bearing = cam.model->unproject(Vec2d(u(rng), v(rng)));
    if (!bearing.ok()) continue;
    const Vec3d dir_w = T_w_c.rotation_matrix() * *bearing;
    const Vec3d origin_w = T_w_c.translation();
    const auto hit = b.world.scene->intersect(origin_w.cast<float>(), dir_w.cast<float>(), 100.0f);
    if (!hit) continue;
    // Map frame = T_map_world * world (identity in the easy preset), then map-local.
    const Vec3d origin_m = b.world.map.T_map_world * origin_w;
    const Vec3d dir_m = b.world.map.T_map_world.rotation_matrix() * dir_w;
    RayQuery q;
    q.origin = (origin_m - b.map->origin).cast<float>();
    q.direction = dir_m.cast<float>();
    q.initial_distance = static_cast<float>(hit->distance * (1.0 + noise(rng)));
    q.resolution = 0.01f;
    b.rays_fixed.push_back(q);
    b.true_points.push_back((origin_m + hit->distance * dir_m - b.map->origin).cast<float>());
    const double depth = q.initial_distance * bearing->z();
    q.resolution =
        static_cast<float>(resolutions[voxel::select_level(resolutions, depth, focal).value_or(0)]);
    b.rays_selected.push_back(q);
  }
  b.true_hit_fraction = static_cast<double>(b.rays_fixed.size()) / static_cast<double>(tried);
}

Bench build_bench() {
  Bench b;
  auto start = Clock::now();
  StatusOr<sim::World> world = sim::build_world(indoor_request());
  if (!world.ok()) {
    b.error = std::string(world.status().message());
    return b;
  }
  b.world = std::move(*world);
  b.seconds_world = std::chrono::duration<double>(Clock::now() - start).count();
  for (const sim::MapPoint& p : b.world.map.points) {
    b.cloud.positions.push_back(p.position.cast<double>());
    b.cloud.intensities.push_back(p.intensity);
  }
  b.cloud.source = "bench_map: simulated indoor survey";
  b.rss_before_build = peak_rss_bytes();
  start = Clock::now();
  StatusOr<VoxelMap> map = build_voxel_map(b.cloud, MapBuilderOptions{}, &b.build_report);
  b.seconds_build = std::chrono::duration<double>(Clock::now() - start).count();
  b.rss_after_build = peak_rss_bytes();
  if (!map.ok()) {
    b.error = std::string(map.status().message());
    return b;
  }
  b.map = std::make_shared<const VoxelMap>(std::move(*map));
  make_rays(b);
  std::printf(
      "bench_map: world %.1f s (%zu map points), build_voxel_map %.1f s, %zu rays (%.0f %% of pixels hit a "
      "face)\n",
      b.seconds_world, b.cloud.size(), b.seconds_build, b.rays_fixed.size(), 100.0 * b.true_hit_fraction);
  std::printf("%s\n", b.build_report.summary().c_str());
  return b;
}

const Bench& bench() {
  static const Bench b = build_bench();
  return b;
}

/// Queries `rays` round-robin; counters from one counted pass over all of them.
void run_queries(benchmark::State& state, const std::vector<RayQuery>& rays, bool refine) {
  const Bench& b = bench();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  QueryOptions options;
  options.refine_plane_intersection = refine;
  const StatusOr<QueryEngine> engine = QueryEngine::create(b.map, options);
  if (!engine.ok()) {
    state.SkipWithError(std::string(engine.status().message()).c_str());
    return;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(engine->query(rays[i]));
    if (++i == rays.size()) i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  QueryCounters counters;
  std::size_t status_count[5] = {0, 0, 0, 0, 0};
  std::size_t finest = 0;
  std::vector<double> errors_mm;  // accepted point to the true surface point of the ray
  for (std::size_t k = 0; k < rays.size(); ++k) {
    const QueryResult result = engine->query(rays[k], &counters);
    ++status_count[static_cast<int>(result.status)];
    finest += result.level == 0 ? 1 : 0;
    if (result.status == QueryStatus::kHit)
      errors_mm.push_back(1e3 * (result.point - b.true_points[k]).norm());
  }
  std::sort(errors_mm.begin(), errors_mm.end());
  const auto quantile = [&](double f) {
    return errors_mm.empty() ? 0.0 : errors_mm[static_cast<std::size_t>(f * (errors_mm.size() - 1))];
  };
  state.counters["err_p50_mm"] = quantile(0.5);
  state.counters["err_p90_mm"] = quantile(0.9);
  const auto n = static_cast<double>(rays.size());
  state.counters["hit"] = static_cast<double>(status_count[0]) / n;
  state.counters["miss"] = static_cast<double>(status_count[1]) / n;
  state.counters["rejected"] = static_cast<double>(status_count[2]) / n;
  state.counters["passes"] = static_cast<double>(counters.passes) / n;
  state.counters["bricks"] = static_cast<double>(counters.bricks) / n;
  state.counters["occupied_bricks"] = static_cast<double>(counters.occupied_bricks) / n;
  state.counters["voxels"] = static_cast<double>(counters.voxels) / n;
  state.counters["refined"] = static_cast<double>(counters.refined) / n;
  state.counters["level0"] = static_cast<double>(finest) / n;
}

void BM_QueryLevel001(benchmark::State& state) { run_queries(state, bench().rays_fixed, false); }
void BM_QueryLevel001Refined(benchmark::State& state) { run_queries(state, bench().rays_fixed, true); }
void BM_QuerySelectedLevel(benchmark::State& state) { run_queries(state, bench().rays_selected, false); }

/// First-hit traversal only (one pass, no acceptance), 0.01 m level, d +- 0.75 m.
void BM_FirstHitLevel001(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  const StatusOr<QueryEngine> engine = QueryEngine::create(b.map, {});
  if (!engine.ok()) {
    state.SkipWithError(std::string(engine.status().message()).c_str());
    return;
  }
  std::size_t i = 0;
  for (auto _ : state) {
    const RayQuery& q = b.rays_fixed[i];
    benchmark::DoNotOptimize(engine->first_hit(
        0, q.origin, q.direction, std::max(0.0f, q.initial_distance - 0.75f), q.initial_distance + 0.75f));
    if (++i == b.rays_fixed.size()) i = 0;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}

/// (b) build_voxel_map on the simulated survey (timed once when the shared data was built).
void BM_BuildVoxelMap(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  for (auto _ : state) state.SetIterationTime(b.seconds_build);
  state.counters["raw_points"] = static_cast<double>(b.cloud.size());
  state.counters["map_points"] = static_cast<double>(b.map->point_count());
  state.counters["seconds_saliency"] = b.build_report.seconds_saliency;
  state.counters["seconds_levels"] = b.build_report.seconds_levels;
  state.counters["peak_rss_MB_before"] = static_cast<double>(b.rss_before_build) / 1e6;
  state.counters["peak_rss_MB_after"] = static_cast<double>(b.rss_after_build) / 1e6;
}

/// QueryEngine::create: index build of all levels.
void BM_CreateEngine(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) {
    state.SkipWithError(b.error.c_str());
    return;
  }
  std::size_t bytes = 0;
  for (auto _ : state) {
    const StatusOr<QueryEngine> engine = QueryEngine::create(b.map, {});
    if (!engine.ok()) {
      state.SkipWithError(std::string(engine.status().message()).c_str());
      return;
    }
    bytes = engine->index_memory_bytes();
  }
  state.counters["index_MB"] = static_cast<double>(bytes) / 1e6;
  state.counters["map_points"] = static_cast<double>(b.map->point_count());
}

BENCHMARK(BM_QueryLevel001);
BENCHMARK(BM_QueryLevel001Refined);
BENCHMARK(BM_QuerySelectedLevel);
BENCHMARK(BM_FirstHitLevel001);
BENCHMARK(BM_BuildVoxelMap)->UseManualTime()->Iterations(1)->Repetitions(1)->Unit(benchmark::kSecond);
BENCHMARK(BM_CreateEngine)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace mrvs::map

BENCHMARK_MAIN();
