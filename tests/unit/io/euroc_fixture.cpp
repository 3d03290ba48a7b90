#include "euroc_fixture.h"

#include "mrvs/test/euroc_sensor_yaml.h"

#include <array>
#include <stdexcept>

#include <fmt/format.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

namespace mrvs::io::test_fixture {
namespace {

// Real EuRoC sensor.yaml files with the intrinsics shrunk to the tiny test images.
std::string camera_yaml(int cam, const EurocSpec& spec) {
  const std::array<double, 4> intrinsics =
      cam == 0 ? std::array<double, 4>{20.5, 20.25, 7.5, 5.5} : std::array<double, 4>{20.0, 19.5, 8.0, 6.0};
  return test::euroc_camera_sensor_yaml(cam, spec.width, spec.height, intrinsics);
}

std::string groundtruth_csv(const EurocSpec& spec) {
  std::string text =
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
      "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad "
      "s^-1], "
      "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\r\n";
  const int n = spec.frames * spec.imu_per_frame;
  for (int k = 0; k < n; ++k) {
    text += fmt::format(
        "{}, {}, -1.786938, 0.783338, 0.534108, -0.153029, -0.827383, -0.082152, {}, 0.033207, "
        "0.800006, -0.002229, 0.020700, 0.076126, -0.012492, 0.547666, 0.069073\r\n",
        imu_t_ns(spec, k), 4.5 + 0.001 * k, -0.027876 * k);
  }
  return text;
}

void write_png(const std::filesystem::path& path, int width, int height, int value) {
  std::filesystem::create_directories(path.parent_path());
  const cv::Mat image(height, width, CV_8UC1, cv::Scalar(value));
  if (!cv::imwrite(path.string(), image)) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

TimestampNs image_t_ns(const EurocSpec& spec, int k) { return spec.t0_ns + k * spec.frame_period_ns; }

TimestampNs imu_t_ns(const EurocSpec& spec, int k) {
  // The IMU starts 5 ms before the first image, as in EuRoC.
  return spec.t0_ns - 5'000'000 + k * (spec.frame_period_ns / spec.imu_per_frame);
}

// Divisions are correctly rounded, so k / 100.0 is the double of the literal "0.0k".
Vec3d imu_gyro(int k) { return Vec3d(k / 100.0, -0.125, k / 1e5); }
Vec3d imu_accel(int k) { return Vec3d(9.81, -0.5 * k, (10 * k + 1) / 10.0); }
int pixel_value(int cam, int k) { return 10 + 20 * k + cam; }

std::string image_csv(const EurocSpec& spec) {
  std::string text = "#timestamp [ns],filename\r\n";
  for (int k = 0; k < spec.frames; ++k) {
    text += fmt::format("{}, {}.png\r\n", image_t_ns(spec, k), image_t_ns(spec, k));
  }
  return text;
}

std::string imu_csv(const EurocSpec& spec) {
  std::string text =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m s^-2],"
      "a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\r\n";
  const int n = spec.frames * spec.imu_per_frame;
  for (int k = 0; k < n; ++k) {
    const Vec3d w = imu_gyro(k);
    const Vec3d a = imu_accel(k);
    text += fmt::format("{}, {}, {}, {}, {}, {}, {}\r\n", imu_t_ns(spec, k), w.x(), w.y(), w.z(), a.x(),
                        a.y(), a.z());
  }
  return text;
}

std::filesystem::path write_euroc_sequence(const test::TempDir& dir, const EurocSpec& spec,
                                           const std::string& name) {
  const std::string mav0 = name + "/mav0/";
  dir.write(mav0 + "cam0/sensor.yaml", camera_yaml(0, spec));
  dir.write(mav0 + "cam1/sensor.yaml", camera_yaml(1, spec));
  dir.write(mav0 + "imu0/sensor.yaml", test::euroc_imu_sensor_yaml(/*opencv_header=*/true));
  for (int cam = 0; cam < 2; ++cam) {
    dir.write(mav0 + fmt::format("cam{}/data.csv", cam), image_csv(spec));
    for (int k = 0; k < spec.frames; ++k) {
      write_png(dir / (mav0 + fmt::format("cam{}/data/{}.png", cam, image_t_ns(spec, k))), spec.width,
                spec.height, pixel_value(cam, k));
    }
  }
  dir.write(mav0 + "imu0/data.csv", imu_csv(spec));
  if (spec.groundtruth) dir.write(mav0 + "state_groundtruth_estimate0/data.csv", groundtruth_csv(spec));
  return dir / name;
}

}  // namespace mrvs::io::test_fixture
