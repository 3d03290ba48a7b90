// frontend_replay: runs the edge front-end (KLT tracking, DSO-style selection, stereo
// matching) over a EuRoC ASL sequence (real or generated) and reports tracking figures and
// the paper's timing columns (a) image processing and (b) feature extraction and tracking.
//
//   frontend_replay --dataset DIR [--config config/euroc.yaml] [--set tracker.max_features=150]
//       [--frames N] [--threads 1] [--per-frame]
//
// stdout: "KEY: value" lines; logs on stderr. Exit codes: 0 success, 1 data error (a missing
// or unreadable image is named), 2 usage or config error.
#include <algorithm>
#include <string>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/options.h"
#include "mrvs/config/yaml_document.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/feature_tracker.h"
#include "mrvs/io/dataset.h"

namespace {

using mrvs::quantile;

struct Args {
  std::string dataset;
  std::string config;
  std::vector<std::string> overrides;
  int frames = 0;
  int threads = 1;
  bool per_frame = false;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--dataset", a.dataset, "EuRoC ASL sequence folder (containing mav0/)")->required();
  app.add_option("--config", a.config, "Tuning file with a `tracker` section (config/euroc.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides, "Override one option, e.g. --set tracker.max_features=150");
  app.add_option("--frames", a.frames, "Stereo frames to process (0 = all)")
      ->capture_default_str()
      ->check(CLI::Range(0, 100000000));
  app.add_option("--threads", a.threads, "OpenCV threads (1 = the single-thread figures)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_flag("--per-frame", a.per_frame, "Print one line per frame");
  mrvs::add_log_level_option(app, a.log_level);
}

struct Totals {
  std::vector<double> image_ms, tracking_ms, total_ms, ended_lengths, temporal_ms, detection_ms, stereo_ms;
  double features = 0, stereo = 0, tracked = 0, created = 0, lost_klt = 0, rejected_temporal = 0;
  double crowded = 0, stereo_failed = 0, stereo_epipolar = 0, stereo_lr = 0, stereo_depth = 0;
  std::unordered_map<mrvs::edge::FeatureId, int> live;  ///< id -> track length in the last frame

  void add(const mrvs::edge::TrackedFrame& f) {
    image_ms.push_back(f.timing.image_ms);
    tracking_ms.push_back(f.timing.tracking_ms);
    temporal_ms.push_back(f.timing.temporal_ms);
    detection_ms.push_back(f.timing.detection_ms);
    stereo_ms.push_back(f.timing.stereo_ms);
    total_ms.push_back(f.timing.image_ms + f.timing.tracking_ms);
    const auto& s = f.stats;
    features += static_cast<double>(f.features.size());
    stereo += s.stereo;
    tracked += s.tracked;
    created += s.created;
    lost_klt += s.lost_klt;
    rejected_temporal += s.rejected_temporal;
    crowded += s.dropped_crowded;
    stereo_failed += s.stereo_failed_klt;
    stereo_epipolar += s.stereo_rejected_epipolar;
    stereo_lr += s.stereo_rejected_lr;
    stereo_depth += s.stereo_rejected_depth;
    std::unordered_map<mrvs::edge::FeatureId, int> now;
    for (const auto& o : f.features) now[o.id] = o.track_length;
    for (const auto& [id, length] : live) {
      if (now.count(id) == 0) ended_lengths.push_back(length);
    }
    live = std::move(now);
  }
};

void print_summary(Totals& t) {
  for (const auto& [id, length] : t.live) t.ended_lengths.push_back(length);  // still alive at the end
  const double n = std::max<double>(1.0, static_cast<double>(t.total_ms.size()));
  fmt::print("FRAMES: {}\nFEATURES_PER_FRAME: {:.1f}\nSTEREO_FRACTION: {:.3f}\n", t.total_ms.size(),
             t.features / n, t.features > 0 ? t.stereo / t.features : 0.0);
  fmt::print("TRACKED_PER_FRAME: {:.1f}\nCREATED_PER_FRAME: {:.1f}\nLOST_KLT_PER_FRAME: {:.2f}\n",
             t.tracked / n, t.created / n, t.lost_klt / n);
  fmt::print("REJECTED_TEMPORAL_PER_FRAME: {:.2f}\nDROPPED_CROWDED_PER_FRAME: {:.2f}\n",
             t.rejected_temporal / n, t.crowded / n);
  fmt::print("STEREO_NO_MATCH_PER_FRAME: {:.2f}\nSTEREO_REJECTED_LR_PER_FRAME: {:.2f}\n", t.stereo_failed / n,
             t.stereo_lr / n);
  fmt::print("STEREO_REJECTED_EPIPOLAR_PER_FRAME: {:.2f}\nSTEREO_REJECTED_DEPTH_PER_FRAME: {:.2f}\n",
             t.stereo_epipolar / n, t.stereo_depth / n);
  fmt::print("TRACK_LENGTH_MEDIAN: {:.0f}\nTRACK_LENGTH_P90: {:.0f}\nTRACK_LENGTH_MAX: {:.0f}\n",
             quantile(t.ended_lengths, 0.5), quantile(t.ended_lengths, 0.9), quantile(t.ended_lengths, 1.0));
  fmt::print(
      "IMAGE_MS_MEDIAN: {:.3f}\nIMAGE_MS_P95: {:.3f}\nTRACKING_MS_MEDIAN: {:.3f}\nTRACKING_MS_P95: {:.3f}\n",
      quantile(t.image_ms, 0.5), quantile(t.image_ms, 0.95), quantile(t.tracking_ms, 0.5),
      quantile(t.tracking_ms, 0.95));
  fmt::print(
      "TEMPORAL_MS_MEDIAN: {:.3f}\nDETECTION_MS_MEDIAN: {:.3f}\nDETECTION_MS_P95: {:.3f}\nSTEREO_MS_MEDIAN: "
      "{:.3f}\n",
      quantile(t.temporal_ms, 0.5), quantile(t.detection_ms, 0.5), quantile(t.detection_ms, 0.95),
      quantile(t.stereo_ms, 0.5));
  fmt::print("FRONTEND_MS_MEDIAN: {:.3f}\nFRONTEND_MS_P95: {:.3f}\n", quantile(t.total_ms, 0.5),
             quantile(t.total_ms, 0.95));
}

int run(const Args& a) {
  cv::setNumThreads(a.threads);
  auto options = [&]() -> mrvs::StatusOr<mrvs::edge::TrackerOptions> {
    MRVS_ASSIGN_OR_RETURN(const auto doc, mrvs::config::load_yaml_with_overrides(a.config, a.overrides));
    return mrvs::config::load_options<mrvs::edge::TrackerOptions>(doc, "tracker");
  }();
  if (!options.ok()) {
    fmt::print(stderr, "frontend_replay: error: {}\n", std::string(options.status().message()));
    return mrvs::kExitUsageError;
  }
  spdlog::info("tracker options:\n{}", mrvs::config::options_to_yaml(*options, "tracker"));
  mrvs::io::DatasetOptions dataset_options;
  dataset_options.path = a.dataset;
  auto dataset = mrvs::io::open_euroc_dataset(dataset_options);
  if (!dataset.ok()) {
    fmt::print(stderr, "frontend_replay: error: {}\n", std::string(dataset.status().message()));
    return mrvs::kExitDataError;
  }
  const auto& reader = **dataset;
  auto tracker = mrvs::edge::FeatureTracker::create(*options, reader.calibration());
  if (!tracker.ok()) {
    fmt::print(stderr, "frontend_replay: error: {}\n", std::string(tracker.status().message()));
    return mrvs::kExitDataError;
  }
  const auto& frames = reader.stereo_frames();
  const std::size_t n =
      a.frames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(a.frames), frames.size()) : frames.size();
  Totals totals;
  for (std::size_t k = 0; k < n; ++k) {
    auto left = reader.load_image(0, frames[k].left);
    auto right = left.ok() ? reader.load_image(1, frames[k].right) : left;
    auto tracked = right.ok() ? tracker->process(frames[k].t_ns, *left, *right) : right.status();
    if (!tracked.ok()) {
      fmt::print(stderr, "frontend_replay: error: frame {} ({} ns): {}\n", k, frames[k].t_ns,
                 std::string(tracked.status().message()));
      return mrvs::kExitDataError;
    }
    totals.add(*tracked);
    if (a.per_frame) {
      const auto& s = tracked->stats;
      const auto& tm = tracked->timing;
      fmt::print(
          "frame {} features {} stereo {} tracked {} created {} image_ms {:.3f} tracking_ms {:.3f} "
          "temporal_ms {:.3f} detection_ms {:.3f} stereo_ms {:.3f}\n",
          k, tracked->features.size(), s.stereo, s.tracked, s.created, tm.image_ms, tm.tracking_ms,
          tm.temporal_ms, tm.detection_ms, tm.stereo_ms);
    }
  }
  print_summary(totals);
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs the edge front-end over a EuRoC sequence and reports tracks and timing.",
               "frontend_replay"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
