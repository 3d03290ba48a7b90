// Front-end benchmarks (Google Benchmark, not in CTest), single thread (cv::setNumThreads(1)):
//   BM_FrontendStereoFrame/P  one 752x480 stereo frame through FeatureTracker::process, on a
//                           rendered V1_01 sequence (3 s from t = 20 s, 60 frames, replayed),
//                           without (P = 0) or with (P = 1) the camera motion as prior, as the
//                           VIO gives it from the IMU;
//                           counters: median / p95 of the frame time and of the paper's
//                           columns (a) image processing and (b) extraction + tracking
//   BM_GradientPyramid      3-level float pyramid + gradients of one image
//   BM_SelectPixels/H       the DSO-style selector asked for 200 pixels on an empty mask,
//                           starting from cell size H (0: the first frame's 3 px)
//   BM_DenseStereoPoints/S  DenseStereo::points of one pair of the same sequence (replayed) with
//                           downsample S (1, 2, 4); counters: median / p95 ms per pair,
//                           median points per pair
// The tracker runs with the `tracker` section of MRVS_BENCH_CONFIG (default config/euroc.yaml,
// the options the edge client ships with), dense stereo with its `dense_stereo` section (the
// defaults when there is none), plus the overrides in MRVS_BENCH_SET (space-separated, e.g.
// "tracker.klt_iterations=15 tracker.klt_window=9" or "dense_stereo.matcher=sgbm").
// Environment: MRVS_BENCH_PRESET (easy | realistic | hard, default easy), MRVS_BENCH_CONFIG, MRVS_BENCH_SET.
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/options.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/dense_stereo.h"
#include "mrvs/edge/feature_tracker.h"
#include "mrvs/edge/pixel_selector.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/photometry.h"
#include "mrvs/sim/stereo_renderer.h"
#include "mrvs/test/shared_data.h"

namespace {

using namespace mrvs;

struct Bench {
  std::string error;
  edge::TrackerOptions tracker;
  edge::DenseStereoOptions dense_stereo;
  config::StereoRigCalibration rig;
  std::vector<std::array<cv::Mat, 2>> images;
  std::vector<TimestampNs> t_ns;
  std::vector<SE3d> T_w_c0;  ///< true left-camera poses (the motion prior of BM_FrontendStereoFrame/1)
};

Bench failed(std::string error) {
  Bench b;
  b.error = std::move(error);
  return b;
}

/// Section `section` of MRVS_BENCH_CONFIG with the overrides of MRVS_BENCH_SET.
template <class T>
StatusOr<T> bench_options(const std::string& section) {
  const char* file = std::getenv("MRVS_BENCH_CONFIG");
  const char* set = std::getenv("MRVS_BENCH_SET");
  std::vector<std::string> overrides;
  std::istringstream words(set != nullptr ? set : "");
  for (std::string w; words >> w;) overrides.push_back(w);
  return config::load_options_file<T>(
      file != nullptr ? std::string(file) : std::string(MRVS_SOURCE_DIR "/config/euroc.yaml"), section,
      overrides);
}

Bench build_bench() {
  Bench b;
  StatusOr<edge::TrackerOptions> tracker = bench_options<edge::TrackerOptions>("tracker");
  if (!tracker.ok()) return failed(std::string(tracker.status().message()));
  b.tracker = *tracker;
  StatusOr<edge::DenseStereoOptions> dense = bench_options<edge::DenseStereoOptions>("dense_stereo");
  if (!dense.ok()) return failed(std::string(dense.status().message()));
  b.dense_stereo = *dense;
  sim::GeneratorRequest r;
  r.profile = sim::SceneProfile::kIndoor;
  r.trajectory = test::euroc_groundtruth_file("V1_01_easy.txt");
  const char* preset = std::getenv("MRVS_BENCH_PRESET");
  r.preset = preset != nullptr ? preset : "easy";
  r.options = sim::default_options(r.profile);
  if (Status s = sim::apply_preset(r.preset, r.profile, r.options); !s.ok())
    return failed(std::string(s.message()));
  r.options.trajectory.window_start_s = 20.0;
  r.options.trajectory.window_duration_s = 3.05;
  r.options.map.spacing_near_m = r.options.map.spacing_far_m = 0.2;
  StatusOr<sim::World> world = sim::build_world(r);
  if (!world.ok()) return failed(std::string(world.status().message()));
  auto renderer = sim::StereoRenderer::create(*world->scene, world->calibration, r.options.render, 1);
  if (!renderer.ok()) return failed(std::string(renderer.status().message()));
  const std::size_t n = std::min<std::size_t>(60, world->grid.camera_true_ns.size());
  const auto gains = sim::exposure_gains(1, static_cast<std::int64_t>(n), renderer->options());
  for (std::size_t k = 0; k < n; ++k) {
    auto images =
        renderer->render_stereo(world->frame_pose(k), sim::FrameInfo{static_cast<std::int64_t>(k), gains[k]});
    if (!images.ok()) return failed(std::string(images.status().message()));
    b.images.push_back(*images);
    b.t_ns.push_back(world->grid.camera_stamp_ns[k]);
    b.T_w_c0.push_back(renderer->camera_pose(0, world->frame_pose(k)));
  }
  b.rig = world->calibration;
  return b;
}

const Bench& bench() {
  static const Bench b = [] {
    cv::setNumThreads(1);
    return build_bench();
  }();
  return b;
}

void BM_FrontendStereoFrame(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) return state.SkipWithError(b.error.c_str());
  std::optional<edge::FeatureTracker> tracker;
  std::vector<double> total, image, tracking;
  std::size_t k = 0;
  TimestampNs offset = 0;  // replays keep times increasing
  for (auto _ : state) {
    if (!tracker || k == b.images.size()) {
      state.PauseTiming();
      tracker.emplace(*edge::FeatureTracker::create(b.tracker, b.rig));
      offset += k == b.images.size() ? b.t_ns.back() - b.t_ns.front() + 1 : 0;
      k = 0;
      state.ResumeTiming();
    }
    std::optional<SE3d> T_c_cprev;
    if (state.range(0) != 0 && k > 0) T_c_cprev = b.T_w_c0[k].inverse() * b.T_w_c0[k - 1];
    auto frame = tracker->process(b.t_ns[k] + offset, b.images[k][0], b.images[k][1], T_c_cprev);
    if (!frame.ok()) return state.SkipWithError(std::string(frame.status().message()).c_str());
    image.push_back(frame->timing.image_ms);
    tracking.push_back(frame->timing.tracking_ms);
    total.push_back(frame->timing.image_ms + frame->timing.tracking_ms);
    ++k;
  }
  state.counters["frame_ms_p50"] = quantile(total, 0.5);
  state.counters["frame_ms_p95"] = quantile(total, 0.95);
  state.counters["a_image_ms_p50"] = quantile(image, 0.5);
  state.counters["b_tracking_ms_p50"] = quantile(tracking, 0.5);
  state.counters["b_tracking_ms_p95"] = quantile(tracking, 0.95);
}

void BM_GradientPyramid(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) return state.SkipWithError(b.error.c_str());
  edge::GradientPyramid pyramid;
  for (auto _ : state) benchmark::DoNotOptimize(edge::build_gradient_pyramid(b.images[0][0], 3, &pyramid));
}

/// state.range(0): the pot hint (0 = options.initial_pot, as on the first frame).
void BM_SelectPixels(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) return state.SkipWithError(b.error.c_str());
  edge::GradientPyramid pyramid;
  (void)edge::build_gradient_pyramid(b.images[0][0], 3, &pyramid);
  std::size_t selected = 0;
  for (auto _ : state) {
    const auto result = edge::select_pixels(pyramid, cv::Mat(), 200, edge::SelectorOptions{},
                                            static_cast<int>(state.range(0)));
    selected = result.pixels.size();
    state.counters["passes"] = result.passes;
    state.counters["pot"] = result.pot;
  }
  state.counters["selected"] = static_cast<double>(selected);
}

/// state.range(0): DenseStereoOptions::downsample.
void BM_DenseStereoPoints(benchmark::State& state) {
  const Bench& b = bench();
  if (!b.error.empty()) return state.SkipWithError(b.error.c_str());
  edge::DenseStereoOptions options = b.dense_stereo;
  options.downsample = static_cast<int>(state.range(0));
  auto stereo = edge::DenseStereo::create(options, b.rig);
  if (!stereo.ok()) return state.SkipWithError(std::string(stereo.status().message()).c_str());
  std::vector<double> ms, points;
  std::size_t k = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    auto p = stereo->points(b.images[k][0], b.images[k][1]);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    if (!p.ok()) return state.SkipWithError(std::string(p.status().message()).c_str());
    points.push_back(static_cast<double>(p->size()));
    k = (k + 1) % b.images.size();
  }
  state.counters["pair_ms_p50"] = quantile(ms, 0.5);
  state.counters["pair_ms_p95"] = quantile(ms, 0.95);
  state.counters["points_p50"] = quantile(points, 0.5);
}

BENCHMARK(BM_FrontendStereoFrame)->Arg(0)->Arg(1)->Iterations(600)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GradientPyramid)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SelectPixels)->Arg(0)->Arg(35)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_DenseStereoPoints)->Arg(1)->Arg(2)->Arg(4)->Iterations(120)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
