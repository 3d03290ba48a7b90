// Renderer and PNG timings (not a test; run by hand): per 752x480 EuRoC image for each
// anti-aliasing mode, the ray tables and the PNG writes. Each benchmark runs 25 iterations
// over 25 poses of V1_01 and reports the wall-clock median / min / max per iteration as
// counters (OpenMP uses every core).
//   build/bin/bench_sim_render [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "mrvs/config/calibration.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/sim/png_writer.h"
#include "mrvs/sim/stereo_renderer.h"
#include "mrvs/test/euroc_sensor_yaml.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

struct BenchWorld {
  config::StereoRigCalibration rig;
  io::Trajectory trajectory;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<StereoRenderer> renderer;
  std::vector<SE3d> poses;  ///< 25 cam0 poses spread over the moving part of V1_01
};

// Exits with a message on failure (a benchmark main, not library code).
template <class T>
T or_die(StatusOr<T> value) {
  if (!value.ok()) {
    std::fprintf(stderr, "bench_sim_render: %s\n", value.status().ToString().c_str());
    std::exit(1);
  }
  return *std::move(value);
}

std::unique_ptr<BenchWorld> build_world() {
  auto w = std::make_unique<BenchWorld>();
  mrvs::test::TempDir dir;
  for (int c = 0; c < 2; ++c) {
    w->rig.cameras[static_cast<std::size_t>(c)] = or_die(config::load_euroc_camera_yaml(
        dir.write("cam" + std::to_string(c) + "/sensor.yaml", mrvs::test::euroc_camera_sensor_yaml(c))));
  }
  w->trajectory = or_die(io::read_trajectory(mrvs::test::euroc_groundtruth_file("V1_01_easy.txt")));
  std::vector<Vec3d> keep_clear;
  for (std::size_t i = 0; i < w->trajectory.size(); i += 10) {
    for (const auto& c : w->rig.cameras)
      keep_clear.push_back((w->trajectory[i].T_w_b * c.T_b_c).translation());
    keep_clear.push_back(w->trajectory[i].T_w_b.translation());
  }
  w->scene =
      std::make_unique<Scene>(or_die(make_scene(SceneProfile::kIndoor, SceneOptions{}, keep_clear, 7)));
  w->renderer =
      std::make_unique<StereoRenderer>(or_die(StereoRenderer::create(*w->scene, w->rig, RenderOptions{}, 1)));
  const std::size_t first = 1000, step = (w->trajectory.size() - first) / 26;
  for (std::size_t i = 0; i < 25; ++i) {
    w->poses.push_back(w->renderer->camera_pose(0, w->trajectory[first + i * step].T_w_b));
  }
  return w;
}

const BenchWorld& world() {
  static const std::unique_ptr<BenchWorld> instance = build_world();
  return *instance;
}

// Per-iteration wall-clock times; sets the median_ms / min_ms / max_ms counters.
class IterationTimer {
 public:
  void start() { t0_ = std::chrono::steady_clock::now(); }
  void stop() {
    ms_.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count());
  }
  void report(benchmark::State& state) {
    if (ms_.empty()) return;
    std::sort(ms_.begin(), ms_.end());
    state.counters["median_ms"] = ms_[ms_.size() / 2];
    state.counters["min_ms"] = ms_.front();
    state.counters["max_ms"] = ms_.back();
  }

 private:
  std::chrono::steady_clock::time_point t0_;
  std::vector<double> ms_;
};

void render_mode(benchmark::State& state, AntiAliasing aa) {
  const BenchWorld& w = world();
  RenderOptions options;
  options.aa = aa;
  const StereoRenderer r = or_die(w.renderer->with_options(options));
  cv::Mat image;
  std::size_t k = 0;
  IterationTimer timer;
  for (auto _ : state) {
    timer.start();
    const Status s = r.render(0, w.poses[k++ % w.poses.size()], FrameInfo{}, &image);
    timer.stop();
    if (!s.ok()) state.SkipWithError(s.ToString().c_str());
    benchmark::DoNotOptimize(image.data);
  }
  timer.report(state);
}

void BM_RenderAdaptive(benchmark::State& state) { render_mode(state, AntiAliasing::kAdaptive); }
void BM_RenderFull(benchmark::State& state) { render_mode(state, AntiAliasing::kFull); }
void BM_RenderNone(benchmark::State& state) { render_mode(state, AntiAliasing::kNone); }

void BM_RenderAdaptiveWithNoise(benchmark::State& state) {
  const BenchWorld& w = world();
  RenderOptions options;
  options.read_noise_sigma = 2.0;
  options.shot_noise = true;
  const StereoRenderer r = or_die(w.renderer->with_options(options));
  cv::Mat image;
  std::int64_t k = 0;
  IterationTimer timer;
  for (auto _ : state) {
    timer.start();
    const Status s =
        r.render(0, w.poses[static_cast<std::size_t>(k) % w.poses.size()], FrameInfo{k, 1.0}, &image);
    timer.stop();
    ++k;
    if (!s.ok()) state.SkipWithError(s.ToString().c_str());
  }
  timer.report(state);
}

void BM_RayTableBuild(benchmark::State& state) {
  const BenchWorld& w = world();
  IterationTimer timer;
  for (auto _ : state) {
    timer.start();
    StatusOr<RayTable> t = RayTable::build(*w.rig.cameras[0].model);
    timer.stop();
    benchmark::DoNotOptimize(t);
  }
  timer.report(state);
}

// PNG writes of rendered images (one per pose), with our settings and, for comparison,
// cv::imwrite with IMWRITE_PNG_COMPRESSION = 1.
void png_write(benchmark::State& state, bool ours) {
  const BenchWorld& w = world();
  std::vector<cv::Mat> images;
  for (const SE3d& T : w.poses) images.push_back(or_die(w.renderer->render(0, T, FrameInfo{})));
  mrvs::test::TempDir dir;
  const std::string path = (dir / "x.png").string();
  std::size_t k = 0, bytes = 0;
  IterationTimer timer;
  for (auto _ : state) {
    const cv::Mat& image = images[k++ % images.size()];
    timer.start();
    if (ours) {
      const Status s = write_png(path, image);
      if (!s.ok()) state.SkipWithError(s.ToString().c_str());
    } else {
      cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
    }
    timer.stop();
    bytes += std::filesystem::file_size(path);
  }
  timer.report(state);
  state.counters["KB_per_image"] =
      static_cast<double>(bytes) / 1024.0 / static_cast<double>(state.iterations());
}

void BM_PngWrite(benchmark::State& state) { png_write(state, true); }
void BM_PngWriteImwriteLevel1(benchmark::State& state) { png_write(state, false); }

#define MRVS_RENDER_BENCH(fn) BENCHMARK(fn)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(25)

MRVS_RENDER_BENCH(BM_RenderAdaptive);
MRVS_RENDER_BENCH(BM_RenderFull);
MRVS_RENDER_BENCH(BM_RenderNone);
MRVS_RENDER_BENCH(BM_RenderAdaptiveWithNoise);
MRVS_RENDER_BENCH(BM_RayTableBuild);
MRVS_RENDER_BENCH(BM_PngWrite);
MRVS_RENDER_BENCH(BM_PngWriteImwriteLevel1);

}  // namespace
}  // namespace mrvs::sim

BENCHMARK_MAIN();
