#pragma once
// Sensor time grid (simulator.md sections 1.2, 2.5, 2.6), pure integer arithmetic:
// IMU stamps t_k = t0_ns + k * period_ns; camera frames on every N-th IMU stamp; a
// camera-IMU time offset t_d with t_imu = t_cam + t_d: images are rendered at the true
// (IMU clock) time t and stamped t - t_d.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"

namespace mrvs::sim {

/// Rates and offsets of the grid. Defaults: EuRoC (IMU 200 Hz, cameras 20 Hz).
struct TimeGridOptions : config::OptionsEquality<TimeGridOptions> {
  int imu_rate_hz = 200;                   ///< Hz; 1e9 must be divisible by it (integer ns period)
  int camera_rate_hz = 20;                 ///< Hz; must divide imu_rate_hz
  std::int64_t camera_time_offset_ns = 0;  ///< t_d, ns: t_imu = t_cam + t_d
  int first_camera_imu_index = 1;          ///< IMU index of the first frame (>= 1: an IMU row precedes it)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("imu_rate_hz", imu_rate_hz, in_range(1, 100000), "Hz");
    v("camera_rate_hz", camera_rate_hz, in_range(1, 100000), "Hz, divides imu_rate_hz");
    v("camera_time_offset_ns", camera_time_offset_ns,
      in_range(std::int64_t{-1'000'000'000}, std::int64_t{1'000'000'000}), "t_d, ns: t_imu = t_cam + t_d");
    v("first_camera_imu_index", first_camera_imu_index, in_range(0, 1000000), "IMU index of the first frame");
  }
};

/// EuRoC: IMU 200 Hz, cameras 20 Hz (every 10th IMU stamp).
TimeGridOptions euroc_time_grid();
/// KAIST-like: IMU 100 Hz, cameras 10 Hz (every 10th IMU stamp).
TimeGridOptions kaist_time_grid();

/// The stamps of one sequence.
struct TimeGrid {
  DurationNs imu_period_ns = 0;
  int imu_per_camera = 0;                     ///< N: a frame on every N-th IMU stamp
  std::vector<TimestampNs> imu_ns;            ///< t0 + k * period, all <= t_end
  std::vector<std::size_t> camera_imu_index;  ///< per frame: index into imu_ns of its true time
  std::vector<TimestampNs> camera_true_ns;    ///< per frame: render time (IMU clock)
  std::vector<TimestampNs> camera_stamp_ns;   ///< per frame: written stamp = true - t_d
};

/// Grid over [t0_ns, t_end_ns]. Errors: t_end < t0, a rate that gives no integer ns
/// period, a camera rate that does not divide the IMU rate.
StatusOr<TimeGrid> make_time_grid(TimestampNs t0_ns, TimestampNs t_end_ns, const TimeGridOptions& options);

}  // namespace mrvs::sim
