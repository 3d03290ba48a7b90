#pragma once
// Calibration error (issue 31): the rig that renders the images is not the one written in
// mav0/camN/sensor.yaml, as a real rig's Kalibr calibration is off. Each error is a
// zero-mean Gaussian draw (CounterRng(seed, Stream::kCalibration)), sigma per component:
//   camera-IMU:  R_b_c0 <- exp(dtheta) R_b_c0, p_b_c0 <- p_b_c0 + dp (body frame, both
//                cameras move with cam0: the stereo pair is one rigid block),
//   stereo:      T_c0_c1 <- (exp(dtheta_s), dp_s) * T_c0_c1 (cam0 frame),
//   intrinsics:  fx, fy, cx, cy, k1, k2, p1, p2 of each camera,
//   time offset: t_d <- t_d + dt (t_imu = t_cam + t_d).
// A calibration pins the rays a camera sees on its targets, not each parameter on its own,
// so with compensate_intrinsics (default) each camera also turns by the rotation that best
// maps its true pixel rays onto the written ones (Kabsch over a pixel grid): a principal
// point error becomes an orientation the rays agree with, and what stays is what no rotation
// hides (focal length, distortion) plus the drawn rotation errors. Without it, 1 px
// principal-point draws in each camera make a 1.4 px sigma stereo disparity bias (8 % of the
// depth at 3 m), which a calibration with sub-pixel target residuals does not leave.
// The true values are written to sim0/true_calibration/ for evaluation.
#include <array>
#include <cstdint>
#include <filesystem>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/sim/rig.h"

namespace mrvs::sim {

struct CalibrationErrorOptions : config::OptionsEquality<CalibrationErrorOptions> {
  bool enabled = false;                ///< render with a rig drawn around the written one
  double rotation_deg = 0.1;           ///< camera-IMU rotation, sigma per axis, deg
  double translation_mm = 2.0;         ///< camera-IMU translation, sigma per axis, mm
  double focal_px = 1.0;               ///< fx and fy, sigma, px
  double principal_point_px = 1.0;     ///< cx and cy, sigma, px
  double radial_k1 = 0.0012;           ///< k1, sigma (Kalibr's reported sigma, radtan, ethz-asl/kalibr#502)
  double radial_k2 = 0.0017;           ///< k2, sigma (idem)
  double tangential = 1e-4;            ///< p1 and p2, sigma (idem: 1.5e-4 and 0.8e-4)
  double stereo_rotation_deg = 0.02;   ///< cam1 relative to cam0, sigma per axis, deg
  double stereo_translation_mm = 0.2;  ///< cam1 relative to cam0, sigma per axis, mm
  double time_offset_ms = 2.0;         ///< camera-IMU time offset, sigma, ms
  bool compensate_intrinsics = true;   ///< each camera turns to keep its rays (see above)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("enabled", enabled, any(), "render with a rig drawn around the one written in sensor.yaml");
    v("rotation_deg", rotation_deg, in_range(0.0, 10.0), "camera-IMU rotation error, sigma per axis, deg");
    v("translation_mm", translation_mm, in_range(0.0, 100.0),
      "camera-IMU translation error, sigma per axis, mm");
    v("focal_px", focal_px, in_range(0.0, 50.0), "focal length error, sigma, px");
    v("principal_point_px", principal_point_px, in_range(0.0, 50.0), "principal point error, sigma, px");
    v("radial_k1", radial_k1, in_range(0.0, 0.5), "k1 error, sigma");
    v("radial_k2", radial_k2, in_range(0.0, 0.5), "k2 error, sigma");
    v("tangential", tangential, in_range(0.0, 0.01), "p1 and p2 error, sigma");
    v("stereo_rotation_deg", stereo_rotation_deg, in_range(0.0, 10.0),
      "cam1-cam0 rotation error, sigma, deg");
    v("stereo_translation_mm", stereo_translation_mm, in_range(0.0, 100.0),
      "cam1-cam0 translation error, sigma, mm");
    v("time_offset_ms", time_offset_ms, in_range(0.0, 100.0), "camera-IMU time offset error, sigma, ms");
    v("compensate_intrinsics", compensate_intrinsics, any(),
      "each camera turns by the rotation that best keeps its pixel rays (as a calibration does)");
  }
};

/// The true rig and camera-IMU time offset behind a written calibration.
struct TrueCalibration {
  Rig rig;                      ///< what renders the images
  double time_offset_ms = 0.0;  ///< true t_d, ms
  /// Per camera, R_w_t: the rotation (true camera -> written camera axes) that hides the
  /// intrinsic error; each true T_BS is the drawn pose times it. Identity when off.
  std::array<Mat3d, 2> R_compensation{Mat3d::Identity(), Mat3d::Identity()};
};

/// `written` and `time_offset_ms` unchanged when !options.enabled; otherwise the drawn
/// true calibration (the same for the same seed).
TrueCalibration draw_true_calibration(const Rig& written, double time_offset_ms,
                                      const CalibrationErrorOptions& options, std::uint64_t seed);

/// sim0/true_calibration/: cam0/sensor.yaml and cam1/sensor.yaml (EuRoC format, as
/// mav0/camN/sensor.yaml) and time_offset.yaml ("time_offset_ms: t_d").
Status write_true_calibration(const std::filesystem::path& dir, const TrueCalibration& truth);
/// time_offset.yaml read back.
StatusOr<double> read_true_time_offset_ms(const std::filesystem::path& dir);

}  // namespace mrvs::sim
