#include "mrvs/test/generated_sequence.h"

#include <fmt/format.h>

#include "mrvs/test/shared_data.h"

namespace mrvs::test {

sim::GeneratorRequest indoor_sequence_request(const std::string& trajectory_file, double start_s,
                                              double duration_s, const std::string& preset) {
  sim::GeneratorRequest r;
  r.profile = sim::SceneProfile::kIndoor;
  r.trajectory = euroc_groundtruth_file(trajectory_file);
  r.preset = preset;
  r.options = sim::default_options(r.profile);
  (void)sim::apply_preset(preset, r.profile, r.options);
  r.options.trajectory.window_start_s = start_s;
  r.options.trajectory.window_duration_s = duration_s;
  // A thin surface survey: the unit tests that need the shipped survey copy its map options.
  r.options.map.model = sim::MapModel::kSurface;
  r.options.map.spacing_near_m = r.options.map.spacing_far_m = 0.2;
  return r;
}

StatusOr<std::filesystem::path> generated_sequence(const std::string& name, sim::GeneratorRequest request) {
  const std::filesystem::path out = std::filesystem::path(MRVS_TEST_DATA_DIR) / name;
  std::error_code ec;
  if (std::filesystem::is_directory(out / "mav0", ec)) return out;
  request.out = out;
  request.overwrite = false;
  const auto report = sim::generate_dataset(request);
  if (!report.ok() && !std::filesystem::is_directory(out / "mav0", ec)) {
    return absl::InternalError(fmt::format("cannot generate test sequence {}: {}", out.string(),
                                           std::string(report.status().message())));
  }
  return out;
}

}  // namespace mrvs::test
