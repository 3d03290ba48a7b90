// Calibration loaders (EuRoC sensor.yaml, Kalibr camchain / imu) and the shipped
// config/euroc files.
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/config/calibration.h"
#include "mrvs/test/euroc_sensor_yaml.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::config {
namespace {

using ::testing::HasSubstr;

const std::filesystem::path kConfigDir = MRVS_CONFIG_DIR;

// The dataset's own files (mav0/cam0/sensor.yaml etc.), verbatim layout.
const std::string kEurocCam0 = test::euroc_camera_sensor_yaml(0);
const std::string kEurocCam1 = test::euroc_camera_sensor_yaml(1);
const std::string kEurocImu = test::euroc_imu_sensor_yaml();

/// A valid Kalibr camchain whose cam0 block can be replaced.
std::string camchain(const std::string& cam0_body) {
  return "cam0:\n" + cam0_body +
         "cam1:\n"
         "  T_cam_imu:\n"
         "  - [1.0, 0.0, 0.0, -0.1]\n"
         "  - [0.0, 1.0, 0.0, 0.0]\n"
         "  - [0.0, 0.0, 1.0, 0.0]\n"
         "  - [0.0, 0.0, 0.0, 1.0]\n"
         "  camera_model: pinhole\n"
         "  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n"
         "  distortion_model: radtan\n"
         "  intrinsics: [400.0, 400.0, 376.0, 240.0]\n"
         "  resolution: [752, 480]\n";
}

constexpr const char* kIdentityCam0 =
    "  T_cam_imu:\n"
    "  - [1.0, 0.0, 0.0, 0.0]\n"
    "  - [0.0, 1.0, 0.0, 0.0]\n"
    "  - [0.0, 0.0, 1.0, 0.0]\n"
    "  - [0.0, 0.0, 0.0, 1.0]\n"
    "  camera_model: pinhole\n"
    "  distortion_coeffs: [0.0, 0.0, 0.0, 0.0]\n"
    "  distortion_model: radtan\n"
    "  intrinsics: [400.0, 400.0, 376.0, 240.0]\n"
    "  resolution: [752, 480]\n";

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

double max_abs_diff(const SE3d& a, const SE3d& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

TEST(Calibration, EurocCameraSensorYaml) {
  test::TempDir dir;
  auto cam = load_euroc_camera_yaml(dir.write("mav0/cam0/sensor.yaml", kEurocCam0));
  ASSERT_TRUE(cam.ok()) << cam.status();
  EXPECT_EQ(cam->name, "cam0");
  EXPECT_EQ(cam->rate_hz, 20.0);
  EXPECT_EQ(cam->time_offset_ns, 0);
  ASSERT_NE(cam->model, nullptr);
  EXPECT_EQ(cam->model->model(), camera::DistortionModel::kRadTan);
  EXPECT_EQ(cam->model->width(), 752);
  EXPECT_EQ(cam->model->height(), 480);
  camera::Params expected;
  expected << 458.654, 457.296, 367.215, 248.375, -0.28340811, 0.07395907, 0.00019359, 1.76187114e-05;
  EXPECT_EQ(cam->model->params(), expected);
  Mat4d T_BS;
  T_BS << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975, 0.999557249008,
      0.0149672133247, 0.025715529948, -0.064676986768, -0.0257744366974, 0.00375618835797, 0.999660727178,
      0.00981073058949, 0.0, 0.0, 0.0, 1.0;
  EXPECT_LT((cam->T_b_c.matrix() - T_BS).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Calibration, EurocImuSensorYaml) {
  test::TempDir dir;
  auto imu = load_euroc_imu_yaml(dir.write("mav0/imu0/sensor.yaml", kEurocImu));
  ASSERT_TRUE(imu.ok()) << imu.status();
  EXPECT_EQ(imu->gyroscope_noise_density, 1.6968e-04);
  EXPECT_EQ(imu->gyroscope_random_walk, 1.9393e-05);
  EXPECT_EQ(imu->accelerometer_noise_density, 2.0000e-3);
  EXPECT_EQ(imu->accelerometer_random_walk, 3.0000e-3);
  EXPECT_EQ(imu->rate_hz, 200.0);
}

TEST(Calibration, ShippedKalibrFilesAgreeWithEurocSensorYaml) {
  test::TempDir dir;
  auto cam0 = load_euroc_camera_yaml(dir.write("cam0/sensor.yaml", kEurocCam0));
  auto cam1 = load_euroc_camera_yaml(dir.write("cam1/sensor.yaml", kEurocCam1));
  auto imu = load_euroc_imu_yaml(dir.write("imu0/sensor.yaml", kEurocImu));
  ASSERT_TRUE(cam0.ok() && cam1.ok() && imu.ok()) << cam0.status() << cam1.status() << imu.status();

  auto chain = load_kalibr_camchain(kConfigDir / "euroc/camchain-imucam.yaml");
  ASSERT_TRUE(chain.ok()) << chain.status();
  const std::array<const CameraCalibration*, 2> euroc = {&*cam0, &*cam1};
  for (std::size_t i = 0; i < 2; ++i) {
    const CameraCalibration& k = (*chain)[i];
    SCOPED_TRACE(k.name);
    EXPECT_EQ(k.name, i == 0 ? "cam0" : "cam1");
    EXPECT_LT(max_abs_diff(k.T_b_c, euroc[i]->T_b_c), 1e-9);
    ASSERT_NE(k.model, nullptr);
    EXPECT_EQ(k.model->model(), euroc[i]->model->model());
    EXPECT_EQ(k.model->params(), euroc[i]->model->params());
    EXPECT_EQ(k.model->width(), euroc[i]->model->width());
    EXPECT_EQ(k.model->height(), euroc[i]->model->height());
    EXPECT_EQ(k.time_offset_ns, 0);
  }

  auto kalibr_imu = load_kalibr_imu(kConfigDir / "euroc/imu.yaml");
  ASSERT_TRUE(kalibr_imu.ok()) << kalibr_imu.status();
  EXPECT_EQ(kalibr_imu->gyroscope_noise_density, imu->gyroscope_noise_density);
  EXPECT_EQ(kalibr_imu->gyroscope_random_walk, imu->gyroscope_random_walk);
  EXPECT_EQ(kalibr_imu->accelerometer_noise_density, imu->accelerometer_noise_density);
  EXPECT_EQ(kalibr_imu->accelerometer_random_walk, imu->accelerometer_random_walk);
  EXPECT_EQ(kalibr_imu->rate_hz, imu->rate_hz);
}

TEST(Calibration, StereoRigGeometryAndDescription) {
  auto chain = load_kalibr_camchain(kConfigDir / "euroc/camchain-imucam.yaml");
  auto imu = load_kalibr_imu(kConfigDir / "euroc/imu.yaml");
  ASSERT_TRUE(chain.ok() && imu.ok()) << chain.status() << imu.status();
  StereoRigCalibration rig{*chain, *imu};
  const SE3d T_c0_c1 = rig.T_c0_c1();
  // EuRoC's stereo baseline is 11.0 cm, mostly along the camera x axis (cam1 to the right).
  EXPECT_NEAR(T_c0_c1.translation().norm(), 0.110, 1e-3);
  EXPECT_GT(T_c0_c1.translation().x(), 0.109);
  EXPECT_LT(max_abs_diff(rig.cameras[0].T_b_c * T_c0_c1, rig.cameras[1].T_b_c), 1e-12);
  const std::string text = rig.describe();
  EXPECT_THAT(text, HasSubstr("cam0: "));
  EXPECT_THAT(text, HasSubstr("cam1: "));
  EXPECT_THAT(text, HasSubstr("752x480"));
  EXPECT_THAT(text, HasSubstr("baseline |p_c0_c1| = 0.110"));
  EXPECT_THAT(text, HasSubstr("rate 200 Hz"));
  EXPECT_THAT(text, HasSubstr("1.6968e-04"));
}

TEST(Calibration, KalibrTimeshiftBecomesNanoseconds) {
  test::TempDir dir;
  const auto path =
      dir.write("cc.yaml", camchain(std::string(kIdentityCam0) + "  timeshift_cam_imu: -0.0015\n"));
  auto chain = load_kalibr_camchain(path);
  ASSERT_TRUE(chain.ok()) << chain.status();
  EXPECT_EQ((*chain)[0].time_offset_ns, -1'500'000);
  EXPECT_EQ((*chain)[1].time_offset_ns, 0);
  EXPECT_EQ((*chain)[0].rate_hz, 0.0);
  // T_cam_imu of cam1 translates by -0.1 m in x: the camera sits at +0.1 m in the body frame.
  EXPECT_NEAR((*chain)[1].T_b_c.translation().x(), 0.1, 1e-15);
}

TEST(Calibration, EquidistantModelIsAccepted) {
  test::TempDir dir;
  const auto path = dir.write("cc.yaml", camchain(replace(kIdentityCam0, "radtan", "equidistant")));
  auto chain = load_kalibr_camchain(path);
  ASSERT_TRUE(chain.ok()) << chain.status();
  EXPECT_EQ((*chain)[0].model->model(), camera::DistortionModel::kEquidistant);
  EXPECT_EQ((*chain)[1].model->model(), camera::DistortionModel::kRadTan);
}

TEST(CalibrationErrors, NonOrthonormalRotation) {
  test::TempDir dir;
  const auto path =
      dir.write("cc.yaml", camchain(replace(kIdentityCam0, "[1.0, 0.0, 0.0, 0.0]", "[1.02, 0.0, 0.0, 0.0]")));
  auto chain = load_kalibr_camchain(path);
  ASSERT_FALSE(chain.ok());
  EXPECT_EQ(
      std::string(chain.status().message()),
      path.string() +
          ":3:3: key 'cam0.T_cam_imu': the rotation block is not a rotation matrix: max |R^T R - I| = 0.0404 "
          "(tolerance 1e-06), det(R) = 1.02");
}

TEST(CalibrationErrors, WrongMatrixShapes) {
  test::TempDir dir;
  {
    const auto path =
        dir.write("rows.yaml", camchain(replace(kIdentityCam0, "  - [0.0, 0.0, 0.0, 1.0]\n", "")));
    auto chain = load_kalibr_camchain(path);
    ASSERT_FALSE(chain.ok());
    EXPECT_EQ(std::string(chain.status().message()),
              path.string() +
                  ":3:3: key 'cam0.T_cam_imu': expected a 4x4 matrix (a list of 4 rows of 4 numbers), "
                  "got 3 rows");
  }
  {
    const auto path =
        dir.write("cols.yaml", camchain(replace(kIdentityCam0, "[0.0, 1.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]")));
    auto chain = load_kalibr_camchain(path);
    ASSERT_FALSE(chain.ok());
    EXPECT_EQ(
        std::string(chain.status().message()),
        path.string() + ":4:5: key 'cam0.T_cam_imu[1]': expected a row of 4 numbers, got '[0.0, 1.0, 0.0]'");
  }
  {
    const auto path = dir.write(
        "last.yaml", camchain(replace(kIdentityCam0, "[0.0, 0.0, 0.0, 1.0]", "[0.0, 0.0, 0.5, 1.0]")));
    auto chain = load_kalibr_camchain(path);
    ASSERT_FALSE(chain.ok());
    EXPECT_THAT(std::string(chain.status().message()),
                HasSubstr("key 'cam0.T_cam_imu': expected last row [0, 0, 0, 1], got [0, 0, 0.5, 1]"));
  }
  {
    const auto path =
        dir.write("cam0/sensor.yaml", replace(kEurocCam0, "0.0, 0.0, 0.0, 1.0]", "0.0, 0.0, 1.0]"));
    auto cam = load_euroc_camera_yaml(path);
    ASSERT_FALSE(cam.ok());
    EXPECT_EQ(std::string(cam.status().message()),
              path.string() +
                  ":10:9: key 'T_BS.data': expected a list of 16 numbers (4x4, row-major), got 15 values");
  }
  {
    const auto path = dir.write("cam1/sensor.yaml", replace(kEurocCam0, "rows: 4", "rows: 3"));
    auto cam = load_euroc_camera_yaml(path);
    ASSERT_FALSE(cam.ok());
    EXPECT_EQ(std::string(cam.status().message()),
              path.string() + ":9:9: key 'T_BS.rows': expected 4 (a 4x4 matrix), got '3'");
  }
}

TEST(CalibrationErrors, NegativeOrMissingNoise) {
  test::TempDir dir;
  const auto path = dir.write("imu.yaml",
                              "imu0:\n"
                              "  accelerometer_noise_density: 2.0e-3\n"
                              "  accelerometer_random_walk: 3.0e-3\n"
                              "  gyroscope_noise_density: -1.6968e-04\n"
                              "  update_rate: 200.0\n");
  auto imu = load_kalibr_imu(path);
  ASSERT_FALSE(imu.ok());
  const std::string message(imu.status().message());
  EXPECT_THAT(message, HasSubstr(path.string() +
                                 ":4:28: key 'imu0.gyroscope_noise_density': expected a number > 0, got "
                                 "'-1.6968e-04'"));
  EXPECT_THAT(message, HasSubstr(path.string() +
                                 ":2:3: key 'imu0.gyroscope_random_walk': missing, expected a number > 0"));

  const auto euroc = dir.write("imu0/sensor.yaml", replace(kEurocImu, "rate_hz: 200", "rate_hz: 0"));
  auto e = load_euroc_imu_yaml(euroc);
  ASSERT_FALSE(e.ok());
  EXPECT_THAT(std::string(e.status().message()), HasSubstr("key 'rate_hz': expected a number > 0, got '0'"));
}

TEST(CalibrationErrors, UnknownDistortionAndCameraModel) {
  test::TempDir dir;
  const auto path =
      dir.write("cc.yaml", camchain(replace(replace(kIdentityCam0, "radtan", "fov"), "pinhole", "omni")));
  auto chain = load_kalibr_camchain(path);
  ASSERT_FALSE(chain.ok());
  const std::string message(chain.status().message());
  EXPECT_THAT(message,
              HasSubstr(path.string() + ":7:17: key 'cam0.camera_model': expected 'pinhole' (the only "
                                        "projection supported), got 'omni'"));
  EXPECT_THAT(message, HasSubstr(path.string() + ":9:21: key 'cam0.distortion_model': "));
  EXPECT_THAT(message, HasSubstr("'fov'"));
}

TEST(CalibrationErrors, WrongListSizesAndMissingCamera) {
  test::TempDir dir;
  std::string cam0 = replace(kIdentityCam0, "[400.0, 400.0, 376.0, 240.0]", "[400.0, 400.0, 376.0]");
  cam0 = replace(cam0, "distortion_coeffs: [0.0, 0.0, 0.0, 0.0]", "distortion_coeffs: [0.0, 0.0]");
  cam0 = replace(cam0, "[752, 480]", "[752, 480, 3]");
  const auto path = dir.write("cc.yaml", "cam0:\n" + cam0);
  auto chain = load_kalibr_camchain(path);
  ASSERT_FALSE(chain.ok());
  const std::string message(chain.status().message());
  EXPECT_THAT(message,
              HasSubstr(":10:15: key 'cam0.intrinsics': expected a list of 4 numbers [fu, fv, cu, cv] (px), "
                        "got '[400.0, 400.0, 376.0]'"));
  EXPECT_THAT(message, HasSubstr("key 'cam0.distortion_coeffs': expected a list of 4 numbers"));
  EXPECT_THAT(message,
              HasSubstr("key 'cam0.resolution': expected a list of 2 positive integers [width, height], "
                        "got '[752, 480, 3]'"));
  EXPECT_THAT(message,
              HasSubstr(path.string() + ":1:1: key 'cam1': missing, expected a section (a map of keys)"));
}

TEST(CalibrationErrors, CameraModelValidationIsPassedOn) {
  test::TempDir dir;
  const auto path =
      dir.write("cc.yaml", camchain(replace(kIdentityCam0, "[400.0, 400.0,", "[-400.0, 400.0,")));
  auto chain = load_kalibr_camchain(path);
  ASSERT_FALSE(chain.ok());
  EXPECT_THAT(std::string(chain.status().message()), HasSubstr(path.string() + ":2:3: camera 'cam0': "));
}

TEST(CalibrationErrors, InconsistentStereoChain) {
  test::TempDir dir;
  const std::string good = camchain(kIdentityCam0) +
                           "  T_cn_cnm1:\n"
                           "  - [1.0, 0.0, 0.0, -0.1]\n"
                           "  - [0.0, 1.0, 0.0, 0.0]\n"
                           "  - [0.0, 0.0, 1.0, 0.0]\n"
                           "  - [0.0, 0.0, 0.0, 1.0]\n";
  EXPECT_TRUE(load_kalibr_camchain(dir.write("good.yaml", good)).ok());
  const auto path = dir.write("bad.yaml", replace(good,
                                                  "  - [1.0, 0.0, 0.0, -0.1]\n  - [0.0, 1.0, 0.0, 0.0]\n  - "
                                                  "[0.0, 0.0, 1.0, 0.0]\n  - [0.0, 0.0, 0.0, 1.0]\n",
                                                  "  - [1.0, 0.0, 0.0, -0.2]\n  - [0.0, 1.0, 0.0, 0.0]\n  - "
                                                  "[0.0, 0.0, 1.0, 0.0]\n  - [0.0, 0.0, 0.0, 1.0]\n"));
  // replace() changed cam1's T_cam_imu (the first match); T_cn_cnm1 still says -0.1.
  auto chain = load_kalibr_camchain(path);
  ASSERT_FALSE(chain.ok());
  EXPECT_THAT(std::string(chain.status().message()),
              HasSubstr("key 'cam1.T_cn_cnm1': disagrees with cam0/cam1 T_cam_imu by 0.1"));
}

TEST(CalibrationErrors, MissingFileAndSyntaxError) {
  test::TempDir dir;
  auto missing = load_kalibr_camchain(dir / "nope.yaml");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(missing.status().message()), HasSubstr("nope.yaml"));
  const auto bad = dir.write("bad.yaml", "imu0:\n  update_rate: [200\n");
  auto imu = load_kalibr_imu(bad);
  ASSERT_FALSE(imu.ok());
  EXPECT_THAT(std::string(imu.status().message()), ::testing::StartsWith(bad.string() + ":"));
  EXPECT_THAT(std::string(imu.status().message()), HasSubstr("YAML syntax error"));
}

}  // namespace
}  // namespace mrvs::config
