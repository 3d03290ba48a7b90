// edge_client: the edge process. Today: stereo VIO on a EuRoC ASL folder (real or
// generated) without the map (--no-map), writing a TUM trajectory of the IMU pose in the
// map frame at each image time. The map-based update over DDS arrives with issue 8.
//
//   edge_client --dataset DIR --config config/euroc.yaml --output TRAJ.txt --no-map
//       [--groundtruth FILE] [--set estimator.msckf.sigma_px=1.5] [--frames N]
//
// stdout: "KEY: value" lines (frames, timings per column); logs and progress on stderr.
// Exit codes: 0 success, 1 data error (named), 2 usage or configuration error.
#include <chrono>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/vio_system.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/trajectory_io.h"

namespace {

using mrvs::quantile;

struct Args {
  std::string dataset;
  std::string config;
  std::string output;
  std::string groundtruth;
  std::vector<std::string> overrides;
  bool no_map = false;
  int frames = 0;
  int threads = 1;
  double progress_s = 5.0;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--dataset", a.dataset, "EuRoC ASL sequence folder (containing mav0/)")->required();
  app.add_option("--config", a.config, "Tuning file (config/euroc.yaml or config/kaist.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--output", a.output, "TUM trajectory to write (IMU pose in the map frame at each image)")
      ->required();
  app.add_flag("--no-map", a.no_map, "Plain stereo VIO without the cloud map");
  app.add_option("--groundtruth", a.groundtruth,
                 "Ground truth for the one-time alignment (TUM or EuRoC csv; default: the dataset's own)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides, "Override one option, e.g. --set estimator.msckf.sigma_px=1.5");
  app.add_option("--frames", a.frames, "Stereo frames to process (0 = all)")->check(CLI::NonNegativeNumber);
  app.add_option("--threads", a.threads, "OpenCV threads (1 = the single-thread figures)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_option("--progress", a.progress_s, "Seconds between progress lines (0 = none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  mrvs::add_log_level_option(app, a.log_level);
}

struct Inputs {
  mrvs::edge::EdgeOptions options;
  std::unique_ptr<mrvs::io::DatasetReader> dataset;
  mrvs::io::Trajectory groundtruth;
};

/// Options, calibration, dataset and ground truth; `usage` tells config errors apart.
mrvs::StatusOr<Inputs> load_inputs(const Args& a, bool* usage) {
  Inputs in;
  *usage = true;
  MRVS_ASSIGN_OR_RETURN(const auto doc, mrvs::config::load_yaml_with_overrides(a.config, a.overrides));
  MRVS_ASSIGN_OR_RETURN(in.options, mrvs::config::load_options<mrvs::edge::EdgeOptions>(doc));
  *usage = false;
  mrvs::io::DatasetOptions dataset_options;
  dataset_options.path = a.dataset;
  const auto& calib = in.options.calibration;
  if (!calib.camchain.empty() || !calib.imu.empty()) {
    if (calib.camchain.empty() || calib.imu.empty()) {
      *usage = true;
      return absl::InvalidArgumentError(
          "calibration: set both camchain and imu, or neither (the dataset's files)");
    }
    mrvs::config::StereoRigCalibration rig;
    MRVS_ASSIGN_OR_RETURN(rig.cameras, mrvs::config::load_kalibr_camchain(calib.camchain));
    MRVS_ASSIGN_OR_RETURN(rig.imu, mrvs::config::load_kalibr_imu(calib.imu));
    dataset_options.calibration = rig;
  }
  MRVS_ASSIGN_OR_RETURN(in.dataset, mrvs::io::open_euroc_dataset(dataset_options));
  for (const std::string& w : in.dataset->warnings()) spdlog::warn("{}", w);
  if (!a.groundtruth.empty()) {
    MRVS_ASSIGN_OR_RETURN(in.groundtruth, mrvs::io::read_trajectory(a.groundtruth));
  } else if (in.dataset->has_groundtruth()) {
    in.groundtruth = mrvs::io::to_trajectory(in.dataset->groundtruth());
  }
  return in;
}

struct Report {
  std::vector<double> image_ms, tracking_ms, update_ms, total_ms;
  int frames = 0, skipped = 0, initialized_at = -1, points_max = 0;
  mrvs::io::Trajectory trajectory;
};

void print_report(const Report& r, double wall_s) {
  fmt::print("FRAMES: {}\nFRAMES_SKIPPED: {}\nINITIALIZED_AT_FRAME: {}\nPOSES: {}\n", r.frames, r.skipped,
             r.initialized_at, r.trajectory.size());
  fmt::print("WALL_S: {:.2f}\nRATE_FPS: {:.1f}\nPOINTS_IN_STATE_MAX: {}\n", wall_s,
             r.frames / std::max(wall_s, 1e-9), r.points_max);
  const auto line = [](const char* key, const std::vector<double>& v) {
    fmt::print("{}_MS_MEDIAN: {:.3f}\n{}_MS_P95: {:.3f}\n", key, quantile(v, 0.5), key, quantile(v, 0.95));
  };
  line("A_IMAGE", r.image_ms);
  line("B_TRACKING", r.tracking_ms);
  line("C_UPDATE", r.update_ms);
  line("FRAME", r.total_ms);
}

/// Feeds the IMU samples up to the first one at or after t_ns (IMU clock).
mrvs::Status feed_imu_until(mrvs::edge::VioSystem& vio, const std::vector<mrvs::io::ImuSample>& imu,
                            std::size_t* next, mrvs::TimestampNs t_ns) {
  while (*next < imu.size()) {
    MRVS_RETURN_IF_ERROR(vio.feed_imu(imu[*next]));
    if (imu[(*next)++].t_ns >= t_ns) break;
  }
  return absl::OkStatus();
}

void account(const mrvs::edge::StereoOutput& out, int k, Report* r) {
  const auto& e = out.estimate;
  r->image_ms.push_back(out.tracked.timing.image_ms);
  r->tracking_ms.push_back(out.tracked.timing.tracking_ms);
  r->update_ms.push_back(e.timing.total_ms);
  r->total_ms.push_back(out.tracked.timing.image_ms + out.tracked.timing.tracking_ms + e.timing.total_ms);
  r->points_max = std::max(r->points_max, e.slam_points);
  if (e.initialized && r->initialized_at < 0) r->initialized_at = k;
  if (e.T_w_b) r->trajectory.push_back({e.t_imu_ns, *e.T_w_b});
}

int run(const Args& a) {
  cv::setNumThreads(a.threads);
  if (!a.no_map) {
    fmt::print(stderr, "edge_client: the map-based update is not available yet; run with --no-map\n");
    return mrvs::kExitUsageError;
  }
  bool usage = false;
  auto in = load_inputs(a, &usage);
  if (!in.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(in.status().message()));
    return usage ? mrvs::kExitUsageError : mrvs::kExitDataError;
  }
  spdlog::info("calibration:\n{}", in->dataset->calibration().describe());
  spdlog::info("options:\n{}", mrvs::config::options_to_yaml(in->options));
  auto vio = mrvs::edge::VioSystem::create(in->options, in->dataset->calibration(), in->groundtruth);
  if (!vio.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(vio.status().message()));
    return mrvs::kExitUsageError;
  }
  const auto& reader = *in->dataset;
  const auto& frames = reader.stereo_frames();
  const std::size_t n =
      a.frames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(a.frames), frames.size()) : frames.size();
  const mrvs::DurationNs td = reader.calibration().cameras[0].time_offset_ns;
  Report report;
  std::size_t next_imu = 0;
  const auto t0 = std::chrono::steady_clock::now();
  auto last_progress = t0;
  for (std::size_t k = 0; k < n; ++k) {
    const auto& f = frames[k];
    if (auto s = feed_imu_until(*vio, reader.imu(), &next_imu, f.t_ns + td); !s.ok()) {
      fmt::print(stderr, "edge_client: error: {}\n", std::string(s.message()));
      return mrvs::kExitDataError;
    }
    auto left = reader.load_image(0, f.left);
    auto right = left.ok() ? reader.load_image(1, f.right) : left;
    if (!right.ok()) {
      fmt::print(stderr, "edge_client: error: {}\n", std::string(right.status().message()));
      return mrvs::kExitDataError;
    }
    auto out = vio->feed_stereo(f.t_ns, *left, *right);
    ++report.frames;
    if (!out.ok()) {
      ++report.skipped;
      spdlog::warn("frame {} ({} ns) skipped: {}", k, f.t_ns, std::string(out.status().message()));
      continue;
    }
    account(*out, static_cast<int>(k), &report);
    if (out->estimate.initialized && report.initialized_at == static_cast<int>(k)) {
      spdlog::info("{}", vio->estimator().initialization_summary());
    }
    const auto now = std::chrono::steady_clock::now();
    if (a.progress_s > 0 && std::chrono::duration<double>(now - last_progress).count() >= a.progress_s) {
      last_progress = now;
      const double el = std::chrono::duration<double>(now - t0).count();
      spdlog::info("frame {}/{} ({:.1f} fps), {}", k + 1, n, (k + 1) / el,
                   out->estimate.initialized ? fmt::format("tracking: {} clones, {} points",
                                                           out->estimate.clones, out->estimate.slam_points)
                                             : out->estimate.status);
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (auto s = mrvs::io::write_tum_trajectory(a.output, report.trajectory); !s.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(s.message()));
    return mrvs::kExitDataError;
  }
  print_report(report, wall);
  if (report.trajectory.empty()) {
    fmt::print(stderr, "edge_client: error: never initialised ({})\n", vio->estimator().waiting_reason());
    return mrvs::kExitDataError;
  }
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Edge client: stereo VIO on a EuRoC ASL folder (map-based update: issue 8).", "edge_client"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
