// Whole edge frame benchmark (Google Benchmark, not in CTest), single thread
// (cv::setNumThreads(1)): front-end + filter per stereo frame through VioSystem::feed_stereo
// on a generated V1_01 clip (realistic preset, 20 s from the still start, images in memory),
// as edge_client runs it without the map. Counters: median / p95 of the frame time after
// initialisation, and of the paper's columns (a) image processing, (b) extraction and
// tracking, (c) state update. Allocator settings as in edge_client (mrvs/core/memory.h).
//   build/bin/bench_vio [--benchmark_repetitions=3]
#include <array>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/options.h"
#include "mrvs/core/memory.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/vio_system.h"
#include "mrvs/io/dataset.h"
#include "mrvs/test/generated_sequence.h"

namespace {

using namespace mrvs;

struct Clip {
  std::string error;
  std::unique_ptr<io::DatasetReader> reader;
  std::vector<std::array<cv::Mat, 2>> images;
  edge::EdgeOptions options;
};

Clip load() {
  Clip c;
  auto path = test::generated_sequence(
      "vio_v101_20s_realistic", test::indoor_sequence_request("V1_01_easy.txt", 0.0, 20.0, "realistic"));
  if (!path.ok()) return Clip{std::string(path.status().message()), nullptr, {}, {}};
  io::DatasetOptions o;
  o.path = *path;
  auto reader = io::open_euroc_dataset(o);
  if (!reader.ok()) return Clip{std::string(reader.status().message()), nullptr, {}, {}};
  c.reader = std::move(*reader);
  for (const auto& f : c.reader->stereo_frames()) {
    auto l = c.reader->load_image(0, f.left);
    auto r = c.reader->load_image(1, f.right);
    if (!l.ok() || !r.ok()) return Clip{"cannot load an image", nullptr, {}, {}};
    c.images.push_back({*l, *r});
  }
  auto options = config::load_options_file<edge::EdgeOptions>(MRVS_CONFIG_DIR "/euroc.yaml");
  if (!options.ok()) return Clip{std::string(options.status().message()), nullptr, {}, {}};
  c.options = *options;
  return c;
}

const Clip& clip() {
  static const Clip c = [] {
    cv::setNumThreads(1);
    return load();
  }();
  return c;
}

void BM_EdgeFrame(benchmark::State& state) {
  const Clip& c = clip();
  if (!c.error.empty()) return state.SkipWithError(c.error.c_str());
  std::vector<double> frame, a, b, update;
  for (auto _ : state) {
    auto vio = edge::VioSystem::create(c.options, c.reader->calibration(),
                                       io::to_trajectory(c.reader->groundtruth()));
    if (!vio.ok()) return state.SkipWithError(std::string(vio.status().message()).c_str());
    const auto& frames = c.reader->stereo_frames();
    const auto& imu = c.reader->imu();
    std::size_t next = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      while (next < imu.size()) {
        (void)vio->feed_imu(imu[next]);
        if (imu[next++].t_ns >= vio->imu_time(frames[k].t_ns)) break;
      }
      auto out = vio->feed_stereo(frames[k].t_ns, c.images[k][0], c.images[k][1]);
      if (!out.ok() || !out->estimate.initialized) continue;
      const double ta = out->tracked.timing.image_ms, tb = out->tracked.timing.tracking_ms;
      const double tc = out->estimate.timing.total_ms;
      a.push_back(ta), b.push_back(tb), update.push_back(tc), frame.push_back(ta + tb + tc);
    }
  }
  state.counters["frame_ms_p50"] = quantile(frame, 0.5);
  state.counters["frame_ms_p95"] = quantile(frame, 0.95);
  state.counters["a_ms_p50"] = quantile(a, 0.5);
  state.counters["b_ms_p50"] = quantile(b, 0.5);
  state.counters["c_ms_p50"] = quantile(update, 0.5);
  state.counters["c_ms_p95"] = quantile(update, 0.95);
  state.counters["frames"] = static_cast<double>(frame.size());
}

BENCHMARK(BM_EdgeFrame)->Iterations(1)->Unit(benchmark::kSecond);

}  // namespace

// As edge_client runs: large temporaries stay on the heap (mrvs/core/memory.h).
int main(int argc, char** argv) {
  mrvs::keep_large_blocks_on_the_heap();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
