// localise_probe: the localisation service measured without the network. Runs the edge's
// VIO (VioSystem, the shipped config) on a EuRoC folder with the cloud in process
// (InProcessCloud: the map's QueryEngine and Localiser; each reply held back by the
// registration time it took, in the sensor clock, as in a real-time run) and compares every
// localisation answer with the ground truth (read here, by the measurement, never by the
// estimator): the error of T_map_odom at the submap's anchor, and of the pose at the frame the
// edge accepted an answer. Prints one line per request (--per-request) and KEY: value lines.
//
//   localise_probe --dataset SEQ --map MAP.mrvm --config config/euroc.yaml
//                  --map-config config/map_indoor.yaml [--set ...] [--until-localised]
// Exit codes: 0 done, 1 data error, 2 usage error.
#include <cstdio>
#include <map>
#include <memory>
#include <optional>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <CLI/CLI.hpp>
#include <opencv2/core/utility.hpp>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/global_alignment.h"
#include "mrvs/edge/vio_system.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/map/map_file.h"
#include "mrvs/test/in_process_cloud.h"
#include "mrvs/tools/request_dump.h"

namespace {

using mrvs::SE3d;
using mrvs::TimestampNs;

struct Args {
  std::string dataset, map, config, map_config;
  std::vector<std::string> overrides, map_overrides;
  bool per_request = false;
  std::string dump;
  std::string replay;
  int repeat = 1;
  std::string output;
  bool until_localised = false;
  int frames = 0;
  std::string log_level = "warn";
};

struct Cloud {
  std::shared_ptr<mrvs::test::InProcessCloud> service;
  std::shared_ptr<const mrvs::localise::Localiser> localiser;
};

mrvs::StatusOr<Cloud> make_cloud(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const auto doc,
                        mrvs::config::load_yaml_with_overrides(a.map_config, a.map_overrides));
  MRVS_ASSIGN_OR_RETURN(const auto query, mrvs::config::load_options<mrvs::map::QueryOptions>(doc, "query"));
  MRVS_ASSIGN_OR_RETURN(const auto loc,
                        mrvs::config::load_options<mrvs::localise::LocaliserOptions>(doc, "localise"));
  MRVS_ASSIGN_OR_RETURN(mrvs::map::VoxelMap vm, mrvs::map::load_voxel_map(a.map));
  auto shared = std::make_shared<const mrvs::map::VoxelMap>(std::move(vm));
  MRVS_ASSIGN_OR_RETURN(auto engine, mrvs::map::QueryEngine::create(shared, query));
  MRVS_ASSIGN_OR_RETURN(auto localiser, mrvs::localise::Localiser::create(shared, loc));
  Cloud c;
  c.localiser = std::make_shared<const mrvs::localise::Localiser>(std::move(localiser));
  c.service = std::make_shared<mrvs::test::InProcessCloud>(
      std::make_shared<const mrvs::map::QueryEngine>(std::move(engine)), c.localiser);
  return c;
}

/// sim0/T_map_world.yaml of a generated sequence (identity when absent).
SE3d map_from_world(const std::string& dataset) {
  try {
    const YAML::Node n = YAML::LoadFile(dataset + "/sim0/T_map_world.yaml")["T_map_world"]["data"];
    Eigen::Matrix4d T;
    for (int i = 0; i < 16; ++i) T(i / 4, i % 4) = n[i].as<double>();
    return SE3d::from_matrix(T);
  } catch (const std::exception&) {
    return SE3d();
  }
}

struct Error {
  double m = 0.0, deg = 0.0;
};

Error pose_error(const SE3d& est, const SE3d& truth) {
  return {(est.translation() - truth.translation()).norm(),
          std::abs(mrvs::edge::yaw_of(est * truth.inverse())) * mrvs::kRadToDeg};
}

/// Pose fixes (requests sent once in the map frame): how far the filter was from the truth at
/// the anchor, how far the answer would put it, and the answer's error in its own sigmas.
struct FixStats {
  std::vector<double> filter_m, filter_deg, answer_m, answer_deg, nees;
  int ok = 0;
};

void add_fix(const mrvs::test::InProcessCloud::Exchange& x, const SE3d& est, const SE3d& truth, bool print,
             FixStats* f) {
  const mrvs::localisation::Result& r = x.result;
  const Error before = pose_error(est, truth);
  const Error after = pose_error(r.T_m_o * est, truth);
  const bool is_ok = r.status == mrvs::localisation::Status::kOk;
  double nees = -1.0;
  if (is_ok) {
    ++f->ok;
    f->filter_m.push_back(before.m);
    f->filter_deg.push_back(before.deg);
    f->answer_m.push_back(after.m);
    f->answer_deg.push_back(after.deg);
    // The answer's error [position; yaw] at the anchor against its covariance there.
    const mrvs::Vec3d anchor_m = r.T_m_o * x.request.anchor_o;
    const Eigen::Matrix4d S = mrvs::edge::position_yaw_covariance(r.covariance, anchor_m, anchor_m);
    Eigen::Vector4d e;
    e.head<3>() = (r.T_m_o * est).translation() - truth.translation();
    e(3) = mrvs::edge::yaw_of((r.T_m_o * est) * truth.inverse());
    nees = e.dot(S.ldlt().solve(e));
    f->nees.push_back(nees);
  }
  if (print) {
    fmt::print(
        "FIX {} status '{}' filter {:.3f} m {:.2f} deg answer {:.3f} m {:.2f} deg nees {:.1f} sd {:.3f} m "
        "{:.2f} deg cloud {:.0f} ms\n",
        x.request.seq, mrvs::localisation::status_name(r.status), before.m, before.deg, after.m, after.deg,
        nees, std::sqrt(r.covariance(0, 0)), std::sqrt(r.covariance(5, 5)) * mrvs::kRadToDeg, r.time_ms);
  }
}

void print_fixes(const FixStats& f) {
  fmt::print("FIXES_OK: {}\nFIX_FILTER_ERROR_M_MEDIAN: {:.4f}\nFIX_FILTER_ERROR_DEG_MEDIAN: {:.3f}\n", f.ok,
             mrvs::quantile(f.filter_m, 0.5), mrvs::quantile(f.filter_deg, 0.5));
  fmt::print(
      "FIX_ANSWER_ERROR_M_MEDIAN: {:.4f}\nFIX_ANSWER_ERROR_DEG_MEDIAN: {:.3f}\nFIX_NEES_MEDIAN: {:.2f}\n",
      mrvs::quantile(f.answer_m, 0.5), mrvs::quantile(f.answer_deg, 0.5), mrvs::quantile(f.nees, 0.5));
}

/// --replay: every dumped request of a folder localised again with the given cloud options;
/// one line per request and the count of accepted and wrong answers.
int replay(const Args& a) {
  auto cloud = make_cloud(a);
  if (!cloud.ok())
    return fmt::print(stderr, "localise_probe: {}\n", std::string(cloud.status().message())),
           mrvs::kExitUsageError;
  const std::vector<std::string> files = mrvs::tools::request_dump_files(a.replay);
  int ok = 0, wrong = 0;
  std::vector<double> ms;
  for (const std::string& f : files) {
    const auto d = mrvs::tools::read_request_dump(f);
    if (!d.ok()) {
      fmt::print(stderr, "localise_probe: {} (see --dump)\n", std::string(d.status().message()));
      return mrvs::kExitDataError;
    }
    auto r = cloud->localiser->localise(d->request);
    std::vector<double> runs{r.time_ms};
    for (int k = 1; k < a.repeat; ++k) runs.push_back(cloud->localiser->localise(d->request).time_ms);
    r.time_ms = mrvs::quantile(runs, 0.5);
    const SE3d at(mrvs::Quatd::Identity(), d->request.anchor_o);
    const Error e = pose_error(r.T_m_o * at, d->truth * at);
    const bool is_ok = r.status == mrvs::localisation::Status::kOk;
    ok += is_ok;
    wrong += is_ok && (e.m > 0.1 || e.deg > 2.0);
    ms.push_back(r.time_ms);
    // Where the error lies (map axes), how well the truth itself fits, and where the fine stage
    // goes from the truth: a wrong answer that fits better than the truth is the data's, one the
    // fine stage leaves the truth for is the fine stage's, one it does not reach is the search's.
    const Eigen::Vector3d d_m = (r.T_m_o * at).translation() - (d->truth * at).translation();
    const auto at_truth = cloud->localiser->evaluate(d->request, d->truth);
    const auto from_truth = cloud->localiser->refine(d->request, d->truth);
    const Error ft = pose_error(from_truth.T_m_o * at, d->truth * at);
    fmt::print(
        "REPLAY {} status '{}' ambiguity {:.2f} fitness {:.2f} error {:.3f} m {:.2f} deg {:.0f} ms ({}) "
        "error_xyz {:.3f} {:.3f} {:.3f} truth_fitness {:.2f} from_truth {:.3f} m fitness {:.2f} "
        "hypotheses {} T_m_o {:.4f} {:.4f} {:.4f} yaw {:.5f} anchor_o {:.4f} {:.4f} {:.4f}\n",
        f, mrvs::localisation::status_name(r.status), r.ambiguity, r.fitness, e.m, e.deg, r.time_ms, r.detail,
        d_m.x(), d_m.y(), d_m.z(), at_truth.fitness, ft.m, from_truth.fitness, r.hypotheses,
        r.T_m_o.translation().x(), r.T_m_o.translation().y(), r.T_m_o.translation().z(),
        mrvs::edge::yaw_of(r.T_m_o), d->request.anchor_o.x(), d->request.anchor_o.y(),
        d->request.anchor_o.z());
  }
  fmt::print(
      "REPLAYED: {}\nANSWERS_OK: {}\nANSWERS_OK_WRONG: {}\nCLOUD_MS_MEDIAN: {:.1f}\nCLOUD_MS_P95: {:.1f}\n",
      files.size(), ok, wrong, mrvs::quantile(ms, 0.5), mrvs::quantile(ms, 0.95));
  return mrvs::kExitOk;
}

int run(const Args& a) {
  if (!a.replay.empty()) return replay(a);
  cv::setNumThreads(1);
  auto cfg = mrvs::config::load_yaml_with_overrides(a.config, a.overrides);
  if (!cfg.ok())
    return fmt::print(stderr, "localise_probe: {}\n", std::string(cfg.status().message())),
           mrvs::kExitUsageError;
  auto options = mrvs::config::load_options<mrvs::edge::EdgeOptions>(*cfg);
  auto cloud = options.ok() ? make_cloud(a) : mrvs::StatusOr<Cloud>(options.status());
  if (!cloud.ok())
    return fmt::print(stderr, "localise_probe: {}\n", std::string(cloud.status().message())),
           mrvs::kExitUsageError;
  mrvs::io::DatasetOptions dopt;
  dopt.path = a.dataset;
  auto data = mrvs::io::open_euroc_dataset(dopt);
  if (!data.ok() || !(*data)->has_groundtruth()) {
    fmt::print(
        stderr, "localise_probe: {}\n",
        data.ok() ? std::string("the dataset has no ground truth") : std::string(data.status().message()));
    return mrvs::kExitDataError;
  }
  const mrvs::io::Trajectory gt = mrvs::io::to_trajectory((*data)->groundtruth());
  const SE3d T_m_w = map_from_world(a.dataset);
  auto vio = mrvs::edge::VioSystem::create(*options, (*data)->calibration());
  if (!vio.ok())
    return fmt::print(stderr, "localise_probe: {}\n", std::string(vio.status().message())),
           mrvs::kExitUsageError;
  vio->set_map_service(cloud->service.get());
  const auto& frames = (*data)->stereo_frames();
  const auto& imu = (*data)->imu();
  const mrvs::DurationNs td = (*data)->calibration().cameras[0].time_offset_ns;
  std::map<TimestampNs, SE3d> odometry;  ///< estimator pose by camera time, odometry frame
  std::map<TimestampNs, SE3d> mapped;    ///< ... once in the map frame
  mrvs::io::Trajectory trajectory;       ///< IMU poses in the map frame (those before the lock moved by it)
  std::size_t next_imu = 0, next_gnss = 0;
  const auto& gnss = (*data)->gnss();
  TimestampNs init_ns = 0, lock_ns = 0;
  std::optional<Error> lock_error;
  const std::size_t n = a.frames > 0 ? std::min<std::size_t>(frames.size(), a.frames) : frames.size();
  for (std::size_t k = 0; k < n; ++k) {
    const auto& f = frames[k];
    while (next_imu < imu.size()) {
      if (!vio->feed_imu(imu[next_imu]).ok()) break;
      if (imu[next_imu++].t_ns >= vio->imu_time(f.t_ns)) break;
    }
    for (; next_gnss < gnss.size() && gnss[next_gnss].t_ns <= f.t_ns + td; ++next_gnss) {
      vio->feed_gnss(gnss[next_gnss], (*data)->T_b_gnss().value_or(SE3d()));
    }
    cloud->service->set_now(f.t_ns);
    auto left = (*data)->load_image(0, f.left);
    auto right = (*data)->load_image(1, f.right);
    if (!left.ok() || !right.ok()) return mrvs::kExitDataError;
    auto out = vio->feed_stereo(f.t_ns, *left, *right);
    if (!out.ok() || !out->estimate.T_w_b) continue;
    const auto& e = out->estimate;
    if (init_ns == 0) init_ns = f.t_ns;
    (e.in_map_frame ? mapped : odometry)[f.t_ns] = *e.T_w_b;
    if (e.T_m_o) {
      for (const auto& [t, T] : odometry) trajectory.push_back({t + td, *e.T_m_o * T});
    }
    if (e.in_map_frame) trajectory.push_back({e.t_imu_ns, *e.T_w_b});
    if (e.T_m_o && !lock_error) {
      lock_ns = f.t_ns;
      auto truth = mrvs::edge::interpolate_trajectory(gt, e.t_imu_ns);
      if (truth.ok()) lock_error = pose_error(*e.T_w_b, T_m_w * *truth);
      if (a.until_localised) break;
    }
  }
  int ok = 0, wrong = 0;
  std::vector<double> err_m, err_deg, cloud_ms;
  FixStats fixes;
  for (const auto& x : cloud->service->exchanges()) {
    const auto it = odometry.find(x.request.stamp_ns);
    auto truth = mrvs::edge::interpolate_trajectory(gt, x.request.stamp_ns + td);
    if (const auto m = mapped.find(x.request.stamp_ns); m != mapped.end() && truth.ok()) {
      add_fix(x, m->second, T_m_w * *truth, a.per_request, &fixes);
      continue;
    }
    if (it == odometry.end() || !truth.ok()) continue;
    const SE3d T_m_o_true = T_m_w * *truth * it->second.inverse();
    const Error e = pose_error(x.result.T_m_o * it->second, T_m_o_true * it->second);
    cloud_ms.push_back(x.result.time_ms);
    const bool is_ok = x.result.status == mrvs::localisation::Status::kOk;
    ok += is_ok;
    if (is_ok) {
      err_m.push_back(e.m);
      err_deg.push_back(e.deg);
      wrong += e.m > 0.1 || e.deg > 2.0;
    }
    if (!a.dump.empty()) {
      if (const auto st = mrvs::tools::write_request_dump(a.dump, x.request, x.result.T_m_o, T_m_o_true);
          !st.ok())
        return fmt::print(stderr, "localise_probe: {}\n", std::string(st.message())), mrvs::kExitDataError;
    }
    if (a.per_request) {
      const auto at_truth = cloud->localiser->evaluate(x.request, T_m_o_true);
      fmt::print(
          "REQUEST {} t {:.2f} s points {} status '{}' fitness {:.2f} ambiguity {:.2f} blocked {:.2f} "
          "error {:.3f} m {:.2f} deg cloud {:.0f} ms truth fitness {:.2f} blocked {:.2f} ({})\n",
          x.request.seq, mrvs::to_seconds(x.request.stamp_ns - init_ns), x.request.points.size(),
          mrvs::localisation::status_name(x.result.status), x.result.fitness, x.result.ambiguity,
          x.result.blocked, e.m, e.deg, x.result.time_ms, at_truth.fitness, at_truth.blocked,
          x.result.detail);
    }
  }
  fmt::print("REQUESTS: {}\nANSWERS_OK: {}\nANSWERS_OK_WRONG: {}\n", cloud->service->exchanges().size(), ok,
             wrong);
  fmt::print("ANSWER_ERROR_M_MEDIAN: {:.4f}\nANSWER_ERROR_DEG_MEDIAN: {:.3f}\n", mrvs::quantile(err_m, 0.5),
             mrvs::quantile(err_deg, 0.5));
  fmt::print("CLOUD_MS_MEDIAN: {:.1f}\nCLOUD_MS_P95: {:.1f}\n", mrvs::quantile(cloud_ms, 0.5),
             mrvs::quantile(cloud_ms, 0.95));
  fmt::print("LOCALISED: {}\nLOCALISED_AFTER_S: {:.3f}\n", lock_error ? 1 : 0,
             lock_error ? mrvs::to_seconds(lock_ns - init_ns) : -1.0);
  fmt::print("LOCK_ERROR_M: {:.4f}\nLOCK_ERROR_DEG: {:.3f}\n", lock_error ? lock_error->m : -1.0,
             lock_error ? lock_error->deg : -1.0);
  print_fixes(fixes);
  if (!a.output.empty()) {
    if (const auto st = mrvs::io::write_tum_trajectory(a.output, trajectory); !st.ok())
      return fmt::print(stderr, "localise_probe: {}\n", std::string(st.message())), mrvs::kExitDataError;
  }
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Measures the cloud's localisation on a EuRoC folder with ground truth, in process.",
               "localise_probe"};
  Args a;
  auto* dataset = app.add_option("--dataset", a.dataset, "EuRoC folder with ground truth");
  app.add_option("--replay", a.replay, "Localise the requests of a --dump folder again (no VIO)")
      ->check(CLI::ExistingDirectory)
      ->excludes(dataset);
  app.add_option("--map", a.map, "Voxel map (.mrvm)")->required()->check(CLI::ExistingFile);
  app.add_option("--config", a.config, "Edge tuning file (config/euroc.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--map-config", a.map_config, "Cloud tuning file (config/map_indoor.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides, "Edge option override, e.g. estimator.localisation.window_s=2");
  app.add_option("--map-set", a.map_overrides, "Cloud option override, e.g. localise.inlier_m=0.08");
  app.add_option("--frames", a.frames, "Frames to run (0 = all)");
  app.add_option("--repeat", a.repeat,
                 "--replay: localise each request this many times, report the median time")
      ->check(CLI::Range(1, 1000));
  app.add_flag("--per-request", a.per_request, "One line per localisation request");
  app.add_option("--dump", a.dump,
                 "Folder for one text file per request: true and answered T_map_odom, the points");
  app.add_flag("--until-localised", a.until_localised, "Stop at the first accepted answer");
  app.add_option(
      "--output", a.output,
      "TUM trajectory of the IMU in the map frame (from the lock on; the poses before it moved by it)");
  mrvs::add_log_level_option(app, a.log_level);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, a.log_level)) return *exit_code;
  if (a.dataset.empty() && a.replay.empty()) {
    fmt::print(stderr, "localise_probe: give --dataset (a EuRoC folder) or --replay (a --dump folder)\n");
    return mrvs::kExitUsageError;
  }
  return run(a);
}
