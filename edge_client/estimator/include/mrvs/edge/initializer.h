#pragma once
// Initialisation (algorithm.md 6.1; OpenVINS' InertialInitializer picks one of two):
// - static: the platform has been still for `static_window_s` (accelerometer spread and
//   image disparity small): gravity alignment from the mean specific force, the gyro bias
//   from the mean rate, zero velocity;
// - dynamic (dynamic_initializer.h): the platform moves with enough rotation.
// The Initializer buffers IMU samples and feature frames and says why it still waits.
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "mrvs/config/calibration.h"
#include "mrvs/config/options.h"
#include "mrvs/edge/dynamic_initializer.h"

namespace mrvs::edge {

struct InitializerOptions : config::OptionsEquality<InitializerOptions> {
  double window_s = 2.0;                   ///< frames and IMU kept for initialisation
  double static_window_s = 1.0;            ///< stillness needed for the static initialiser
  double max_accel_std = 0.15;             ///< m/s^2: stiller than this is still
  double max_static_disparity_px = 1.5;    ///< mean feature motion over the static window
  bool dynamic = true;                     ///< try the dynamic initialiser when moving
  double min_dynamic_disparity_px = 10.0;  ///< mean feature motion over the window to try it
  double sigma_orientation = 0.02;         ///< rad: prior of the static result (reference code)
  double sigma_position = 0.05;            ///< m
  double sigma_velocity = 0.01;            ///< m/s
  double sigma_gyro_bias = 0.02;           ///< rad/s
  double sigma_accel_bias = 0.02;          ///< m/s^2
  DynamicInitOptions dynamic_options;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("window_s", window_s, in_range(0.2, 60.0), "data kept for initialisation, s");
    v("static_window_s", static_window_s, in_range(0.1, 60.0), "stillness needed, s");
    v("max_accel_std", max_accel_std, in_range(0.0, 100.0), "still: accelerometer spread below, m/s^2");
    v("max_static_disparity_px", max_static_disparity_px, in_range(0.0, 1000.0),
      "still: mean feature motion below, px");
    v("dynamic", dynamic, any(), "try the dynamic initialiser when moving");
    v("min_dynamic_disparity_px", min_dynamic_disparity_px, in_range(0.0, 1000.0),
      "moving: mean feature motion over the window above, px");
    v("sigma_orientation", sigma_orientation, in_range(1e-6, 10.0), "static prior sd, rad");
    v("sigma_position", sigma_position, in_range(1e-6, 100.0), "static prior sd, m");
    v("sigma_velocity", sigma_velocity, in_range(1e-6, 100.0), "static prior sd, m/s");
    v("sigma_gyro_bias", sigma_gyro_bias, in_range(1e-9, 10.0), "static prior sd, rad/s");
    v("sigma_accel_bias", sigma_accel_bias, in_range(1e-9, 10.0), "static prior sd, m/s^2");
    v.section("dynamic_options", dynamic_options, "dynamic initialiser");
  }
};

/// Static initialisation from still IMU data (the samples over the still window): the
/// state at `t_ns` (IMU clock). InvalidArgument when there are fewer than 10 samples.
StatusOr<InitializationResult> static_initialize(const std::vector<io::ImuSample>& samples, TimestampNs t_ns,
                                                 double g, const InitializerOptions& options);

class Initializer {
 public:
  Initializer(const InitializerOptions& options, const config::StereoRigCalibration& rig,
              const ImuNoise& noise, double g, const TriangulationOptions& triangulation);

  void feed_imu(const io::ImuSample& s);
  void feed_frame(const FeatureFrame& frame);

  /// A result at the newest frame (IMU clock), or nullopt with `why` saying what is
  /// missing ("waiting: 0.4 s of IMU, need 1.0", "moving but 3.2 deg of rotation, ...").
  std::optional<InitializationResult> try_initialize(std::string* why);

  const std::deque<FeatureFrame>& frames() const { return frames_; }

 private:
  double mean_disparity(double since_s) const;
  std::vector<io::ImuSample> imu_between(TimestampNs from_ns, TimestampNs to_ns) const;

  InitializerOptions options_;
  config::StereoRigCalibration rig_;
  ImuNoise noise_;
  double g_;
  TriangulationOptions triangulation_;  ///< the estimator's (the dynamic initialiser's points)
  std::deque<io::ImuSample> imu_;
  std::deque<FeatureFrame> frames_;
};

}  // namespace mrvs::edge
