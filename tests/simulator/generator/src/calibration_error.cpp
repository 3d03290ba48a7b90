#include "mrvs/sim/calibration_error.h"

#include <cmath>

#include <fmt/format.h>
#include <Eigen/SVD>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/file.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

/// Draws keyed by (what, camera, component).
enum Draw : std::uint64_t {
  kRotation = 1,
  kTranslation,
  kIntrinsics,
  kStereoRotation,
  kStereoTranslation,
  kTime
};

Vec3d draw3(const CounterRng& rng, Draw what, double sigma) {
  return sigma * Vec3d(rng.normal(what, 0, 0), rng.normal(what, 0, 1), rng.normal(what, 0, 2));
}

/// T with its rotation left-multiplied by exp(dtheta) and dp added to its translation.
Mat4d perturbed(const Mat4d& T, const Vec3d& dtheta, const Vec3d& dp) {
  Mat4d out = T;
  out.topLeftCorner<3, 3>() = so3::exp(dtheta) * T.topLeftCorner<3, 3>();
  out.topRightCorner<3, 1>() += dp;
  return out;
}

void perturb_intrinsics(const CounterRng& rng, int cam, const CalibrationErrorOptions& o, camera::Params& p) {
  const double sigma[8] = {o.focal_px,  o.focal_px,  o.principal_point_px, o.principal_point_px,
                           o.radial_k1, o.radial_k2, o.tangential,         o.tangential};
  for (int i = 0; i < 8; ++i) {
    p[i] +=
        sigma[i] * rng.normal(kIntrinsics, static_cast<std::uint64_t>(cam), static_cast<std::uint64_t>(i));
  }
}

/// The rotation R_w_t (true camera -> written camera) that best maps the true camera's ray of
/// each pixel of a 16 x 10 grid onto the written camera's ray of the same pixel (Kabsch):
/// the share of an intrinsic error that a calibration moves into the camera's orientation
/// (target reprojections pin the rays, not the parameters one by one). Identity when either
/// camera cannot be built.
Mat3d compensating_rotation(const RigCamera& written, const camera::Params& true_params) {
  auto w = camera::make_camera(written.model, written.width, written.height, written.params);
  auto t = camera::make_camera(written.model, written.width, written.height, true_params);
  if (!w.ok() || !t.ok()) return Mat3d::Identity();
  constexpr int kU = 16, kV = 10;
  Mat3d H = Mat3d::Zero();
  for (int j = 0; j < kV; ++j) {
    for (int i = 0; i < kU; ++i) {
      const Vec2d uv((i + 0.5) * written.width / kU, (j + 0.5) * written.height / kV);
      const StatusOr<Vec3d> a = (*w)->unproject(uv), b = (*t)->unproject(uv);
      if (a.ok() && b.ok()) H += *b * a->transpose();
    }
  }
  const Eigen::JacobiSVD<Mat3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3d D = Mat3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  return svd.matrixV() * D * svd.matrixU().transpose();
}

Mat4d rotated(const Mat4d& T, const Mat3d& R) {
  Mat4d out = T;
  out.topLeftCorner<3, 3>() = T.topLeftCorner<3, 3>() * R;
  return out;
}

}  // namespace

TrueCalibration draw_true_calibration(const Rig& written, double time_offset_ms,
                                      const CalibrationErrorOptions& o, std::uint64_t seed) {
  TrueCalibration truth{written, time_offset_ms};
  if (!o.enabled) return truth;
  const CounterRng rng(seed, Stream::kCalibration);
  const Mat4d& T_b_c0 = written.cameras[0].T_BS;
  const Mat4d T_c0_c1 = T_b_c0.inverse() * written.cameras[1].T_BS;
  const Mat4d T_c0_c1_true =
      perturbed(T_c0_c1, draw3(rng, kStereoRotation, o.stereo_rotation_deg * kDegToRad),
                draw3(rng, kStereoTranslation, 1e-3 * o.stereo_translation_mm));
  const Mat4d T_b_c0_true = perturbed(T_b_c0, draw3(rng, kRotation, o.rotation_deg * kDegToRad),
                                      draw3(rng, kTranslation, 1e-3 * o.translation_mm));
  for (int c = 0; c < 2; ++c) {
    RigCamera& cam = truth.rig.cameras[static_cast<std::size_t>(c)];
    perturb_intrinsics(rng, c, o, cam.params);
    truth.R_compensation[static_cast<std::size_t>(c)] =
        o.compensate_intrinsics
            ? compensating_rotation(written.cameras[static_cast<std::size_t>(c)], cam.params)
            : Mat3d::Identity();
  }
  truth.rig.cameras[0].T_BS = rotated(T_b_c0_true, truth.R_compensation[0]);
  truth.rig.cameras[1].T_BS = rotated(T_b_c0_true * T_c0_c1_true, truth.R_compensation[1]);
  truth.time_offset_ms += o.time_offset_ms * rng.normal(kTime);
  return truth;
}

Status write_true_calibration(const std::filesystem::path& dir, const TrueCalibration& truth) {
  for (int c = 0; c < 2; ++c) {
    MRVS_RETURN_IF_ERROR(write_file_atomically(dir / fmt::format("cam{}/sensor.yaml", c),
                                               camera_sensor_yaml(truth.rig.cameras[c])));
  }
  return write_file_atomically(
      dir / "time_offset.yaml",
      fmt::format("# True camera-IMU time offset t_d (t_imu = t_cam + t_d) of the rendered rig, ms.\n"
                  "time_offset_ms: {}\n",
                  truth.time_offset_ms));
}

StatusOr<double> read_true_time_offset_ms(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "time_offset.yaml";
  MRVS_ASSIGN_OR_RETURN(const config::YamlDocument doc, config::load_yaml_file(path));
  try {
    return doc.root["time_offset_ms"].as<double>();
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(fmt::format("{}: needs time_offset_ms ({})", path.string(), e.what()));
  }
}

}  // namespace mrvs::sim
