#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "mrvs/config/calibration.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/rig.h"
#include "mrvs/test/euroc_sensor_yaml.h"
#include "mrvs/test/numeric_jacobian.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

std::string without_first_line(const std::string& text) { return text.substr(text.find('\n') + 1); }

// Same keys, same scalars, same numbers (bit for bit) in two YAML texts.
void expect_same_yaml(const YAML::Node& a, const YAML::Node& b, const std::string& where) {
  ASSERT_EQ(a.Type(), b.Type()) << where;
  if (a.IsMap()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (const auto& kv : a) {
      const std::string key = kv.first.as<std::string>();
      ASSERT_TRUE(b[key]) << where << "." << key << " missing";
      expect_same_yaml(kv.second, b[key], where + "." + key);
    }
  } else if (a.IsSequence()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (std::size_t i = 0; i < a.size(); ++i)
      expect_same_yaml(a[i], b[i], where + "[" + std::to_string(i) + "]");
  } else {
    double x = 0, y = 0;
    if (YAML::convert<double>::decode(a, x) && YAML::convert<double>::decode(b, y)) {
      EXPECT_EQ(x, y) << where;
    } else {
      EXPECT_EQ(a.as<std::string>(), b.as<std::string>()) << where;
    }
  }
}

TEST(Rig, EurocSensorYamlHasExactlyTheRealFilesKeysAndValues) {
  const Rig rig = euroc_rig();
  for (int cam = 0; cam < 2; ++cam) {
    // The fixture holds the dataset's own text, with the OpenCV "%YAML:1.0" first line.
    expect_same_yaml(YAML::Load(camera_sensor_yaml(rig.cameras[cam])),
                     YAML::Load(without_first_line(test::euroc_camera_sensor_yaml(cam))),
                     "cam" + std::to_string(cam));
  }
  expect_same_yaml(YAML::Load(imu_sensor_yaml(rig.imu)), YAML::Load(test::euroc_imu_sensor_yaml()), "imu0");
}

TEST(Rig, WrittenFilesLoadBackExactlyWithTheProjectReader) {
  const test::TempDir dir;
  for (const Rig& rig : {euroc_rig(), kaist_like_rig()}) {
    for (int cam = 0; cam < 2; ++cam) {
      const RigCamera& c = rig.cameras[cam];
      auto loaded =
          config::load_euroc_camera_yaml(dir.write(rig.name + c.name + ".yaml", camera_sensor_yaml(c)));
      ASSERT_TRUE(loaded.ok()) << loaded.status();
      EXPECT_EQ(loaded->model->width(), c.width);
      EXPECT_EQ(loaded->model->height(), c.height);
      EXPECT_MATRIX_NEAR(loaded->model->params(), c.params, 0.0);
      EXPECT_MATRIX_NEAR(loaded->T_b_c.matrix(), c.T_BS, 1e-12);
      EXPECT_EQ(loaded->rate_hz, c.rate_hz);
    }
    auto imu = config::load_euroc_imu_yaml(dir.write(rig.name + "imu.yaml", imu_sensor_yaml(rig.imu)));
    ASSERT_TRUE(imu.ok()) << imu.status();
    EXPECT_DOUBLE_EQ(imu->gyroscope_noise_density, rig.imu.gyroscope_noise_density);
    EXPECT_DOUBLE_EQ(imu->accelerometer_random_walk, rig.imu.accelerometer_random_walk);
    EXPECT_EQ(imu->rate_hz, rig.imu.rate_hz);
  }
}

TEST(Rig, BaselinesAndRatesMatchTheRealRigs) {
  auto euroc = euroc_rig().calibration();
  ASSERT_TRUE(euroc.ok()) << euroc.status();
  EXPECT_NEAR(euroc->T_c0_c1().translation().norm(), 0.11008, 5e-5);
  EXPECT_EQ(euroc_rig().imu_samples_per_frame(), 10);
  auto kaist = kaist_like_rig().calibration();
  ASSERT_TRUE(kaist.ok()) << kaist.status();
  EXPECT_NEAR(kaist->T_c0_c1().translation().norm(), 0.47515, 5e-5);
  EXPECT_EQ(kaist_like_rig().imu_samples_per_frame(), 10);
}

TEST(Rig, KaistRotationsAreReorthonormalised) {
  for (const RigCamera& c : kaist_like_rig().cameras) {
    const Mat3d R = c.T_BS.topLeftCorner<3, 3>();
    EXPECT_MATRIX_NEAR(R.transpose() * R, Mat3d::Identity(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    // The camera looks forward: its z axis is about the IMU x axis (x forward, z up).
    EXPECT_GT(R.col(2).x(), 0.99);
  }
}

TEST(Rig, OrthonormalizedFindsTheNearestRotation) {
  const Mat3d R = so3::exp<double>(Vec3d(0.3, -0.2, 1.1));
  Mat4d T = Mat4d::Identity();
  T.topLeftCorner<3, 3>() = R + 1e-4 * Mat3d::Ones();
  T.topRightCorner<3, 1>() = Vec3d(1, 2, 3);
  const Mat4d fixed = orthonormalized(T);
  EXPECT_TRUE(so3::is_rotation_matrix<double>(Mat3d(fixed.topLeftCorner<3, 3>()), 1e-12));
  EXPECT_MATRIX_NEAR((fixed.topLeftCorner<3, 3>()), R, 3e-4);
  EXPECT_MATRIX_NEAR((fixed.topRightCorner<3, 1>()), Vec3d(1, 2, 3), 0.0);
}

}  // namespace
}  // namespace mrvs::sim
