#pragma once
// Plain sensor and trajectory records read from datasets. Units in the names:
// t_ns is int64 nanoseconds, angular rate rad/s, acceleration m/s^2, positions metres.
#include <filesystem>
#include <vector>

#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"

namespace mrvs::io {

/// One IMU reading (EuRoC imu0/data.csv).
struct ImuSample {
  TimestampNs t_ns = 0;
  Vec3d gyro_radps = Vec3d::Zero();
  Vec3d accel_mps2 = Vec3d::Zero();
};

/// One image of one camera (EuRoC camN/data.csv row): the file is read on demand.
struct ImageRecord {
  TimestampNs t_ns = 0;
  std::filesystem::path path;  ///< absolute or relative to the working directory
};

/// A pose in a world frame: T_w_b maps body points into the world frame.
struct StampedPose {
  TimestampNs t_ns = 0;
  SE3d T_w_b;
};
using Trajectory = std::vector<StampedPose>;

/// Full ground-truth state (EuRoC state_groundtruth_estimate0/data.csv).
struct GroundTruthState {
  TimestampNs t_ns = 0;
  SE3d T_w_b;
  Vec3d v_w_b = Vec3d::Zero();       ///< velocity of the body in the world frame, m/s
  Vec3d bias_gyro = Vec3d::Zero();   ///< rad/s
  Vec3d bias_accel = Vec3d::Zero();  ///< m/s^2
};

/// One GNSS position fix (mav0/gnss0/data.csv row; format in mrvs/io/gnss.h).
struct GnssFix {
  TimestampNs t_ns = 0;             ///< IMU clock
  Vec3d p_map = Vec3d::Zero();      ///< position of the ANTENNA in the map frame, m
  double sigma_horizontal_m = 0.0;  ///< standard deviation of each horizontal axis (x, y), m
  double sigma_vertical_m = 0.0;    ///< standard deviation of z, m
};

}  // namespace mrvs::io
