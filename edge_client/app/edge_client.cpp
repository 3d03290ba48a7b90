// edge_client: the edge process. Stereo VIO on a EuRoC ASL folder (real or generated) with
// the paper's two-stage update against the cloud's voxel map over Fast DDS (or plain VIO
// with --no-map), writing a TUM trajectory of the IMU pose at each image: in the map frame
// once the cloud's localisation service has placed the filter (the poses before it are
// mapped by the same answer), in the filter's own gravity-aligned odometry frame when it
// never did (and with --no-map). Ground truth is read only by the ablations that ask for it
// (estimator.alignment.source gt / gt_noisy, --query-pose-source gt).
//
//   edge_client --dataset DIR --config config/euroc.yaml --output TRAJ.txt
//       [--dds-profile config/dds/loopback.xml] [--no-map] [--fixed-resolution 0.02]
//       [--query-pose-source gt] [--stage1-mode msckf_nullspace]
//       [--groundtruth FILE] [--set estimator.msckf.sigma_px=1.5] [--frames N]
//
// stdout: "KEY: value" lines (frames, timing columns a-e, link figures, the final calibration
// CALIB_*); logs and progress
// on stderr. Exit codes: 0 success, 1 data error (named), 2 usage or configuration error.
#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/memory.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/dds_map_service.h"
#include "mrvs/edge/map_trajectory.h"
#include "mrvs/edge/vio_system.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/trajectory_io.h"

namespace {

using mrvs::quantile;

struct Args {
  std::string dataset;
  std::string config;
  std::string output;
  std::string lock_poses;  ///< --lock-poses: each lock's placed pose (empty: not written)
  std::string groundtruth;
  std::vector<std::string> overrides;
  bool no_map = false;
  std::string dds_profile;
  int dds_domain = 42;
  std::string dds_interface;
  std::vector<std::string> dds_peers;
  double map_wait_s = 10.0;
  double fixed_resolution = -1.0;
  std::string query_pose_source;
  std::string stage1_mode;
  int frames = 0;
  int threads = 1;
  bool realtime = false;
  double progress_s = 5.0;
  std::vector<double> imu_outage;  ///< start (s after the first image), duration (s)
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--dataset", a.dataset, "EuRoC ASL sequence folder (containing mav0/)")->required();
  app.add_option("--config", a.config, "Tuning file (config/euroc.yaml or config/kaist.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--output", a.output, "TUM trajectory to write (IMU pose in the map frame at each image)")
      ->required();
  app.add_option("--lock-poses", a.lock_poses,
                 "TUM file of the pose each accepted localisation placed at its own frame (map frame, never "
                 "re-placed after a doubt)");
  app.add_flag("--no-map", a.no_map, "Plain stereo VIO without the cloud map");
  app.add_option("--dds-profile", a.dds_profile,
                 "Fast DDS profile (config/dds/loopback.xml, two_hosts.xml, ...)")
      ->check(CLI::ExistingFile);
  app.add_option("--dds-domain", a.dds_domain, "DDS domain")
      ->capture_default_str()
      ->check(CLI::Range(0, 232));
  app.add_option("--dds-interface", a.dds_interface, "Only this interface address (two-host profile)");
  app.add_option("--dds-peer", a.dds_peers, "Initial peer address (two-host profile; repeatable)");
  app.add_option("--map-wait", a.map_wait_s,
                 "Seconds to wait for the cloud's map at start (it is also picked up later)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 600.0));
  app.add_option("--fixed-resolution", a.fixed_resolution,
                 "Ask one level only (m; the ablation), 0 = multi-resolution")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--query-pose-source", a.query_pose_source, "estimated | gt (the paper's w/ GT rows)")
      ->check(CLI::IsMember({"estimated", "gt"}));
  app.add_option("--stage1-mode", a.stage1_mode,
                 "known_landmark | msckf_nullspace (the reference code) | ray_depth | plane")
      ->check(CLI::IsMember({"known_landmark", "msckf_nullspace", "ray_depth", "plane"}));
  app.add_option(
         "--groundtruth", a.groundtruth,
         "Ground truth for the ablations that read it (alignment.source gt / gt_noisy, --query-pose-source "
         "gt; TUM or EuRoC csv; default: the dataset's own)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides, "Override one option, e.g. --set estimator.msckf.sigma_px=1.5");
  app.add_option("--frames", a.frames, "Stereo frames to process (0 = all)")->check(CLI::NonNegativeNumber);
  app.add_option("--threads", a.threads, "OpenCV threads (1 = the single-thread figures)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_flag(
      "--realtime", a.realtime,
      "Feed the frames no faster than the sensor clock (as on a robot: the cloud's replies then arrive "
      "as many frames later as they would live)");
  app.add_option("--progress", a.progress_s, "Seconds between progress lines (0 = none)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--imu-outage", a.imu_outage,
                 "Fault injection: drop the IMU samples from START s after the first image for DURATION s "
                 "(the filter restarts and must find itself in the map again)")
      ->expected(2)
      ->type_name("START DURATION")
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
  std::vector<std::string> overrides = a.overrides;  // the shorthand flags, then --set
  if (a.no_map) overrides.insert(overrides.begin(), "estimator.map.enabled=false");
  if (a.fixed_resolution >= 0)
    overrides.insert(overrides.begin(),
                     fmt::format("estimator.map.fixed_resolution_m={}", a.fixed_resolution));
  if (!a.query_pose_source.empty())
    overrides.insert(overrides.begin(), "estimator.map.query_pose_source=" + a.query_pose_source);
  if (!a.stage1_mode.empty())
    overrides.insert(overrides.begin(), "estimator.map.stage1_mode=" + a.stage1_mode);
  MRVS_ASSIGN_OR_RETURN(const auto doc, mrvs::config::load_yaml_with_overrides(a.config, overrides));
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
  const auto& est = in.options.estimator;
  const bool needs_gt = mrvs::edge::needs_groundtruth(est.alignment) || est.map.query_pose_source == "gt";
  dataset_options.read_groundtruth = needs_gt && a.groundtruth.empty();
  MRVS_ASSIGN_OR_RETURN(in.dataset, mrvs::io::open_euroc_dataset(dataset_options));
  for (const std::string& w : in.dataset->warnings()) spdlog::warn("{}", w);
  if (!needs_gt) {
    if (!a.groundtruth.empty())
      spdlog::warn("--groundtruth ignored: no ablation that reads ground truth is on");
    return in;
  }
  if (!a.groundtruth.empty()) {
    MRVS_ASSIGN_OR_RETURN(in.groundtruth, mrvs::io::read_trajectory(a.groundtruth));
  } else if (in.dataset->has_groundtruth()) {
    in.groundtruth = mrvs::io::to_trajectory(in.dataset->groundtruth());
  } else {
    return absl::FailedPreconditionError(fmt::format(
        "the ablation alignment.source '{}' / query_pose_source '{}' reads ground truth, and {} has no "
        "state_groundtruth_estimate0: pass --groundtruth FILE, or use estimator.alignment.source map (the "
        "default)",
        est.alignment.source, est.map.query_pose_source, a.dataset));
  }
  spdlog::info("ground truth read for the ablation (alignment.source {}, query_pose_source {})",
               est.alignment.source, est.map.query_pose_source);
  return in;
}

/// Localisation figures over the run (alignment.source map).
struct LocalisationReport {
  int requests = 0, replies = 0, timeouts = 0, accepted = 0, fixes_applied = 0, fixes_refused = 0,
      doubted = 0;
  std::vector<double> after_s;  ///< per filter run placed in the map: seconds from its initialisation
  std::vector<mrvs::TimestampNs> at_t_imu_ns;  ///< ... and the IMU time of the pose it was placed at
  int placed_run = -1;  ///< the last filter run placed (a re-lock after a doubt is not a new run)
  std::vector<double> bytes_up, bytes_down, rtt_ms, cloud_ms, points;
  double first_after_s = -1.0;           ///< sensor time from initialisation to the first acceptance
  mrvs::TimestampNs first_t_imu_ns = 0;  ///< IMU time of the pose at that frame
};

struct Report {
  std::vector<double> image_ms, tracking_ms, update_ms, select_ms, ray_ms, total_ms;
  std::vector<double> rays, hits, accepted, planes, registered, bytes_up, bytes_down, rtt_ms;
  int frames = 0, skipped = 0, initialized_at = -1, points_max = 0, frames_without_map = 0, requests = 0,
      timeouts = 0;
  double frame_interval_ms = 0.0;   ///< median image interval of the dataset (the frame's real-time budget)
  mrvs::edge::MapTrajectory poses;  ///< what --output writes
  int run = 0;
  mrvs::TimestampNs run_start_ns = 0;
  LocalisationReport loc;
};

void print_ms(const char* key, const std::vector<double>& v) {
  fmt::print("{}_MS_MEDIAN: {:.3f}\n{}_MS_P95: {:.3f}\n", key, quantile(v, 0.5), key, quantile(v, 0.95));
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

void print_report(const Report& r, double wall_s) {
  fmt::print("FRAMES: {}\nFRAMES_SKIPPED: {}\nINITIALIZED_AT_FRAME: {}\nPOSES: {}\n", r.frames, r.skipped,
             r.initialized_at,
             r.poses.trajectory().empty() ? r.poses.odometry().size() : r.poses.trajectory().size());
  fmt::print("FRAME_INTERVAL_MS: {:.3f}\n", r.frame_interval_ms);
  fmt::print("WALL_S: {:.2f}\nRATE_FPS: {:.1f}\nPOINTS_IN_STATE_MAX: {}\n", wall_s,
             r.frames / std::max(wall_s, 1e-9), r.points_max);
  print_ms("A_IMAGE", r.image_ms);
  print_ms("B_TRACKING", r.tracking_ms);
  print_ms("C_UPDATE", r.update_ms);
  print_ms("D_SELECTION", r.select_ms);
  print_ms("E_RAYS", r.ray_ms);
  print_ms("FRAME", r.total_ms);
  fmt::print("MAP_REQUESTS: {}\nMAP_TIMEOUTS: {}\nFRAMES_WITHOUT_MAP: {}\n", r.requests, r.timeouts,
             r.frames_without_map);
  fmt::print("RAYS_PER_FRAME: {:.1f}\nRAYS_PER_FRAME_MAX: {:.0f}\nHITS_PER_FRAME: {:.1f}\n", mean(r.rays),
             quantile(r.rays, 1.0), mean(r.hits));
  fmt::print("ACCEPTED_PER_FRAME: {:.1f}\nWITH_PLANE_PER_FRAME: {:.2f}\nREGISTERED_PER_FRAME: {:.2f}\n",
             mean(r.accepted), mean(r.planes), mean(r.registered));
  fmt::print(
      "PAYLOAD_UP_BYTES_PER_FRAME: {:.0f}\nPAYLOAD_DOWN_BYTES_PER_FRAME: "
      "{:.0f}\nPAYLOAD_BYTES_PER_FRAME_MAX: {:.0f}\n",
      mean(r.bytes_up), mean(r.bytes_down), [&] {
        double m = 0.0;
        for (std::size_t i = 0; i < r.bytes_up.size(); ++i) m = std::max(m, r.bytes_up[i] + r.bytes_down[i]);
        return m;
      }());
  print_ms("RTT", r.rtt_ms);
  const LocalisationReport& L = r.loc;
  fmt::print(
      "LOCALISATION_REQUESTS: {}\nLOCALISATION_REPLIES: {}\nLOCALISATION_TIMEOUTS: {}\nLOCALISED: {}\n",
      L.requests, L.replies, L.timeouts, L.accepted);
  fmt::print("LOCALISED_AFTER_S: {:.3f}\nLOCALISED_AT_T_NS: {}\n", L.first_after_s, L.first_t_imu_ns);
  fmt::print(
      "FILTER_RUNS: {}\nLOCALISED_RUNS: {}\nLOCALISED_AFTER_S_PER_RUN: {:.2f}\nLOCALISED_AT_T_NS_PER_RUN: "
      "{}\n",
      r.run, L.after_s.size(), fmt::join(L.after_s, ","), fmt::join(L.at_t_imu_ns, ","));
  fmt::print("LOCALISATION_FIXES: {}\nLOCALISATION_FIXES_REFUSED: {}\nLOCKS_DOUBTED: {}\n", L.fixes_applied,
             L.fixes_refused, L.doubted);
  fmt::print(
      "LOCALISATION_SUBMAP_POINTS: {:.0f}\nLOCALISATION_REQUEST_BYTES: {:.0f}\nLOCALISATION_REPLY_BYTES: "
      "{:.0f}\n",
      mean(L.points), mean(L.bytes_up), mean(L.bytes_down));
  print_ms("LOCALISATION_RTT", L.rtt_ms);
  print_ms("LOCALISATION_CLOUD", L.cloud_ms);
  fmt::print("POSES_NEVER_IN_MAP_FRAME: {}\n", r.poses.never_mapped());
}

/// The filter's calibration at the end (the written one unless estimator.state.calib_* moved
/// it; scripts/lib/calib_vs_truth.py compares it with a generated sequence's truth):
/// CALIB_TIME_OFFSET_MS, per camera CALIB_CAMk_T_B_C (x y z qx qy qz qw) and CALIB_CAMk_INTRINSICS.
void print_calibration(const mrvs::edge::State* s) {
  if (s == nullptr) return;
  fmt::print("CALIB_TIME_OFFSET_MS: {:.4f}\n", 1e3 * s->time_offset_s);
  for (std::size_t c = 0; c < 2; ++c) {
    const mrvs::SE3d& T = s->cams[c].T_b_c;
    const auto q = T.quaternion();
    fmt::print("CALIB_CAM{}_T_B_C: {:.6f} {:.6f} {:.6f} {:.9f} {:.9f} {:.9f} {:.9f}\n", c,
               T.translation().x(), T.translation().y(), T.translation().z(), q.x(), q.y(), q.z(), q.w());
    std::vector<double> params(s->cams[c].model->params().data(), s->cams[c].model->params().data() + 8);
    fmt::print("CALIB_CAM{}_INTRINSICS: {:.6f}\n", c, fmt::join(params, " "));
  }
}

/// IMU samples dropped by --imu-outage: [from_ns, to_ns) (IMU clock).
struct Outage {
  mrvs::TimestampNs from_ns = 0, to_ns = 0;
  bool drops(mrvs::TimestampNs t_ns) const { return t_ns >= from_ns && t_ns < to_ns; }
};

/// Feeds the IMU samples up to the first one at or after t_ns (IMU clock), but those of the
/// outage, and the GNSS fixes up to t_ns (the localisation's prior region, outdoors).
mrvs::Status feed_sensors_until(mrvs::edge::VioSystem& vio, const mrvs::io::DatasetReader& reader,
                                std::size_t* next_imu, std::size_t* next_gnss, mrvs::TimestampNs t_ns,
                                const Outage& outage) {
  const auto& imu = reader.imu();
  while (*next_imu < imu.size()) {
    if (!outage.drops(imu[*next_imu].t_ns)) MRVS_RETURN_IF_ERROR(vio.feed_imu(imu[*next_imu]));
    if (imu[(*next_imu)++].t_ns >= t_ns) break;
  }
  const auto& gnss = reader.gnss();
  const mrvs::SE3d T_b_antenna = reader.T_b_gnss().value_or(mrvs::SE3d());
  for (; *next_gnss < gnss.size() && gnss[*next_gnss].t_ns <= t_ns; ++*next_gnss) {
    vio.feed_gnss(gnss[*next_gnss], T_b_antenna);
  }
  return absl::OkStatus();
}

/// A pose into the trajectory; a new filter run starts its clock.
void add_pose(const mrvs::edge::FrameOutput& e, Report* r) {
  if (e.run != r->run) {
    r->run = e.run;
    r->run_start_ns = e.t_ns;
  }
  r->poses.add(e.run, {e.t_imu_ns, *e.T_w_b}, e.in_map_frame, e.T_m_o, e.localisation.doubted);
}

void account_localisation(const mrvs::edge::FrameOutput& e, Report* r) {
  const mrvs::edge::LocalisationFrameStats& l = e.localisation;
  LocalisationReport& L = r->loc;
  L.requests += l.requests;
  L.replies += l.replies;
  L.timeouts += l.timeouts;
  L.fixes_applied += l.fixes_applied;
  L.fixes_refused += l.fixes_refused;
  L.doubted += l.doubted;
  if (l.requests > 0) {
    L.bytes_up.push_back(static_cast<double>(l.bytes_up));
    L.points.push_back(l.submap_points);
  }
  if (l.replies > 0) {
    L.bytes_down.push_back(static_cast<double>(l.bytes_down));
    L.rtt_ms.push_back(l.rtt_ms);
    L.cloud_ms.push_back(l.cloud_ms);
  }
  if (!e.T_m_o) return;
  if (e.run != L.placed_run) {
    L.after_s.push_back(mrvs::to_seconds(e.t_ns - r->run_start_ns));
    L.at_t_imu_ns.push_back(e.t_imu_ns);
  }
  L.placed_run = e.run;
  if (++L.accepted == 1) {
    L.first_after_s = mrvs::to_seconds(e.t_ns - r->run_start_ns);
    L.first_t_imu_ns = e.t_imu_ns;
  }
}

void account(const mrvs::edge::StereoOutput& out, int k, bool use_map, Report* r) {
  const auto& e = out.estimate;
  const auto& m = e.map;
  const double select = m.selection_ms, rays = m.ray_ms;
  r->image_ms.push_back(out.tracked.timing.image_ms);
  r->tracking_ms.push_back(out.tracked.timing.tracking_ms);
  r->update_ms.push_back(e.timing.total_ms - select - rays);
  r->select_ms.push_back(select);
  r->ray_ms.push_back(rays);
  r->total_ms.push_back(out.tracked.timing.image_ms + out.tracked.timing.tracking_ms + e.timing.total_ms);
  r->points_max = std::max(r->points_max, e.slam_points);
  if (e.initialized && r->initialized_at < 0) r->initialized_at = k;
  if (e.T_w_b) add_pose(e, r);
  account_localisation(e, r);
  if (!use_map || !e.initialized) return;
  r->requests += m.requests;
  r->timeouts += m.timeouts;
  if (m.requests > 0 && m.answered == 0) ++r->frames_without_map;  // asked, no answer in time
  r->rays.push_back(m.stage1_rays + m.registration_rays);
  r->hits.push_back(m.stage1_hits + m.registration_hits);
  r->accepted.push_back(m.stage1_accepted);
  r->planes.push_back(m.stage1_planes);
  r->registered.push_back(m.registered);
  r->bytes_up.push_back(static_cast<double>(m.bytes_up));
  r->bytes_down.push_back(static_cast<double>(m.bytes_down));
  if (m.answered > 0) r->rtt_ms.push_back(m.rtt_ms);
}

/// The DDS map service when the map is on (nullptr for --no-map).
mrvs::StatusOr<std::unique_ptr<mrvs::edge::DdsMapService>> connect(const Args& a, bool enabled) {
  if (!enabled) return std::unique_ptr<mrvs::edge::DdsMapService>();
  if (a.dds_profile.empty()) {
    return absl::InvalidArgumentError(
        "the map needs a DDS profile: pass --dds-profile config/dds/loopback.xml (or two_hosts.xml), or "
        "--no-map");
  }
  mrvs::edge::MapClientOptions o;
  o.dds.profile_file = a.dds_profile;
  o.dds.domain_id = a.dds_domain;
  o.dds.interface_address = a.dds_interface;
  o.dds.peers = a.dds_peers;
  o.dds.name = "edge_client";
  MRVS_ASSIGN_OR_RETURN(auto service, mrvs::edge::DdsMapService::create(o));
  if (const auto info = service->client().wait_for_map_info(mrvs::from_seconds(a.map_wait_s))) {
    spdlog::info("map '{}' from the cloud: origin [{:.3f} {:.3f} {:.3f}] m, {} levels", info->map_id,
                 info->origin.x(), info->origin.y(), info->origin.z(), info->resolutions.size());
  } else {
    spdlog::warn("no map from the cloud after {:.1f} s: going on as plain VIO until it appears",
                 a.map_wait_s);
  }
  return service;
}

void log_progress(const mrvs::edge::StereoOutput& out, const mrvs::edge::VioEstimator& vio, std::size_t k,
                  std::size_t n, double elapsed_s) {
  const auto& e = out.estimate;
  const std::string map =
      e.in_map_frame ? fmt::format("map: {} rays, {} accepted{}", e.map.stage1_rays + e.map.registration_rays,
                                   e.map.stage1_accepted, e.map.timeouts > 0 ? " (cloud not answering)" : "")
                     : fmt::format("odometry frame (plain VIO): {}", vio.localisation_status());
  spdlog::info("frame {}/{} ({:.1f} fps), {}", k + 1, n, (k + 1) / elapsed_s,
               e.initialized ? fmt::format("tracking: {} clones, {} points, {}", e.clones, e.slam_points, map)
                             : e.status);
}

/// Runs every frame; false on a data error (printed).
bool process(const Args& a, const mrvs::io::DatasetReader& reader, mrvs::edge::VioSystem& vio, bool use_map,
             Report* report) {
  const auto& frames = reader.stereo_frames();
  const std::size_t n =
      a.frames > 0 ? std::min<std::size_t>(static_cast<std::size_t>(a.frames), frames.size()) : frames.size();
  std::vector<double> intervals;
  for (std::size_t k = 1; k < frames.size(); ++k)
    intervals.push_back(1e-6 * static_cast<double>(frames[k].t_ns - frames[k - 1].t_ns));
  report->frame_interval_ms = quantile(intervals, 0.5);
  const mrvs::DurationNs td = reader.calibration().cameras[0].time_offset_ns;
  std::size_t next_imu = 0, next_gnss = 0;
  Outage outage;
  if (a.imu_outage.size() == 2 && n > 0) {
    outage.from_ns = frames.front().t_ns + td + mrvs::from_seconds(a.imu_outage[0]);
    outage.to_ns = outage.from_ns + mrvs::from_seconds(a.imu_outage[1]);
    spdlog::info("IMU outage (--imu-outage): no IMU samples from {:.2f} s for {:.2f} s", a.imu_outage[0],
                 a.imu_outage[1]);
  }
  if (reader.has_gnss())
    spdlog::info("{} GNSS fixes: the prior region of the localisation requests", reader.gnss().size());
  const auto t0 = std::chrono::steady_clock::now();
  auto last_progress = t0;
  int logged_run = 0;  // the last filter run whose initialisation was logged
  for (std::size_t k = 0; k < n; ++k) {
    const auto& f = frames[k];
    if (a.realtime) {
      std::this_thread::sleep_until(t0 + std::chrono::nanoseconds(f.t_ns - frames.front().t_ns));
    }
    if (auto s = feed_sensors_until(vio, reader, &next_imu, &next_gnss, vio.imu_time(f.t_ns), outage);
        !s.ok()) {
      fmt::print(stderr, "edge_client: error: {}\n", std::string(s.message()));
      return false;
    }
    auto left = reader.load_image(0, f.left);
    auto right = left.ok() ? reader.load_image(1, f.right) : left;
    if (!right.ok()) {
      fmt::print(stderr, "edge_client: error: {}\n", std::string(right.status().message()));
      return false;
    }
    auto out = vio.feed_stereo(f.t_ns, *left, *right);
    ++report->frames;
    if (!out.ok()) {
      ++report->skipped;
      spdlog::warn("frame {} ({} ns) skipped: {}", k, f.t_ns, std::string(out.status().message()));
      continue;
    }
    account(*out, static_cast<int>(k), use_map, report);
    if (out->estimate.initialized && out->estimate.run != logged_run) {  // each filter run's start
      spdlog::info("{}", vio.estimator().initialization_summary());
      logged_run = out->estimate.run;
    }
    const auto now = std::chrono::steady_clock::now();
    if (a.progress_s > 0 && std::chrono::duration<double>(now - last_progress).count() >= a.progress_s) {
      last_progress = now;
      log_progress(*out, vio.estimator(), k, n, std::chrono::duration<double>(now - t0).count());
    }
  }
  return true;
}

int run(const Args& a) {
  cv::setNumThreads(a.threads);
  bool usage = false;
  auto in = load_inputs(a, &usage);
  if (!in.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(in.status().message()));
    return usage ? mrvs::kExitUsageError : mrvs::kExitDataError;
  }
  spdlog::info("calibration:\n{}", in->dataset->calibration().describe());
  spdlog::info("options:\n{}", mrvs::config::options_to_yaml(in->options));
  auto vio = mrvs::edge::VioSystem::create(in->options, in->dataset->calibration(), in->groundtruth);
  const bool use_map = in->options.estimator.map.enabled;
  auto map = vio.ok() ? connect(a, use_map) : vio.status();
  if (!map.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(map.status().message()));
    return mrvs::kExitUsageError;
  }
  vio->set_map_service(map->get());
  Report report;
  const auto t0 = std::chrono::steady_clock::now();
  if (!process(a, *in->dataset, *vio, use_map, &report)) return mrvs::kExitDataError;
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  report.poses.finish();
  if (report.poses.never_mapped() > 0 && !report.poses.trajectory().empty()) {
    spdlog::warn(
        "{} poses were never placed by the cloud (a restart or a doubted lock it did not answer in time): "
        "written as the filter had them, continuing from its last placed pose",
        report.poses.never_mapped());
  }
  const bool mapped = !report.poses.trajectory().empty();
  mrvs::io::Trajectory out = mapped ? report.poses.trajectory() : report.poses.odometry();
  std::stable_sort(out.begin(), out.end(), [](const auto& x, const auto& y) { return x.t_ns < y.t_ns; });
  if (!mapped && vio->estimator().options().alignment.source == "map" && use_map && !out.empty()) {
    spdlog::warn("the cloud never placed the filter in its map ({}): the trajectory is in the odometry frame",
                 vio->estimator().localisation_status());
  }
  if (auto s = mrvs::io::write_tum_trajectory(a.output, out); !s.ok()) {
    fmt::print(stderr, "edge_client: error: {}\n", std::string(s.message()));
    return mrvs::kExitDataError;
  }
  if (!a.lock_poses.empty()) {
    if (auto s = mrvs::io::write_tum_trajectory(a.lock_poses, report.poses.locks()); !s.ok()) {
      fmt::print(stderr, "edge_client: error: --lock-poses: {}\n", std::string(s.message()));
      return mrvs::kExitDataError;
    }
  }
  print_report(report, wall);
  print_calibration(vio->estimator().state());
  fmt::print("TRAJECTORY_FRAME: {}\n", mapped ? "map" : "odometry");
  if (out.empty()) {
    fmt::print(stderr, "edge_client: error: never initialised ({})\n", vio->estimator().waiting_reason());
    return mrvs::kExitDataError;
  }
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  if (!mrvs::keep_large_blocks_on_the_heap())
    spdlog::warn("glibc refused the malloc settings: updates are slower");
  CLI::App app{"Edge client: stereo VIO with the cloud map over Fast DDS (or plain, --no-map).",
               "edge_client"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
