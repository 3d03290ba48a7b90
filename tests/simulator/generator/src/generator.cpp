#include "mrvs/sim/generator.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <future>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/core.hpp>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/file.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/gnss.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/sim/exposure_log.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/sim/people_plan.h"
#include "mrvs/sim/photometry.h"
#include "mrvs/sim/png_writer.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/rig.h"
#include "mrvs/sim/staging_dir.h"
#include "mrvs/sim/stereo_renderer.h"
#include "mrvs/sim/time_grid.h"

namespace mrvs::sim {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

/// The same error with `what` in front of its message.
Status with_context(const Status& status, const std::string& what) {
  return Status(status.code(), fmt::format("{}: {}", what, std::string(status.message())));
}

StatusOr<io::Trajectory> load_motion_input(const GeneratorRequest& r, World& world) {
  if (r.profile == SceneProfile::kOutdoor) {
    if (!r.trajectory.empty()) {
      return absl::InvalidArgumentError(
          "the outdoor profile drives its own car route (options route.*); omit --trajectory");
    }
    MRVS_ASSIGN_OR_RETURN(world.route, synthesize_car_route(r.options.route, r.options.seed));
    world.source = fmt::format("synthetic car route ({:.1f} m)", world.route->length_m);
    return world.route->trajectory;
  }
  if (r.trajectory.empty()) {
    return absl::InvalidArgumentError(
        "the indoor profile follows a trajectory file: give --trajectory (TUM txt or EuRoC ground-truth csv, "
        "e.g. tests/data/euroc_groundtruth/V1_01_easy.txt)");
  }
  io::Warnings warnings;
  auto input = io::read_trajectory(r.trajectory, {}, &warnings);
  if (!input.ok()) return with_context(input.status(), fmt::format("trajectory {}", r.trajectory.string()));
  for (const std::string& w : warnings) spdlog::warn("{}", w);
  world.source = r.trajectory.string();
  return input;
}

Status plan_motion(const GeneratorRequest& r, World& world) {
  MRVS_ASSIGN_OR_RETURN(io::Trajectory input, load_motion_input(r, world));
  auto spline = SplineTrajectory::fit(input, r.options.trajectory);
  if (!spline.ok()) return with_context(spline.status(), fmt::format("trajectory {}", world.source));
  world.spline = std::move(*spline);
  TimeGridOptions grid;
  grid.imu_rate_hz = static_cast<int>(std::lround(world.rig.imu.rate_hz));
  grid.camera_rate_hz = static_cast<int>(std::lround(world.rig.cameras[0].rate_hz));
  grid.camera_time_offset_ns = std::llround(world.time_offset_ms * 1e6);
  MRVS_ASSIGN_OR_RETURN(world.grid,
                        make_time_grid(world.spline->t_begin_ns(), world.spline->t_end_ns(), grid));
  if (world.grid.camera_true_ns.size() < 2) {
    return absl::InvalidArgumentError(fmt::format(
        "trajectory {}: the time window holds {} camera frame(s); give a longer window (trajectory.window_*)",
        world.source, world.grid.camera_true_ns.size()));
  }
  MRVS_ASSIGN_OR_RETURN(world.imu, simulate_imu(*world.spline, world.grid.imu_ns, r.options.imu,
                                                static_cast<std::uint64_t>(r.options.seed)));
  return absl::OkStatus();
}

Status plan_states(World& world) {
  const std::size_t n = world.grid.imu_ns.size();
  world.states.resize(n);
  Quatd previous = Quatd::Identity();
  for (std::size_t k = 0; k < n; ++k) {
    MRVS_ASSIGN_OR_RETURN(const Kinematics kin, world.spline->evaluate(world.grid.imu_ns[k]));
    Quatd q = kin.T_w_b.quaternion();
    if (k > 0 && q.coeffs().dot(previous.coeffs()) < 0) q.coeffs() = -q.coeffs();  // continuous sign
    previous = q;
    io::GroundTruthState& s = world.states[k];
    s.t_ns = world.grid.imu_ns[k];
    s.T_w_b = SE3d(q, kin.T_w_b.translation());
    s.v_w_b = kin.v_w;
    s.bias_gyro = world.imu[k].bias_gyro;
    s.bias_accel = world.imu[k].bias_accel;
  }
  // The scene and the survey cover the whole trajectory, not only the window: every window
  // of one source trajectory shares one room and one prior map, as with a real survey.
  constexpr DurationNs kStepNs = 50'000'000;
  for (TimestampNs t = world.spline->support_begin_ns(); t <= world.spline->support_end_ns(); t += kStepNs) {
    MRVS_ASSIGN_OR_RETURN(const Kinematics kin, world.spline->evaluate(t));
    world.body_positions.push_back(kin.T_w_b.translation());
    world.keep_clear.push_back(kin.T_w_b.translation());
    for (const auto& cam : world.calibration.cameras) {
      world.keep_clear.push_back((kin.T_w_b * cam.T_b_c).translation());
    }
  }
  return absl::OkStatus();
}

/// render.dim_area: centred on the body position at a drawn point of the whole trajectory.
Illumination plan_light(const RenderOptions& o, const World& world, std::uint64_t seed) {
  Illumination light;
  if (!o.dim_area || world.body_positions.empty()) return light;
  const double u = CounterRng(seed, Stream::kIllumination).uniform(0);
  const std::size_t i =
      std::min(world.body_positions.size() - 1,
               static_cast<std::size_t>(u * static_cast<double>(world.body_positions.size())));
  light.enabled = true;
  light.centre_xy = world.body_positions[i].head<2>().cast<float>();
  light.level = static_cast<float>(o.dim_level);
  light.radius_m = static_cast<float>(o.dim_radius_m);
  return light;
}

/// Indoor: a room around the trajectory. Outdoor: streets along the route's straights.
StatusOr<Scene> build_scene(const GeneratorRequest& r, const World& world, std::uint64_t seed) {
  if (!world.route) return make_scene(r.profile, r.options.scene.value, world.keep_clear, seed);
  std::vector<StreetLeg> legs;
  for (const RouteStraight& straight : world.route->straights)
    legs.push_back({straight.start_xy, straight.end_xy});
  return make_street_scene(r.options.scene.value, legs, world.keep_clear, seed);
}

std::string map_comment(const GeneratorRequest& r) {
  return fmt::format("synthetic survey scan; generator {}; scene {}; seed {}; frame world(R)",
                     generator_version(), profile_name(r.profile), r.options.seed);
}

/// The body poses of an exposure and their times.
struct ExposureSamples {
  std::vector<SE3d> body;
  std::vector<TimestampNs> t_ns;
};

/// Body poses over frame k's exposure of `exposure_ms` (render.motion_blur; centred on its
/// true time, within the spline's support), as many as the faster-moving camera needs
/// (exposure_samples); one, the frame's pose, without blur.
StatusOr<ExposureSamples> exposure_poses(const StereoRenderer& renderer, const World& world, std::int64_t k,
                                         double exposure_ms) {
  const RenderOptions& o = renderer.options();
  const TimestampNs t = world.grid.camera_true_ns[static_cast<std::size_t>(k)];
  const ExposureSamples sharp{{world.frame_pose(static_cast<std::size_t>(k))}, {t}};
  if (!o.motion_blur) return sharp;
  const DurationNs half = static_cast<DurationNs>(std::llround(0.5e6 * exposure_ms));
  const TimestampNs a = std::max(t - half, world.spline->support_begin_ns());
  const TimestampNs b = std::min(t + half, world.spline->support_end_ns());
  MRVS_ASSIGN_OR_RETURN(const Kinematics start, world.spline->evaluate(a));
  MRVS_ASSIGN_OR_RETURN(const Kinematics end, world.spline->evaluate(b));
  int n = 1;
  for (int c = 0; c < 2; ++c) {
    n = std::max(
        n, renderer.exposure_samples(c, renderer.camera_pose(c, start.T_w_b),
                                     renderer.camera_pose(c, end.T_w_b), o.blur_step_px, o.blur_max_samples));
  }
  if (n == 1) return sharp;
  ExposureSamples samples;
  for (int i = 0; i < n; ++i) {  // the middles of n equal parts of the exposure
    const TimestampNs ti =
        a + static_cast<DurationNs>(std::llround((i + 0.5) * static_cast<double>(b - a) / n));
    MRVS_ASSIGN_OR_RETURN(const Kinematics kin, world.spline->evaluate(ti));
    samples.body.push_back(kin.T_w_b);
    samples.t_ns.push_back(ti);
  }
  return samples;
}

/// Both images of frame k, integrated over its exposure (exposure_poses); `record` gets the
/// exposure, gains and sub-sample count.
StatusOr<std::array<cv::Mat, 2>> render_frame(const StereoRenderer& renderer, const World& world,
                                              std::int64_t k, FrameExposure* record) {
  MRVS_ASSIGN_OR_RETURN(const ExposureSamples samples,
                        exposure_poses(renderer, world, k, record->exposure_ms));
  record->samples = static_cast<int>(samples.body.size());
  const FrameInfo info{k, record->gain, record->analog_gain,
                       world.grid.camera_true_ns[static_cast<std::size_t>(k)]};
  if (samples.body.size() == 1) return renderer.render_stereo(samples.body.front(), info);
  std::array<cv::Mat, 2> images;
  for (int c = 0; c < 2; ++c) {
    std::vector<SE3d> cam;
    for (const SE3d& T_w_b : samples.body) cam.push_back(renderer.camera_pose(c, T_w_b));
    MRVS_RETURN_IF_ERROR(
        renderer.render_exposure(c, cam, info, &images[static_cast<std::size_t>(c)], samples.t_ns));
  }
  return images;
}

/// Pixels of frame k's sharp views whose nearest hit is a person.
PeoplePixels count_people(const StereoRenderer& renderer, const World& world, std::int64_t k) {
  const std::size_t i = static_cast<std::size_t>(k);
  PeoplePixels row{world.grid.camera_stamp_ns[i], {0, 0}};
  if (world.people.empty()) return row;
  for (int c = 0; c < 2; ++c) {
    row.pixels[static_cast<std::size_t>(c)] =
        renderer.people_pixels(c, renderer.camera_pose(c, world.frame_pose(i)), world.grid.camera_true_ns[i]);
  }
  return row;
}

/// The exposure controller of a sequence: fixed at render.exposure_ms without
/// render.auto_exposure; otherwise AutoExposure, started converged on frame 0 (a sharp
/// metering render of cam0 at the reference exposure).
class ExposureControl {
 public:
  static StatusOr<ExposureControl> create(const StereoRenderer& renderer, const World& world,
                                          const std::vector<double>& walk) {
    ExposureControl control;
    control.walk_ = &walk;
    control.reference_ms_ = renderer.options().exposure_ms;
    if (!renderer.options().auto_exposure) return control;
    const double interval_ms = 1e3 / world.rig.cameras[0].rate_hz;
    MRVS_ASSIGN_OR_RETURN(AutoExposure ae, AutoExposure::create(renderer.options(), interval_ms));
    MRVS_ASSIGN_OR_RETURN(
        const cv::Mat metering,
        renderer.render(0, renderer.camera_pose(0, world.frame_pose(0)), FrameInfo{0, walk[0]}));
    ae.settle(cv::mean(metering)[0]);
    control.ae_ = ae;
    return control;
  }
  /// The exposure of frame k (before it is rendered).
  FrameExposure next(std::int64_t k, TimestampNs stamp) const {
    FrameExposure e;
    e.t_ns = stamp;
    e.exposure_ms = reference_ms_;
    e.gain = (*walk_)[static_cast<std::size_t>(k)];
    if (!ae_) return e;
    const ExposureSetting s = ae_->setting();
    e.exposure_ms = s.exposure_ms;
    e.analog_gain = s.analog_gain;
    e.gain *= ae_->relative_gain();
    return e;
  }
  /// After frame k: its cam0 image's mean DN drives the auto-exposure.
  void observe(FrameExposure* e, const cv::Mat& cam0) {
    e->mean_dn = cv::mean(cam0)[0];
    if (ae_) ae_->observe(e->mean_dn);
  }

 private:
  const std::vector<double>* walk_ = nullptr;
  double reference_ms_ = 5.0;
  std::optional<AutoExposure> ae_;
};

/// Renders every frame; PNG encoding of frame k overlaps the rendering of frame k + 1.
/// What rendering leaves besides the PNGs: the image lists and the per-frame truth.
struct RenderedFrames {
  std::array<std::vector<io::ImageRecord>, 2> records;
  std::vector<FrameExposure> exposures;
  std::vector<PeoplePixels> people;
};

Status render_frames(const StereoRenderer& renderer, const World& world, const fs::path& mav0,
                     std::uint64_t seed, const ProgressCallback& progress, RenderedFrames& out) {
  const std::int64_t n = static_cast<std::int64_t>(world.grid.camera_true_ns.size());
  const std::vector<double> walk = exposure_gains(seed, n, renderer.options());
  MRVS_ASSIGN_OR_RETURN(ExposureControl control, ExposureControl::create(renderer, world, walk));
  std::future<Status> pending;
  for (std::int64_t k = 0; k < n; ++k) {
    const TimestampNs stamp = world.grid.camera_stamp_ns[k];
    FrameExposure exposure = control.next(k, stamp);
    auto images = render_frame(renderer, world, k, &exposure);
    if (!images.ok()) return with_context(images.status(), fmt::format("rendering frame {}", k));
    control.observe(&exposure, (*images)[0]);
    out.exposures.push_back(exposure);
    out.people.push_back(count_people(renderer, world, k));
    if (pending.valid()) MRVS_RETURN_IF_ERROR(pending.get());
    std::array<fs::path, 2> paths;
    for (int c = 0; c < 2; ++c) {
      paths[c] = mav0 / fmt::format("cam{}/data/{}.png", c, stamp);
      out.records[c].push_back({stamp, paths[c]});
    }
    pending = std::async(std::launch::async, [imgs = std::move(*images), paths]() -> Status {
      for (int c = 0; c < 2; ++c) MRVS_RETURN_IF_ERROR(write_png(paths[c], imgs[c]));
      return absl::OkStatus();
    });
    if (progress) progress({"render", k + 1, n});
  }
  return pending.valid() ? pending.get() : absl::OkStatus();
}

Status write_sensor_files(const World& world, const SimulatorOptions& o, const fs::path& mav0,
                          const std::array<std::vector<io::ImageRecord>, 2>& records) {
  for (int c = 0; c < 2; ++c) {
    const fs::path dir = mav0 / fmt::format("cam{}", c);
    MRVS_RETURN_IF_ERROR(
        write_file_atomically(dir / "sensor.yaml", camera_sensor_yaml(world.rig.cameras[c])));
    MRVS_RETURN_IF_ERROR(io::write_euroc_image_csv(dir / "data.csv", records[c]));
  }
  RigImu imu = world.rig.imu;  // the densities actually simulated
  const ImuNoiseDensities d = effective_noise_densities(o.imu);
  imu.gyroscope_noise_density = d.gyroscope_noise_density;
  imu.gyroscope_random_walk = d.gyroscope_random_walk;
  imu.accelerometer_noise_density = d.accelerometer_noise_density;
  imu.accelerometer_random_walk = d.accelerometer_random_walk;
  MRVS_RETURN_IF_ERROR(write_file_atomically(mav0 / "imu0/sensor.yaml", imu_sensor_yaml(imu)));
  std::vector<io::ImuSample> measured;
  measured.reserve(world.imu.size());
  for (const ImuSimSample& s : world.imu) measured.push_back(s.measured);
  MRVS_RETURN_IF_ERROR(io::write_euroc_imu_csv(mav0 / "imu0/data.csv", measured));
  const fs::path gt = mav0 / "state_groundtruth_estimate0";
  MRVS_RETURN_IF_ERROR(write_file_atomically(
      gt / "sensor.yaml", groundtruth_sensor_yaml(fmt::format(
                              "Synthetic ground truth (cubic B-spline, knot {} ns, generator {}, seed {}).",
                              world.spline->knot_spacing_ns(), generator_version(), o.seed))));
  return io::write_euroc_groundtruth(gt / "data.csv", world.states);
}

std::string config_yaml(const GeneratorRequest& r, const World& world) {
  config::WriteStyle style;
  style.mark_defaults = false;
  return fmt::format(
      "# dataset_simulator configuration of this sequence (load it back with --config).\n"
      "# generator: {}\n# profile: {}\n# preset: {}\n# source: {}\n# rig: {}\n"
      "# t0_ns: {}\n# t_end_ns: {}\n# frames: {}\n# imu_samples: {}\n# knot_spacing_ns: {}\n"
      "# gravity_w: [0, 0, -{}]\n{}",
      generator_version(), profile_name(r.profile), r.preset, world.source, world.rig.name,
      world.grid.imu_ns.front(), world.grid.imu_ns.back(), world.grid.camera_true_ns.size(),
      world.grid.imu_ns.size(), world.spline->knot_spacing_ns(), r.options.imu.gravity_magnitude,
      config::options_to_yaml(r.options, "", style));
}

/// sim0/request.yaml: what load_generator_request needs besides config.yaml.
std::string request_yaml(const GeneratorRequest& r) {
  const std::string trajectory =
      r.trajectory.empty() ? "" : fs::absolute(r.trajectory).lexically_normal().string();
  return fmt::format(
      "# How this sequence was made (read by load_generator_request; options in config.yaml).\n"
      "generator: \"{}\"\nprofile: {}\npreset: {}\ntrajectory: \"{}\"\n",
      generator_version(), profile_name(r.profile), r.preset, trajectory);
}

Status write_truth_files(const GeneratorRequest& r, const World& world, const fs::path& sim0) {
  const PriorMap& map = world.map;
  MRVS_RETURN_IF_ERROR(write_file_atomically(sim0 / "config.yaml", config_yaml(r, world)));
  MRVS_RETURN_IF_ERROR(write_file_atomically(sim0 / "request.yaml", request_yaml(r)));
  MRVS_RETURN_IF_ERROR(write_file_atomically(sim0 / "scene.yaml", world.scene->to_yaml()));
  std::vector<io::ImuSample> noiseless;
  noiseless.reserve(world.imu.size());
  for (const ImuSimSample& s : world.imu) noiseless.push_back(s.noiseless);
  MRVS_RETURN_IF_ERROR(io::write_euroc_imu_csv(sim0 / "imu_noiseless.csv", noiseless));
  MRVS_RETURN_IF_ERROR(write_transform_yaml(sim0 / "T_map_world.yaml", map.T_map_world));
  if (!r.options.write_clean_map) return absl::OkStatus();
  return write_ply(sim0 / "pointcloud_clean.ply", map.clean_points, map_comment(r) + "; clean (no noise)");
}

/// mav0/gnss0/data.csv and sensor.yaml, sim0/gnss_truth.csv (only with gnss.enabled).
Status write_gnss_files(const GeneratorRequest& r, const World& world, const fs::path& root) {
  if (world.gnss.empty()) return absl::OkStatus();
  const GnssSimOptions& o = r.options.gnss;
  std::vector<io::GnssFix> fixes;
  fixes.reserve(world.gnss.size());
  for (const GnssSimFix& f : world.gnss) {
    fixes.push_back({f.t_ns, f.p_measured_map, o.sigma_horizontal_m, o.sigma_vertical_m});
  }
  const fs::path dir = root / "mav0/gnss0";
  MRVS_RETURN_IF_ERROR(io::write_euroc_gnss_csv(dir / "data.csv", fixes));
  const std::string comment = fmt::format(
      "Synthetic GNSS receiver (antenna positions in the map frame of pointcloud0, generator {}, "
      "seed {}).",
      generator_version(), r.options.seed);
  MRVS_RETURN_IF_ERROR(write_file_atomically(dir / "sensor.yaml", gnss_sensor_yaml(o, comment)));
  return write_gnss_truth_csv(root / "sim0/gnss_truth.csv", world.gnss);
}

Status make_folders(const fs::path& root) {
  for (const char* sub :
       {"mav0/cam0/data", "mav0/cam1/data", "mav0/imu0", "mav0/state_groundtruth_estimate0",
        "mav0/pointcloud0", "sim0", "sim0/true_calibration/cam0", "sim0/true_calibration/cam1"}) {
    std::error_code ec;
    fs::create_directories(root / sub, ec);
    if (ec)
      return absl::PermissionDeniedError(
          fmt::format("cannot create {}: {}", (root / sub).string(), ec.message()));
  }
  return absl::OkStatus();
}

}  // namespace

StatusOr<GeneratorRequest> load_generator_request(const fs::path& sequence) {
  const fs::path sim0 = sequence / "sim0";
  MRVS_ASSIGN_OR_RETURN(const config::YamlDocument request, config::load_yaml_file(sim0 / "request.yaml"));
  GeneratorRequest r;
  r.out = sequence;
  try {
    MRVS_ASSIGN_OR_RETURN(r.profile, parse_profile(request.root["profile"].as<std::string>()));
    r.preset = request.root["preset"].as<std::string>();
    r.trajectory = request.root["trajectory"].as<std::string>();
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(fmt::format("{}: needs keys profile, preset and trajectory ({})",
                                                  (sim0 / "request.yaml").string(), e.what()));
  }
  if (!r.trajectory.empty() && !fs::exists(r.trajectory)) {
    return absl::NotFoundError(
        fmt::format("{} was made from {}, which no longer exists", sequence.string(), r.trajectory.string()));
  }
  r.options = default_options(r.profile);
  MRVS_RETURN_IF_ERROR(apply_preset(r.preset, r.profile, r.options));
  MRVS_ASSIGN_OR_RETURN(const config::YamlDocument options, config::load_yaml_file(sim0 / "config.yaml"));
  MRVS_RETURN_IF_ERROR(config::update_options(options, "", r.options));
  return r;
}

std::string generator_version() { return fmt::format("mrvs dataset_simulator {}", MRVS_VERSION); }

StatusOr<World> build_world(const GeneratorRequest& r, const ProgressCallback& progress) {
  World world;
  world.rig = r.profile == SceneProfile::kIndoor ? euroc_rig() : kaist_like_rig();
  const std::uint64_t seed = static_cast<std::uint64_t>(r.options.seed);
  TrueCalibration truth =
      draw_true_calibration(world.rig, r.options.time_offset_ms, r.options.calib_error, seed);
  world.true_rig = std::move(truth.rig);
  world.time_offset_ms = truth.time_offset_ms;
  auto calibration = world.true_rig.calibration();
  if (!calibration.ok())
    return with_context(calibration.status(), "the drawn true calibration (calib_error.*)");
  world.calibration = std::move(*calibration);
  MRVS_RETURN_IF_ERROR(plan_motion(r, world));
  if (r.options.gnss.enabled) {  // a rate off the IMU grid fails before the scene and map are built
    MRVS_RETURN_IF_ERROR(gnss_period_ns(r.options.gnss.rate_hz, world.grid.imu_period_ns).status());
  }
  MRVS_RETURN_IF_ERROR(plan_states(world));
  world.light = plan_light(r.options.render, world, seed);
  if (progress) progress({"scene", 0, 1});
  MRVS_ASSIGN_OR_RETURN(world.scene, build_scene(r, world, seed));
  if (progress) progress({"map", 0, 1});
  MRVS_ASSIGN_OR_RETURN(world.map, sample_prior_map(*world.scene, world.body_positions, r.options.map, seed));
  MRVS_ASSIGN_OR_RETURN(world.people, plan_people(r.options.people, world, seed));
  if (r.options.gnss.enabled) {
    MRVS_ASSIGN_OR_RETURN(world.gnss,
                          simulate_gnss(world.states, world.map.T_map_world, r.options.gnss, seed));
  }
  return world;
}

StatusOr<GeneratorReport> generate_dataset(const GeneratorRequest& r, const ProgressCallback& progress) {
  const Clock::time_point start = Clock::now();
  // Check the destination first: a bad --out fails before any work.
  MRVS_ASSIGN_OR_RETURN(StagingDir staging, StagingDir::create(r.out, r.overwrite));
  GeneratorReport report;
  MRVS_ASSIGN_OR_RETURN(const World world, build_world(r, progress));
  report.seconds_map = seconds_since(start);
  MRVS_RETURN_IF_ERROR(make_folders(staging.path()));
  const fs::path mav0 = staging.path() / "mav0";
  const PriorMap& map = world.map;
  MRVS_RETURN_IF_ERROR(
      write_ply(mav0 / "pointcloud0/data.ply", map.points, map_comment(r), ply_format(r.options.map)));
  MRVS_RETURN_IF_ERROR(
      write_file_atomically(mav0 / "pointcloud0/sensor.yaml", pointcloud_sensor_yaml(map_comment(r))));

  const Clock::time_point stage = Clock::now();
  const std::uint64_t seed = static_cast<std::uint64_t>(r.options.seed);
  MRVS_ASSIGN_OR_RETURN(StereoRenderer renderer,
                        StereoRenderer::create(*world.scene, world.calibration, r.options.render, seed));
  MRVS_ASSIGN_OR_RETURN(renderer, renderer.with_illumination(world.light));
  renderer = renderer.with_people(world.people);
  RenderedFrames frames;
  MRVS_RETURN_IF_ERROR(render_frames(renderer, world, mav0, seed, progress, frames));
  report.seconds_render = seconds_since(stage);

  MRVS_RETURN_IF_ERROR(write_sensor_files(world, r.options, mav0, frames.records));
  MRVS_RETURN_IF_ERROR(write_truth_files(r, world, staging.path() / "sim0"));
  MRVS_RETURN_IF_ERROR(write_exposure_csv(staging.path() / "sim0/exposure.csv", frames.exposures));
  MRVS_RETURN_IF_ERROR(write_illumination_yaml(staging.path() / "sim0/illumination.yaml", world.light));
  MRVS_RETURN_IF_ERROR(write_people_yaml(staging.path() / "sim0/people.yaml", world.people));
  MRVS_RETURN_IF_ERROR(write_people_csv(staging.path() / "sim0/people.csv", frames.people));
  MRVS_RETURN_IF_ERROR(write_true_calibration(staging.path() / "sim0/true_calibration",
                                              TrueCalibration{world.true_rig, world.time_offset_ms}));
  MRVS_RETURN_IF_ERROR(write_gnss_files(r, world, staging.path()));
  MRVS_RETURN_IF_ERROR(staging.commit());

  report.out = staging.destination();
  report.frames = static_cast<std::int64_t>(world.grid.camera_true_ns.size());
  report.imu_samples = static_cast<std::int64_t>(world.grid.imu_ns.size());
  report.map_points = static_cast<std::int64_t>(map.points.size());
  report.gnss_fixes = static_cast<std::int64_t>(world.gnss.size());
  report.t_begin_ns = world.grid.imu_ns.front();
  report.t_end_ns = world.grid.imu_ns.back();
  report.seconds_total = seconds_since(start);
  return report;
}

}  // namespace mrvs::sim
