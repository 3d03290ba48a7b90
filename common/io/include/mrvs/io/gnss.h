#pragma once
// GNSS position fixes in a EuRoC ASL folder: mav0/gnss0/, an extension of the EuRoC layout
// written by the project's simulator for its outdoor profile (real EuRoC sequences have none;
// the dataset reader then reports an empty stream).
//
// mav0/gnss0/data.csv, one fix per row, strictly increasing in time (ReadPolicy applies):
//   #timestamp [ns],p_x [m],p_y [m],p_z [m],sigma_horizontal [m],sigma_vertical [m]
//   - timestamp: int64 ns on the IMU clock;
//   - p_x, p_y, p_z: the position of the ANTENNA (not of the IMU) in the map frame, the frame
//     of the prior map mav0/pointcloud0/data.ply (x, y horizontal, z up);
//   - sigma_horizontal: the receiver's standard deviation of EACH horizontal axis (x and y),
//     sigma_vertical: that of z; both > 0. The covariance of a fix is
//     diag(sigma_h^2, sigma_h^2, sigma_v^2). Fixes may be outliers the sigmas do not cover.
//
// mav0/gnss0/sensor.yaml (EuRoC style):
//   sensor_type: gnss                 # optional; when given it must be 'gnss'
//   comment: ...                      # optional
//   T_BS:                             # required: T_b_antenna, the antenna in the IMU body frame
//     cols: 4                         # (its translation is the lever arm; the rotation of a
//     rows: 4                         # point antenna is unused)
//     data: [16 numbers, row-major]
//   rate_hz: 1.0                      # required, > 0: the nominal fix rate
//   sigma_horizontal_m: 1.5           # optional, > 0: nominal values (each row has its own)
//   sigma_vertical_m: 3.0             # optional, > 0
//   correlation_time_s: 30.0          # optional, >= 0: time constant of the error (0 = white)
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/io/types.h"

namespace mrvs::io {

/// The header of mav0/gnss0/data.csv.
inline constexpr const char* kGnssCsvHeader =
    "#timestamp [ns],p_x [m],p_y [m],p_z [m],sigma_horizontal [m],sigma_vertical [m]";

/// What mav0/gnss0/sensor.yaml says.
struct GnssSensor {
  std::string comment;
  SE3d T_b_antenna;                 ///< antenna -> IMU body (T_BS); the lever arm is its translation
  double rate_hz = 0.0;             ///< nominal fix rate, Hz
  double sigma_horizontal_m = 0.0;  ///< nominal sd of each horizontal axis, m; 0 when the file does not say
  double sigma_vertical_m = 0.0;    ///< nominal sd of z, m; 0 when the file does not say
  double correlation_time_s = 0.0;  ///< Gauss-Markov time constant of the error, s; 0 when not given
};

/// Reads mav0/gnss0/data.csv (6 comma-separated fields per row, see above). Errors name the
/// file, the line and the field; rows are ordered per `policy`, findings go to `warnings`.
StatusOr<std::vector<GnssFix>> read_euroc_gnss_csv(const std::filesystem::path& csv,
                                                   const ReadPolicy& policy = {},
                                                   Warnings* warnings = nullptr);

/// Writes mav0/gnss0/data.csv with kGnssCsvHeader; values in the shortest text that reads
/// back to the same double. Times must strictly increase, positions be finite and sigmas
/// finite and > 0. Written to a temporary name and renamed into place.
Status write_euroc_gnss_csv(const std::filesystem::path& csv, const std::vector<GnssFix>& fixes);

/// Reads mav0/gnss0/sensor.yaml (with or without the OpenCV `%YAML:1.0` line). Every error
/// names the file, line and key; all are reported at once.
StatusOr<GnssSensor> read_gnss_sensor_yaml(const std::filesystem::path& path);

}  // namespace mrvs::io
