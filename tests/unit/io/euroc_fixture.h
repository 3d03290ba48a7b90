#pragma once
// Writes a tiny EuRoC ASL sequence into a temporary folder for the io tests: real-EuRoC
// style sensor.yaml files (with "%YAML:1.0"), CSV files with CRLF line ends and blanks
// after the commas, and small PNG images whose pixels encode the frame index.
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/time.h"
#include "mrvs/geometry/types.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io::test_fixture {

struct EurocSpec {
  int width = 16;
  int height = 12;
  int frames = 10;
  DurationNs frame_period_ns = 50'000'000;  // 20 Hz
  int imu_per_frame = 10;                   // 200 Hz
  TimestampNs t0_ns = 1403636579763555584;  // first image of MH_01_easy
  bool groundtruth = true;
};

/// Stamps of image k and IMU sample k.
TimestampNs image_t_ns(const EurocSpec& spec, int k);
TimestampNs imu_t_ns(const EurocSpec& spec, int k);
/// Values written for IMU sample k (exactly representable after a text round trip).
Vec3d imu_gyro(int k);
Vec3d imu_accel(int k);
/// Grey value of every pixel of image k of camera cam.
int pixel_value(int cam, int k);

/// The CSV text of camN/data.csv (CRLF, blanks after commas).
std::string image_csv(const EurocSpec& spec);
/// The CSV text of imu0/data.csv.
std::string imu_csv(const EurocSpec& spec);

/// Writes <dir>/<name>/mav0/... and returns the sequence folder <dir>/<name>.
std::filesystem::path write_euroc_sequence(const test::TempDir& dir, const EurocSpec& spec,
                                           const std::string& name = "MH_test");

}  // namespace mrvs::io::test_fixture
