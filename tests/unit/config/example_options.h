#pragma once
// Options structs used by the config tests: every supported field type, an enum, a
// nested section, and a root struct that lists module sections.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "mrvs/config/options.h"

namespace mrvs::config::test_options {

enum class UpdateMode { kKnownLandmark, kMsckfNullspace };

struct ImuNoiseOptions : OptionsEquality<ImuNoiseOptions> {
  double gyroscope_noise_density = 1.6968e-4;  ///< rad / s / sqrt(Hz)
  double rate_hz = 200.0;                      ///< Hz

  template <class V>
  void visit(V& v) {
    v("gyroscope_noise_density", gyroscope_noise_density, greater_than(0.0), "rad/s/sqrt(Hz)");
    v("rate_hz", rate_hz, in_range(1.0, 10000.0), "Hz");
  }
};

struct ExampleOptions : OptionsEquality<ExampleOptions> {
  int max_features = 200;                                ///< features per frame
  std::int64_t window_ns = 5'000'000'000;                ///< ns
  double min_px_dist = 10.0;                             ///< px
  float quality = 0.01f;                                 ///< relative corner quality
  bool use_fej = true;                                   ///< first-estimate Jacobians
  std::string mode = "known_landmark";                   ///< stage-1 update
  UpdateMode update = UpdateMode::kKnownLandmark;        ///< same, as an enum
  std::vector<double> resolutions = {0.01, 0.02, 0.03};  ///< m
  std::vector<int> levels = {0, 1, 2};                   ///< pyramid levels
  std::vector<std::string> cameras = {"cam0", "cam1"};   ///< camera names
  Eigen::Vector3d gravity{0.0, 0.0, -9.81};              ///< m/s^2
  std::filesystem::path calibration;                     ///< camchain file
  ImuNoiseOptions imu;                                   ///< nested section

  template <class V>
  void visit(V& v) {
    v("max_features", max_features, in_range(1, 5000), "features per frame");
    v("window_ns", window_ns, at_least(std::int64_t{0}), "ns");
    v("min_px_dist", min_px_dist, in_range(0.0, 100.0), "px between features");
    v("quality", quality, in_range(0.0, 1.0), "relative corner quality");
    v("use_fej", use_fej, any(), "first-estimate Jacobians");
    v("mode", mode, one_of({"known_landmark", "msckf_nullspace"}), "stage-1 update");
    v("update", update,
      enum_names<UpdateMode>(
          {{"known_landmark", UpdateMode::kKnownLandmark}, {"msckf_nullspace", UpdateMode::kMsckfNullspace}}),
      "stage-1 update (enum)");
    v("resolutions", resolutions, each_in_range(0.001, 10.0).size(1, 16), "voxel sizes, m");
    v("levels", levels, list_size(0, 8), "pyramid levels");
    v("cameras", cameras, any(), "camera names");
    v("gravity", gravity, any(), "m/s^2");
    v("calibration", calibration, any(), "camchain, relative to this file");
    v.section("imu", imu, "IMU noise");
  }
};

/// A whole tuning file: one section per module.
struct RootOptions : OptionsEquality<RootOptions> {
  ExampleOptions tracker;
  ImuNoiseOptions imu;

  template <class V>
  void visit(V& v) {
    v.section("tracker", tracker);
    v.section("imu", imu);
  }
};

}  // namespace mrvs::config::test_options
