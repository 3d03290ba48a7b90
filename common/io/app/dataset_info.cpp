// dataset_info: opens a dataset folder with the same reader the edge client uses, checks
// it (every listed image exists, rows in time order, stereo pairing, IMU coverage) and
// prints its summary (with the optional ground truth and GNSS streams), calibration and
// warnings.
//
//   dataset_info --dataset DIR [--format euroc] [--stereo-tolerance 0] [--log-level info]
//
// Exit codes: 0 readable (warnings may be printed), 1 unreadable dataset, 2 usage error.
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/io/dataset.h"

namespace {

struct Args {
  std::string dataset;
  std::string format = "euroc";
  double stereo_tolerance_s = 0.0;
  std::string log_level = "info";
};

int run(const Args& args) {
  mrvs::io::DatasetOptions options;
  options.path = args.dataset;
  options.stereo_tolerance_ns = mrvs::from_seconds(args.stereo_tolerance_s);
  auto dataset = mrvs::io::open_dataset(args.format, options);
  if (!dataset.ok()) {
    fmt::print(stderr, "dataset_info: error: {}\n", std::string(dataset.status().message()));
    return mrvs::kExitDataError;
  }
  const mrvs::io::DatasetReader& reader = **dataset;
  fmt::print("{}\n", reader.summary().describe());
  fmt::print("calibration:\n{}\n", reader.calibration().describe());
  fmt::print("STEREO_FRAMES: {}\nIMU_SAMPLES: {}\nGROUNDTRUTH_STATES: {}\nGNSS_FIXES: {}\nWARNINGS: {}\n",
             reader.stereo_frames().size(), reader.imu().size(), reader.groundtruth().size(),
             reader.gnss().size(), reader.warnings().size());
  for (const std::string& warning : reader.warnings()) spdlog::warn("{}", warning);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Checks a stereo + IMU dataset folder (EuRoC ASL layout) and prints its summary.",
               "dataset_info"};
  Args args;
  app.add_option("--dataset", args.dataset, "Sequence folder (containing mav0/) or the mav0 folder itself")
      ->required();
  app.add_option("--format", args.format, "Dataset format")
      ->capture_default_str()
      ->check(CLI::IsMember(mrvs::io::dataset_formats()));
  app.add_option("--stereo-tolerance", args.stereo_tolerance_s,
                 "Seconds by which cam0 and cam1 stamps of one stereo pair may differ (EuRoC: 0, exact)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  mrvs::add_log_level_option(app, args.log_level);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
