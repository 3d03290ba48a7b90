// dataset_simulator: writes a synthetic EuRoC ASL sequence (stereo PNGs, IMU, ground truth,
// prior LiDAR map) along a real or synthesised trajectory. See tests/simulator/README.md.
//
//   dataset_simulator --trajectory tests/data/euroc_groundtruth/V1_01_easy.txt
//       --profile indoor --duration 30 --seed 1 --out /tmp/seq
//
// Exit codes: 0 success, 1 data or output error (nothing is left at --out), 2 usage error.
#include <omp.h>
#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/sim/generator.h"

namespace {

struct Args {
  std::string trajectory;
  std::string profile = "indoor";
  std::string preset = "easy";
  std::string out;
  std::string config;
  std::vector<std::string> overrides;
  std::int64_t seed = -1;
  double start_s = -1.0;
  double duration_s = -1.0;
  int threads = 0;
  bool overwrite = false;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--trajectory", a.trajectory,
                 "Trajectory to follow (indoor): TUM txt or EuRoC ground-truth csv, e.g. "
                 "tests/data/euroc_groundtruth/V1_01_easy.txt");
  app.add_option("--profile", a.profile, "indoor (EuRoC rig, Vicon-like room) | outdoor (KAIST-like car rig)")
      ->capture_default_str()
      ->check(CLI::IsMember({"indoor", "outdoor"}));
  app.add_option("--preset", a.preset,
                 "easy (realism knobs off) | realistic (noise, exposure, map changes) | hard (realistic plus "
                 "blur, auto-exposure, a dim area, people, calibration error, scanner survey indoors)")
      ->capture_default_str()
      ->check(CLI::IsMember(mrvs::sim::preset_names()));
  app.add_option("--out", a.out, "Sequence folder to create (it will contain mav0/ and sim0/)")->required();
  app.add_option("--seed", a.seed, "Seed of every random stream (default 1; same seed -> identical output)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--start", a.start_s,
                 "Window start, s after the first usable time (trajectory.window_start_s)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--duration", a.duration_s,
                 "Window length in s, 0 = to the end (trajectory.window_duration_s)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--config", a.config, "YAML file with any options (keys as printed at start-up)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides,
                 "Override one option, e.g. --set imu.noise_scale=2 --set render.read_noise_sigma=3 "
                 "--set map.misalignment_deg=0.5 --set scene.unmapped_objects=2 --set time_offset_ms=5 "
                 "(keys as printed at start-up)");
  app.add_option("--threads", a.threads, "OpenMP threads, 0 = all cores (the output does not depend on it)")
      ->check(CLI::NonNegativeNumber);
  app.add_flag("--overwrite", a.overwrite,
               "Replace an existing --out folder (only once the new one is complete)");
  mrvs::add_log_level_option(app, a.log_level);
}

/// Profile defaults, then the preset, the --config file, the shorthand flags and --set.
mrvs::StatusOr<mrvs::sim::SimulatorOptions> resolve_options(const Args& a, mrvs::sim::SceneProfile profile) {
  mrvs::sim::SimulatorOptions options = mrvs::sim::default_options(profile);
  MRVS_RETURN_IF_ERROR(mrvs::sim::apply_preset(a.preset, profile, options));
  std::vector<std::string> overrides;
  if (a.seed >= 0) overrides.push_back(fmt::format("seed={}", a.seed));
  if (a.start_s >= 0) overrides.push_back(fmt::format("trajectory.window_start_s={}", a.start_s));
  if (a.duration_s >= 0) overrides.push_back(fmt::format("trajectory.window_duration_s={}", a.duration_s));
  overrides.insert(overrides.end(), a.overrides.begin(), a.overrides.end());
  MRVS_ASSIGN_OR_RETURN(const mrvs::config::YamlDocument doc,
                        mrvs::config::load_yaml_with_overrides(a.config, overrides));
  MRVS_RETURN_IF_ERROR(mrvs::config::update_options(doc, "", options));
  return options;
}

/// One updating line on a terminal, a line per 10 % otherwise.
mrvs::sim::ProgressCallback make_progress() {
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  return [tty, last_decile = -1](const mrvs::sim::GeneratorProgress& p) mutable {
    if (p.stage != "render") {
      spdlog::info("{}...", p.stage == "map" ? "sampling the prior map" : "building the scene");
      return;
    }
    const int decile = static_cast<int>(10 * p.done / std::max<std::int64_t>(p.total, 1));
    if (tty) {
      fmt::print(stderr, "\rrendering frame {}/{} ({}%){}", p.done, p.total, 100 * p.done / p.total,
                 p.done == p.total ? "\n" : "");
    } else if (decile != last_decile) {
      spdlog::info("rendering frame {}/{} ({}%)", p.done, p.total, 100 * p.done / p.total);
    }
    last_decile = decile;
  };
}

int run(const Args& a) {
  auto profile = mrvs::sim::parse_profile(a.profile);
  if (!profile.ok()) return mrvs::kExitUsageError;
  auto options = resolve_options(a, *profile);
  if (!options.ok()) {
    fmt::print(stderr, "dataset_simulator: error: {}\n", std::string(options.status().message()));
    return mrvs::kExitUsageError;
  }
  if (a.threads > 0) omp_set_num_threads(a.threads);
  spdlog::info("{}: profile {}, preset {}, options:\n{}", mrvs::sim::generator_version(), a.profile, a.preset,
               mrvs::config::options_to_yaml(*options));
  mrvs::sim::GeneratorRequest request{*profile, a.trajectory, a.out, a.overwrite, a.preset, *options};
  auto report = mrvs::sim::generate_dataset(request, make_progress());
  if (!report.ok()) {
    fmt::print(stderr, "dataset_simulator: error: {}\n", std::string(report.status().message()));
    return mrvs::kExitDataError;
  }
  fmt::print(
      "OUT: {}\nFRAMES: {}\nIMU_SAMPLES: {}\nMAP_POINTS: {}\nGNSS_FIXES: {}\nSECONDS_RENDER: {:.2f}\n"
      "SECONDS_MAP: {:.2f}\nSECONDS_TOTAL: {:.2f}\n",
      report->out.string(), report->frames, report->imu_samples, report->map_points, report->gnss_fixes,
      report->seconds_render, report->seconds_map, report->seconds_total);
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes a synthetic EuRoC ASL stereo + IMU sequence with ground truth and a prior LiDAR map.",
               "dataset_simulator"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
