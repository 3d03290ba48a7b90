#include "mrvs/sim/rig.h"

#include <cmath>

#include <fmt/format.h>
#include <Eigen/SVD>

namespace mrvs::sim {
namespace {

Mat4d row_major(const std::array<double, 16>& v) {
  Mat4d m;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) m(r, c) = v[4 * r + c];
  }
  return m;
}

camera::Params params(std::array<double, 4> k, std::array<double, 4> d) {
  camera::Params p;
  p << k[0], k[1], k[2], k[3], d[0], d[1], d[2], d[3];
  return p;
}

// The shortest text that reads back to the same double (so the real values come out digit
// for digit); whole numbers keep a ".0" so YAML reads them as floats, as EuRoC writes them.
std::string number(double v) {
  if (v == std::floor(v) && std::abs(v) < 1e15) return fmt::format("{:.1f}", v);
  return fmt::format("{}", v);
}

// "a, b, c, d,\n         e, ..." with negative row starts pulled one column left, as in
// the EuRoC files.
std::string matrix_data(const Mat4d& m) {
  std::string out;
  for (int r = 0; r < 4; ++r) {
    if (r > 0) out += m(r, 0) < 0 ? ",\n        " : ",\n         ";
    out += fmt::format("{}, {}, {}, {}", number(m(r, 0)), number(m(r, 1)), number(m(r, 2)), number(m(r, 3)));
  }
  return out;
}

std::string t_bs_block(const Mat4d& m) {
  return fmt::format("# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [{}]\n",
                     matrix_data(m));
}

}  // namespace

int Rig::imu_samples_per_frame() const {
  return static_cast<int>(std::lround(imu.rate_hz / cameras[0].rate_hz));
}

StatusOr<config::StereoRigCalibration> Rig::calibration() const {
  config::StereoRigCalibration calib;
  for (int i = 0; i < 2; ++i) {
    const RigCamera& c = cameras[i];
    auto model = camera::make_camera(c.model, c.width, c.height, c.params);
    if (!model.ok()) {
      return absl::InvalidArgumentError(
          fmt::format("rig {} {}: {}", name, c.name, std::string(model.status().message())));
    }
    calib.cameras[i].name = c.name;
    calib.cameras[i].model = std::move(*model);
    calib.cameras[i].T_b_c = SE3d::from_matrix(c.T_BS);
    calib.cameras[i].rate_hz = c.rate_hz;
  }
  calib.imu.gyroscope_noise_density = imu.gyroscope_noise_density;
  calib.imu.gyroscope_random_walk = imu.gyroscope_random_walk;
  calib.imu.accelerometer_noise_density = imu.accelerometer_noise_density;
  calib.imu.accelerometer_random_walk = imu.accelerometer_random_walk;
  calib.imu.rate_hz = imu.rate_hz;
  return calib;
}

Mat4d orthonormalized(const Mat4d& T) {
  const Eigen::JacobiSVD<Mat3d> svd(T.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3d R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0) {
    Mat3d U = svd.matrixU();
    U.col(2) *= -1;
    R = U * svd.matrixV().transpose();
  }
  Mat4d out = T;
  out.topLeftCorner<3, 3>() = R;
  out.row(3) << 0, 0, 0, 1;
  return out;
}

Rig euroc_rig() {
  Rig rig;
  rig.name = "euroc";
  rig.cameras[0] = {
      "cam0",
      "VI-Sensor cam0 (MT9M034)",
      row_major({0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,  //
                 0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,      //
                 -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,  //
                 0.0, 0.0, 0.0, 1.0}),
      752,
      480,
      20.0,
      camera::DistortionModel::kRadTan,
      params({458.654, 457.296, 367.215, 248.375}, {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05})};
  rig.cameras[1] = {
      "cam1",
      "VI-Sensor cam1 (MT9M034)",
      row_major({0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,  //
                 0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,    //
                 -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,  //
                 0.0, 0.0, 0.0, 1.0}),
      752,
      480,
      20.0,
      camera::DistortionModel::kRadTan,
      params({457.587, 456.134, 379.999, 255.238}, {-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05})};
  rig.imu = {"VI-Sensor IMU (ADIS16448)", 200.0, 1.6968e-04, 1.9393e-05, 2.0e-3, 3.0e-3, 9.81};
  return rig;
}

Rig kaist_like_rig() {
  Rig rig;
  rig.name = "kaist_like";
  rig.cameras[0] = {"cam0",
                    "KAIST-like stereo left (synthetic)",
                    orthonormalized(row_major({-0.00681, -0.01532, 0.99987, 1.71239,  //
                                               -0.99998, 0.00033, -0.00680, 0.24740,  //
                                               -0.00023, -0.99988, -0.01532, -0.11589, 0, 0, 0, 1})),
                    1280,
                    560,
                    10.0,
                    camera::DistortionModel::kRadTan,
                    params({816.903790, 811.568038, 608.507263, 263.475998},
                           {-0.0561430, 0.139526, -0.00121559, -0.000972814})};
  rig.cameras[1] = {"cam1",
                    "KAIST-like stereo right (synthetic)",
                    orthonormalized(row_major({-0.01036, -0.01075, 0.99990, 1.70544,    //
                                               -0.99994, -0.00178, -0.01038, -0.22770,  //
                                               0.00189, -0.99994, -0.01073, -0.11611, 0, 0, 0, 1})),
                    1280,
                    560,
                    10.0,
                    camera::DistortionModel::kRadTan,
                    params({813.782055, 808.521656, 613.864195, 249.410493},
                           {-0.0549220, 0.142437, 0.0000754123, -0.000675605})};
  rig.imu = {"KAIST-like Xsens MTi-300 (synthetic)", 100.0, 1.7453e-4, 1.0e-5, 5.886e-3, 1.0e-4, 9.80766};
  return rig;
}

std::string camera_sensor_yaml(const RigCamera& c) {
  return fmt::format(
      "# General sensor definitions.\nsensor_type: camera\ncomment: {}\n\n{}\n"
      "# Camera specific definitions.\nrate_hz: {}\nresolution: [{}, {}]\ncamera_model: pinhole\n"
      "intrinsics: [{}, {}, {}, {}] #fu, fv, cu, cv\ndistortion_model: {}\n"
      "distortion_coefficients: [{}, {}, {}, {}]\n",
      c.comment, t_bs_block(c.T_BS), c.rate_hz, c.width, c.height, number(c.params[0]), number(c.params[1]),
      number(c.params[2]), number(c.params[3]),
      c.model == camera::DistortionModel::kRadTan ? "radial-tangential" : "equidistant", number(c.params[4]),
      number(c.params[5]), number(c.params[6]), number(c.params[7]));
}

std::string imu_sensor_yaml(const RigImu& imu) {
  return fmt::format(
      "#Default imu sensor yaml file\nsensor_type: imu\ncomment: {}\n\n{}rate_hz: {}\n\n"
      "# inertial sensor noise model parameters (static)\n"
      "gyroscope_noise_density: {:.4e}     # [ rad / s / sqrt(Hz) ]   ( gyro \"white noise\" )\n"
      "gyroscope_random_walk: {:.4e}       # [ rad / s^2 / sqrt(Hz) ] ( gyro bias diffusion )\n"
      "accelerometer_noise_density: {:.4e}  # [ m / s^2 / sqrt(Hz) ]   ( accel \"white noise\" )\n"
      "accelerometer_random_walk: {:.4e}    # [ m / s^3 / sqrt(Hz) ].  ( accel bias diffusion )\n",
      imu.comment, t_bs_block(Mat4d::Identity()), imu.rate_hz, imu.gyroscope_noise_density,
      imu.gyroscope_random_walk, imu.accelerometer_noise_density, imu.accelerometer_random_walk);
}

std::string groundtruth_sensor_yaml(const std::string& comment) {
  return fmt::format("# General sensor definitions.\nsensor_type: visual-inertial\ncomment: {}\n{}", comment,
                     t_bs_block(Mat4d::Identity()));
}

std::string pointcloud_sensor_yaml(const std::string& comment) {
  return fmt::format("# General sensor definitions.\nsensor_type: pointcloud\ncomment: {}\n{}", comment,
                     t_bs_block(Mat4d::Identity()));
}

std::string gnss_sensor_yaml(const GnssSimOptions& gnss, const std::string& comment) {
  Mat4d T_BS = Mat4d::Identity();
  T_BS.topRightCorner<3, 1>() = gnss.lever_arm_m;
  return fmt::format(
      "# General sensor definitions.\nsensor_type: gnss\ncomment: {}\n\n{}\n"
      "# GNSS specific definitions: fixes of the antenna position (T_BS translation) in the map frame.\n"
      "rate_hz: {}  # [ Hz ]\n"
      "sigma_horizontal_m: {}  # [ m ] standard deviation of each horizontal axis (x, y)\n"
      "sigma_vertical_m: {}  # [ m ] standard deviation of z\n"
      "correlation_time_s: {}  # [ s ] time constant of the first-order Gauss-Markov error\n",
      comment, t_bs_block(T_BS), number(gnss.rate_hz), number(gnss.sigma_horizontal_m),
      number(gnss.sigma_vertical_m), number(gnss.correlation_time_s));
}

}  // namespace mrvs::sim
