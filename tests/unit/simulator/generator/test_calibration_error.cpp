// Calibration error (calib_error): the draws around the written rig have the stated sigmas,
// the stereo pair moves as one block under the camera-IMU error, and nothing changes when
// it is off.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/geometry/so3.h"
#include "mrvs/sim/calibration_error.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// Sample standard deviation of each column.
std::vector<double> column_sigmas(const std::vector<std::vector<double>>& rows) {
  std::vector<double> sum(rows.front().size(), 0.0), sum_sq(sum.size(), 0.0);
  for (const auto& r : rows) {
    for (std::size_t i = 0; i < r.size(); ++i) sum[i] += r[i], sum_sq[i] += r[i] * r[i];
  }
  std::vector<double> sigma;
  const double n = static_cast<double>(rows.size());
  for (std::size_t i = 0; i < sum.size(); ++i)
    sigma.push_back(std::sqrt(sum_sq[i] / n - sum[i] * sum[i] / n / n));
  return sigma;
}

Vec3d rotation_error(const Mat4d& truth, const Mat4d& written) {
  return so3::log(Mat3d(truth.topLeftCorner<3, 3>() * written.topLeftCorner<3, 3>().transpose()));
}

TEST(CalibrationError, TheDrawsHaveTheStatedSigmas) {
  const Rig written = euroc_rig();
  CalibrationErrorOptions o;
  o.enabled = true;
  std::vector<std::vector<double>> rows;
  for (std::uint64_t seed = 0; seed < 4000; ++seed) {
    const TrueCalibration t = draw_true_calibration(written, 1.5, o, seed);
    std::vector<double> row;
    // The drawn poses: the true ones without the rotations that hide the intrinsic error.
    auto drawn = [&](int c) {
      Mat4d T = t.rig.cameras[static_cast<std::size_t>(c)].T_BS;
      T.topLeftCorner<3, 3>() *= t.R_compensation[static_cast<std::size_t>(c)].transpose();
      return T;
    };
    const Mat4d T0 = drawn(0);
    const Mat4d& W0 = written.cameras[0].T_BS;
    for (double x : rotation_error(T0, W0)) row.push_back(x / kDeg / o.rotation_deg);
    const Vec3d dp = (T0 - W0).topRightCorner<3, 1>();
    for (double x : dp) row.push_back(x * 1e3 / o.translation_mm);
    // cam1 relative to cam0: the stereo draw alone.
    const Mat4d S = T0.inverse() * drawn(1);
    const Mat4d SW = W0.inverse() * written.cameras[1].T_BS;
    for (double x : rotation_error(S, SW)) row.push_back(x / kDeg / o.stereo_rotation_deg);
    for (double x : Vec3d((S - SW).topRightCorner<3, 1>())) row.push_back(x * 1e3 / o.stereo_translation_mm);
    const double sigma[8] = {o.focal_px,  o.focal_px,  o.principal_point_px, o.principal_point_px,
                             o.radial_k1, o.radial_k2, o.tangential,         o.tangential};
    for (int c = 0; c < 2; ++c) {
      for (int i = 0; i < 8; ++i)
        row.push_back((t.rig.cameras[c].params[i] - written.cameras[c].params[i]) / sigma[i]);
    }
    row.push_back((t.time_offset_ms - 1.5) / o.time_offset_ms);
    rows.push_back(row);
  }
  const std::vector<double> s = column_sigmas(rows);
  ASSERT_EQ(s.size(), 3u * 4u + 16u + 1u);
  // 4000 draws: the sample sigma of a unit normal is within 1 +- 0.05 (4.5 standard errors).
  for (std::size_t i = 0; i < s.size(); ++i) EXPECT_NEAR(s[i], 1.0, 0.05) << "component " << i;
}

/// RMS angle (rad) between the rays of the same pixel, seen from the body, of a true camera
/// and its written one, over a grid of pixels.
double rms_ray_angle(const RigCamera& truth, const RigCamera& written) {
  auto t = camera::make_camera(truth.model, truth.width, truth.height, truth.params);
  auto w = camera::make_camera(written.model, written.width, written.height, written.params);
  EXPECT_TRUE(t.ok() && w.ok());
  double sum_sq = 0.0;
  for (int j = 0; j < 12; ++j) {
    for (int i = 0; i < 20; ++i) {
      const Vec2d uv((i + 0.5) * truth.width / 20, (j + 0.5) * truth.height / 12);
      const Vec3d a = truth.T_BS.topLeftCorner<3, 3>() * *(*t)->unproject(uv);
      const Vec3d b = written.T_BS.topLeftCorner<3, 3>() * *(*w)->unproject(uv);
      const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
      sum_sq += angle * angle;
    }
  }
  return std::sqrt(sum_sq / (12 * 20));
}

TEST(CalibrationError, APrincipalPointErrorIsHiddenInTheCamerasOrientation) {
  const Rig written = euroc_rig();
  CalibrationErrorOptions o;
  o.enabled = true;
  o.rotation_deg = o.translation_mm = o.focal_px = o.radial_k1 = o.radial_k2 = o.tangential = 0.0;
  o.stereo_rotation_deg = o.stereo_translation_mm = o.time_offset_ms = 0.0;
  o.principal_point_px = 2.0;
  for (std::uint64_t seed = 0; seed < 20; ++seed) {
    const TrueCalibration hidden = draw_true_calibration(written, 0.0, o, seed);
    o.compensate_intrinsics = false;
    const TrueCalibration raw = draw_true_calibration(written, 0.0, o, seed);
    o.compensate_intrinsics = true;
    for (std::size_t c = 0; c < 2; ++c) {
      const RigCamera& w = written.cameras[c];
      ASSERT_EQ(hidden.rig.cameras[c].params, raw.rig.cameras[c].params);
      const double shift_px = (raw.rig.cameras[c].params - w.params).head<4>().norm();
      // Uncompensated: the rays are off by about the shift over the focal length.
      const double raw_px = rms_ray_angle(raw.rig.cameras[c], w) * w.params[0];
      const double hidden_px = rms_ray_angle(hidden.rig.cameras[c], w) * w.params[0];
      EXPECT_GT(raw_px, 0.7 * shift_px);
      // Compensated: the rotation takes up most of it; the rest is the distortion centre's move.
      EXPECT_LT(hidden_px, 0.25 * raw_px) << "seed " << seed << " cam " << c << " raw " << raw_px;
    }
  }
}

TEST(CalibrationError, OffChangesNothingAndASeedGivesOneDraw) {
  const Rig written = euroc_rig();
  CalibrationErrorOptions o;
  const TrueCalibration off = draw_true_calibration(written, 2.0, o, 3);
  EXPECT_EQ(off.time_offset_ms, 2.0);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(off.rig.cameras[c].T_BS, written.cameras[c].T_BS);
    EXPECT_EQ(off.rig.cameras[c].params, written.cameras[c].params);
  }
  o.enabled = true;
  const TrueCalibration a = draw_true_calibration(written, 2.0, o, 3);
  const TrueCalibration b = draw_true_calibration(written, 2.0, o, 3);
  const TrueCalibration c = draw_true_calibration(written, 2.0, o, 4);
  EXPECT_EQ(a.rig.cameras[1].T_BS, b.rig.cameras[1].T_BS);
  EXPECT_EQ(a.time_offset_ms, b.time_offset_ms);
  EXPECT_NE(a.rig.cameras[1].T_BS, c.rig.cameras[1].T_BS);
  // Rotations stay rotations.
  const Mat3d R = a.rig.cameras[1].T_BS.topLeftCorner<3, 3>();
  EXPECT_LT((R * R.transpose() - Mat3d::Identity()).norm(), 1e-12);
}

TEST(CalibrationError, TheTruthFilesReadBackAsDrawn) {
  mrvs::test::TempDir dir;
  CalibrationErrorOptions o;
  o.enabled = true;
  const TrueCalibration t = draw_true_calibration(euroc_rig(), -0.5, o, 9);
  std::filesystem::create_directories(dir / "cam0");
  std::filesystem::create_directories(dir / "cam1");
  ASSERT_TRUE(write_true_calibration(dir.path(), t).ok());
  const StatusOr<double> td = read_true_time_offset_ms(dir.path());
  ASSERT_TRUE(td.ok()) << td.status();
  EXPECT_EQ(*td, t.time_offset_ms);
  const StatusOr<config::CameraCalibration> cam1 = config::load_euroc_camera_yaml(dir / "cam1/sensor.yaml");
  ASSERT_TRUE(cam1.ok()) << cam1.status();
  EXPECT_LT((cam1->T_b_c.matrix() - t.rig.cameras[1].T_BS).norm(), 1e-12);
  EXPECT_FALSE(read_true_time_offset_ms(dir / "cam0").ok());
}

}  // namespace
}  // namespace mrvs::sim
