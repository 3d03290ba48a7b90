#include "mrvs/sim/time_grid.h"

#include <fmt/format.h>

namespace mrvs::sim {

TimeGridOptions euroc_time_grid() { return TimeGridOptions{}; }

TimeGridOptions kaist_time_grid() {
  TimeGridOptions options;
  options.imu_rate_hz = 100;
  options.camera_rate_hz = 10;
  return options;
}

StatusOr<TimeGrid> make_time_grid(TimestampNs t0_ns, TimestampNs t_end_ns, const TimeGridOptions& options) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "time_grid"));
  if (t_end_ns < t0_ns) {
    return absl::InvalidArgumentError(
        fmt::format("time grid: end {} ns is before start {} ns", t_end_ns, t0_ns));
  }
  if (kNanosecondsPerSecond % options.imu_rate_hz != 0) {
    return absl::InvalidArgumentError(
        fmt::format("time grid: imu_rate_hz = {} has no integer ns period (1e9 is not divisible by it)",
                    options.imu_rate_hz));
  }
  if (options.imu_rate_hz % options.camera_rate_hz != 0) {
    return absl::InvalidArgumentError(
        fmt::format("time grid: camera_rate_hz = {} does not divide imu_rate_hz = {}", options.camera_rate_hz,
                    options.imu_rate_hz));
  }
  TimeGrid grid;
  grid.imu_period_ns = kNanosecondsPerSecond / options.imu_rate_hz;
  grid.imu_per_camera = options.imu_rate_hz / options.camera_rate_hz;
  const std::int64_t count = (t_end_ns - t0_ns) / grid.imu_period_ns + 1;
  grid.imu_ns.reserve(static_cast<std::size_t>(count));
  for (std::int64_t k = 0; k < count; ++k) grid.imu_ns.push_back(t0_ns + k * grid.imu_period_ns);
  for (std::int64_t k = options.first_camera_imu_index; k < count; k += grid.imu_per_camera) {
    const TimestampNs t_true = grid.imu_ns[static_cast<std::size_t>(k)];
    grid.camera_imu_index.push_back(static_cast<std::size_t>(k));
    grid.camera_true_ns.push_back(t_true);
    grid.camera_stamp_ns.push_back(t_true - options.camera_time_offset_ns);
  }
  return grid;
}

}  // namespace mrvs::sim
