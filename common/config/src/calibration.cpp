#include "mrvs/config/calibration.h"

#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "mrvs/config/options.h"
#include "mrvs/config/yaml_document.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::config {
namespace {

constexpr double kRotationTolerance = 1e-6;     ///< max |R^T R - I| of a calibrated rotation
constexpr double kLastRowTolerance = 1e-9;      ///< |last row - [0 0 0 1]|
constexpr double kStereoChainTolerance = 1e-5;  ///< Kalibr T_cn_cnm1 vs the T_cam_imu chain

/// Reads calibration values from one map of a document and collects every error.
class Fields {
 public:
  Fields(const YamlDocument& doc, YAML::Node map, std::string prefix, std::vector<std::string>* errors)
      : doc_(doc), map_(std::move(map)), prefix_(std::move(prefix)), errors_(errors) {}

  const YamlDocument& doc() const { return doc_; }
  const YAML::Node& map() const { return map_; }
  std::string key(const std::string& k) const { return prefix_.empty() ? k : prefix_ + "." + k; }
  void error(std::string message) const { errors_->push_back(std::move(message)); }
  /// Fields of the map stored under key `k` (same document and error list).
  Fields child(const YAML::Node& map, const std::string& k) const {
    return Fields(doc_, map, key(k), errors_);
  }

  /// Value node of `k` (undefined when absent); an error when required and absent.
  YAML::Node get(const std::string& k, bool required, const std::string& expected) const {
    if (map_.IsMap()) {
      for (auto it = map_.begin(); it != map_.end(); ++it) {
        if (it->first.IsScalar() && it->first.Scalar() == k) return it->second;
      }
    }
    if (required) {
      error(fmt::format("{}: key '{}': missing, expected {}", location(doc_, map_), key(k), expected));
    }
    return YAML::Node(YAML::NodeType::Undefined);
  }

  /// A number (> 0 when `positive`); nullopt when absent or wrong (error recorded).
  std::optional<double> number(const std::string& k, bool required, bool positive) const {
    const std::string expected = positive ? "a number > 0" : "a number";
    const YAML::Node node = get(k, required, expected);
    if (!node.IsDefined()) return std::nullopt;
    double value = 0.0;
    if (!detail::Codec<double>::decode(node, value) || !std::isfinite(value) ||
        (positive && !(value > 0.0))) {
      error(expected_error(doc_, node, key(k), expected));
      return std::nullopt;
    }
    return value;
  }

  /// A list of exactly n finite numbers (each > 0 when `positive`).
  std::optional<std::vector<double>> numbers(const std::string& k, std::size_t n, bool positive,
                                             const std::string& what) const {
    const std::string expected = fmt::format("a list of {} {}numbers{}", n, positive ? "positive " : "",
                                             what.empty() ? "" : " " + what);
    const YAML::Node node = get(k, true, expected);
    if (!node.IsDefined()) return std::nullopt;
    std::vector<double> values;
    bool ok = detail::Codec<std::vector<double>>::decode(node, values) && values.size() == n;
    for (const double v : values) ok = ok && std::isfinite(v) && (!positive || v > 0.0);
    if (!ok) {
      error(expected_error(doc_, node, key(k), expected));
      return std::nullopt;
    }
    return values;
  }

  /// A string; nullopt when absent or not a scalar.
  std::optional<std::string> text(const std::string& k, bool required, const std::string& expected) const {
    const YAML::Node node = get(k, required, expected);
    if (!node.IsDefined()) return std::nullopt;
    if (!node.IsScalar()) {
      error(expected_error(doc_, node, key(k), expected));
      return std::nullopt;
    }
    return node.Scalar();
  }

 private:
  const YamlDocument& doc_;
  YAML::Node map_;
  std::string prefix_;
  std::vector<std::string>* errors_;
};

std::string join_errors(const std::vector<std::string>& errors) {
  std::string message;
  for (const std::string& e : errors) message += (message.empty() ? "" : "\n") + e;
  return message;
}

/// Checks the last row and the rotation block of a homogeneous transform.
std::optional<SE3d> to_transform(const Fields& f, const YAML::Node& node, const std::string& k,
                                 const Mat4d& m) {
  if (!m.allFinite()) {
    f.error(fmt::format("{}: key '{}': the matrix has non-finite values", location(f.doc(), node), f.key(k)));
    return std::nullopt;
  }
  const Vec4d last_row = m.row(3).transpose();
  if ((last_row - Vec4d(0.0, 0.0, 0.0, 1.0)).cwiseAbs().maxCoeff() > kLastRowTolerance) {
    f.error(fmt::format("{}: key '{}': expected last row [0, 0, 0, 1], got [{}, {}, {}, {}]",
                        location(f.doc(), node), f.key(k), last_row[0], last_row[1], last_row[2],
                        last_row[3]));
    return std::nullopt;
  }
  const Mat3d R = m.topLeftCorner<3, 3>();
  if (!so3::is_rotation_matrix(R, kRotationTolerance)) {
    const double err = (R.transpose() * R - Mat3d::Identity()).cwiseAbs().maxCoeff();
    f.error(
        fmt::format("{}: key '{}': the rotation block is not a rotation matrix: max |R^T R - I| = {:.3g} "
                    "(tolerance {:g}), "
                    "det(R) = {:.6g}",
                    location(f.doc(), node), f.key(k), err, kRotationTolerance, R.determinant()));
    return std::nullopt;
  }
  return SE3d::from_matrix(m);
}

/// Kalibr 4x4 matrix: a list of 4 rows of 4 numbers.
std::optional<SE3d> nested_transform(const Fields& f, const std::string& k) {
  const std::string expected = "a 4x4 matrix (a list of 4 rows of 4 numbers)";
  const YAML::Node node = f.get(k, true, expected);
  if (!node.IsDefined()) return std::nullopt;
  if (!node.IsSequence() || node.size() != 4) {
    const std::string got =
        node.IsSequence() ? fmt::format("{} rows", node.size()) : "'" + node_text(node) + "'";
    f.error(
        fmt::format("{}: key '{}': expected {}, got {}", location(f.doc(), node), f.key(k), expected, got));
    return std::nullopt;
  }
  Mat4d m;
  for (std::size_t r = 0; r < 4; ++r) {
    std::vector<double> row;
    if (!detail::Codec<std::vector<double>>::decode(node[r], row) || row.size() != 4) {
      f.error(expected_error(f.doc(), node[r], fmt::format("{}[{}]", f.key(k), r), "a row of 4 numbers"));
      return std::nullopt;
    }
    for (std::size_t c = 0; c < 4; ++c) m(static_cast<int>(r), static_cast<int>(c)) = row[c];
  }
  return to_transform(f, node, k, m);
}

/// EuRoC / OpenCV matrix: {rows: 4, cols: 4, data: [16 numbers, row-major]}.
std::optional<SE3d> euroc_transform(const Fields& f, const std::string& k) {
  const YAML::Node node = f.get(k, true, "a 4x4 matrix {rows: 4, cols: 4, data: [16 numbers]}");
  if (!node.IsDefined()) return std::nullopt;
  if (!node.IsMap()) {
    f.error(expected_error(f.doc(), node, f.key(k), "a 4x4 matrix {rows: 4, cols: 4, data: [16 numbers]}"));
    return std::nullopt;
  }
  const Fields matrix = f.child(node, k);
  bool ok = true;
  for (const char* dim : {"rows", "cols"}) {
    const YAML::Node n = matrix.get(dim, false, "");
    int value = 0;
    if (n.IsDefined() && (!detail::Codec<int>::decode(n, value) || value != 4)) {
      f.error(expected_error(f.doc(), n, matrix.key(dim), "4 (a 4x4 matrix)"));
      ok = false;
    }
  }
  const YAML::Node data = matrix.get("data", false, "");
  std::vector<double> values;
  if (!data.IsDefined() || !detail::Codec<std::vector<double>>::decode(data, values) || values.size() != 16) {
    const std::string got = !data.IsDefined()   ? "nothing"
                            : data.IsSequence() ? fmt::format("{} values", data.size())
                                                : "'" + node_text(data) + "'";
    f.error(fmt::format("{}: key '{}': expected a list of 16 numbers (4x4, row-major), got {}",
                        location(f.doc(), data.IsDefined() ? data : node), matrix.key("data"), got));
    return std::nullopt;
  }
  if (!ok) return std::nullopt;
  Mat4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = values[static_cast<std::size_t>(i)];
  return to_transform(f, data, k, m);
}

/// Names of the per-format keys of a camera.
struct CameraKeys {
  const char* distortion_coeffs;
  bool kalibr;
};

/// Image size as two positive integers.
std::optional<std::pair<int, int>> resolution(const Fields& f) {
  const std::string expected = "a list of 2 positive integers [width, height]";
  const YAML::Node node = f.get("resolution", true, expected);
  if (!node.IsDefined()) return std::nullopt;
  std::vector<int> wh;
  if (!detail::Codec<std::vector<int>>::decode(node, wh) || wh.size() != 2 || wh[0] <= 0 || wh[1] <= 0) {
    f.error(expected_error(f.doc(), node, f.key("resolution"), expected));
    return std::nullopt;
  }
  return std::make_pair(wh[0], wh[1]);
}

/// Intrinsics, distortion and image size -> camera model (nullptr on error, recorded).
std::shared_ptr<const camera::CameraModel> camera_model(const Fields& f, const CameraKeys& keys,
                                                        const std::string& name) {
  const auto type = f.text("camera_model", false, "'pinhole'");
  if (type && *type != "pinhole") {
    f.error(expected_error(f.doc(), f.get("camera_model", false, ""), f.key("camera_model"),
                           "'pinhole' (the only projection supported)"));
  }
  const std::string models = "a distortion model name ('radtan', 'radial-tangential', 'equidistant')";
  std::optional<camera::DistortionModel> model;
  if (const auto model_name = f.text("distortion_model", true, models)) {
    StatusOr<camera::DistortionModel> parsed = camera::distortion_model_from_string(*model_name);
    if (parsed.ok()) {
      model = *parsed;
    } else {
      f.error(fmt::format("{}: key '{}': {}", location(f.doc(), f.get("distortion_model", false, "")),
                          f.key("distortion_model"), std::string(parsed.status().message())));
    }
  }
  const auto intrinsics = f.numbers("intrinsics", 4, false, "[fu, fv, cu, cv] (px)");
  const auto distortion = f.numbers(keys.distortion_coeffs, 4, false, "(k1, k2, p1, p2 or k1..k4)");
  const auto size = resolution(f);
  if (!model || !intrinsics || !distortion || !size || (type && *type != "pinhole")) return nullptr;
  camera::Params params;
  for (int i = 0; i < 4; ++i) {
    params[i] = (*intrinsics)[static_cast<std::size_t>(i)];
    params[i + 4] = (*distortion)[static_cast<std::size_t>(i)];
  }
  StatusOr<std::unique_ptr<camera::CameraModel>> cam =
      camera::make_camera(*model, size->first, size->second, params);
  if (!cam.ok()) {
    f.error(fmt::format("{}: camera '{}': {}", location(f.doc(), f.map()), name,
                        std::string(cam.status().message())));
    return nullptr;
  }
  return std::shared_ptr<const camera::CameraModel>(std::move(*cam));
}

/// One camera of either format. Returns nullopt when anything failed (errors recorded).
std::optional<CameraCalibration> read_camera(const Fields& f, const CameraKeys& keys,
                                             const std::string& name) {
  CameraCalibration calib;
  calib.name = name;
  calib.model = camera_model(f, keys, name);
  std::optional<SE3d> T_b_c;
  if (keys.kalibr) {
    if (const auto T_c_b = nested_transform(f, "T_cam_imu")) T_b_c = T_c_b->inverse();
    // Optional: t_imu = t_cam + timeshift_cam_imu (seconds).
    if (const auto seconds = f.number("timeshift_cam_imu", false, false)) {
      calib.time_offset_ns = from_seconds(*seconds);
    }
  } else {
    T_b_c = euroc_transform(f, "T_BS");
    if (const auto rate = f.number("rate_hz", false, true)) calib.rate_hz = *rate;
  }
  if (!calib.model || !T_b_c) return std::nullopt;
  calib.T_b_c = *T_b_c;
  return calib;
}

/// The four noise values shared by the EuRoC and Kalibr IMU files.
std::optional<ImuCalibration> read_imu(const Fields& f, const char* rate_key) {
  ImuCalibration imu;
  const auto gn = f.number("gyroscope_noise_density", true, true);
  const auto gw = f.number("gyroscope_random_walk", true, true);
  const auto an = f.number("accelerometer_noise_density", true, true);
  const auto aw = f.number("accelerometer_random_walk", true, true);
  const auto rate = f.number(rate_key, true, true);
  if (!gn || !gw || !an || !aw || !rate) return std::nullopt;
  imu.gyroscope_noise_density = *gn;
  imu.gyroscope_random_walk = *gw;
  imu.accelerometer_noise_density = *an;
  imu.accelerometer_random_walk = *aw;
  imu.rate_hz = *rate;
  return imu;
}

/// Name of an EuRoC camera from its path (".../cam0/sensor.yaml" -> "cam0").
std::string euroc_camera_name(const std::filesystem::path& path) {
  const std::string folder = path.parent_path().filename().string();
  return folder.empty() ? path.stem().string() : folder;
}

/// Kalibr section (cam0, cam1, imu0) of the document root, as Fields.
std::optional<Fields> kalibr_section(const YamlDocument& doc, const std::string& name,
                                     std::vector<std::string>* errors) {
  const Fields root(doc, doc.root, "", errors);
  const YAML::Node node = root.get(name, true, "a section (a map of keys)");
  if (!node.IsDefined()) return std::nullopt;
  if (!node.IsMap()) {
    errors->push_back(expected_error(doc, node, name, "a section (a map of keys)"));
    return std::nullopt;
  }
  return Fields(doc, node, name, errors);
}

/// cam1's optional T_cn_cnm1 must agree with the two T_cam_imu.
void check_stereo_chain(const Fields& cam1, const std::array<CameraCalibration, 2>& cams) {
  if (!cam1.get("T_cn_cnm1", false, "").IsDefined()) return;
  const std::optional<SE3d> T_c1_c0 = nested_transform(cam1, "T_cn_cnm1");
  if (!T_c1_c0) return;
  const Mat4d chain = (cams[1].T_b_c.inverse() * cams[0].T_b_c).matrix();
  const double diff = (chain - T_c1_c0->matrix()).cwiseAbs().maxCoeff();
  if (diff > kStereoChainTolerance) {
    cam1.error(fmt::format(
        "{}: key '{}': disagrees with cam0/cam1 T_cam_imu by {:.3g} (max element difference, tolerance {:g})",
        location(cam1.doc(), cam1.get("T_cn_cnm1", false, "")), cam1.key("T_cn_cnm1"), diff,
        kStereoChainTolerance));
  }
}

template <class T>
StatusOr<T> finish(std::optional<T> value, const std::vector<std::string>& errors) {
  if (!errors.empty() || !value) {
    return absl::InvalidArgumentError(errors.empty() ? std::string("invalid calibration")
                                                     : join_errors(errors));
  }
  return std::move(*value);
}

/// Runs `read` and turns a stray yaml-cpp exception into an error naming the file.
template <class T, class F>
StatusOr<T> guarded(const std::filesystem::path& path, F&& read) {
  try {
    return read();
  } catch (const YAML::Exception& e) {
    return absl::InvalidArgumentError(
        fmt::format("{}: cannot read calibration: {}", path.string(), e.what()));
  }
}

}  // namespace

StatusOr<CameraCalibration> load_euroc_camera_yaml(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(const YamlDocument doc, load_yaml_file(path));
  return guarded<CameraCalibration>(path, [&]() -> StatusOr<CameraCalibration> {
    std::vector<std::string> errors;
    const Fields f(doc, doc.root, "", &errors);
    return finish(read_camera(f, CameraKeys{"distortion_coefficients", false}, euroc_camera_name(path)),
                  errors);
  });
}

StatusOr<ImuCalibration> load_euroc_imu_yaml(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(const YamlDocument doc, load_yaml_file(path));
  return guarded<ImuCalibration>(path, [&]() -> StatusOr<ImuCalibration> {
    std::vector<std::string> errors;
    const Fields f(doc, doc.root, "", &errors);
    return finish(read_imu(f, "rate_hz"), errors);
  });
}

StatusOr<SE3d> read_euroc_T_BS(const YamlDocument& doc) {
  return guarded<SE3d>(doc.name, [&]() -> StatusOr<SE3d> {
    std::vector<std::string> errors;
    const Fields f(doc, doc.root, "", &errors);
    return finish(euroc_transform(f, "T_BS"), errors);
  });
}

StatusOr<std::array<CameraCalibration, 2>> load_kalibr_camchain(const std::filesystem::path& path) {
  using Cameras = std::array<CameraCalibration, 2>;
  MRVS_ASSIGN_OR_RETURN(const YamlDocument doc, load_yaml_file(path));
  return guarded<Cameras>(path, [&]() -> StatusOr<Cameras> {
    std::vector<std::string> errors;
    std::array<std::optional<CameraCalibration>, 2> read;
    for (std::size_t i = 0; i < 2; ++i) {
      const std::string name = fmt::format("cam{}", i);
      const std::optional<Fields> f = kalibr_section(doc, name, &errors);
      if (f) read[i] = read_camera(*f, CameraKeys{"distortion_coeffs", true}, name);
    }
    std::optional<Cameras> cams;
    if (read[0] && read[1]) {
      cams = Cameras{*read[0], *read[1]};
      check_stereo_chain(*kalibr_section(doc, "cam1", &errors), *cams);
    }
    return finish(std::move(cams), errors);
  });
}

StatusOr<ImuCalibration> load_kalibr_imu(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(const YamlDocument doc, load_yaml_file(path));
  return guarded<ImuCalibration>(path, [&]() -> StatusOr<ImuCalibration> {
    std::vector<std::string> errors;
    const std::optional<Fields> f = kalibr_section(doc, "imu0", &errors);
    return finish(f ? read_imu(*f, "update_rate") : std::nullopt, errors);
  });
}

std::string StereoRigCalibration::describe() const {
  std::string out;
  for (const CameraCalibration& cam : cameras) {
    const Vec3d& p = cam.T_b_c.translation();
    const Vec3d phi = so3::log(cam.T_b_c.quaternion());
    const std::string rate = cam.rate_hz > 0.0 ? fmt::format("{} Hz", cam.rate_hz) : std::string("not given");
    out += fmt::format("{}: {} (rate {}, time offset {} ns)\n", cam.name.empty() ? "camera" : cam.name,
                       cam.model ? cam.model->describe() : std::string("no camera model"), rate,
                       cam.time_offset_ns);
    out += fmt::format(
        "  T_b_c: p_b_c = [{:.6f}, {:.6f}, {:.6f}] m, rotation vector = [{:.6f}, {:.6f}, {:.6f}] rad "
        "({:.3f} deg)\n",
        p.x(), p.y(), p.z(), phi.x(), phi.y(), phi.z(), phi.norm() * kRadToDeg);
  }
  const SE3d T = T_c0_c1();
  out += fmt::format("stereo: baseline |p_c0_c1| = {:.6f} m, relative rotation {:.4f} deg\n",
                     T.translation().norm(), so3::log(T.quaternion()).norm() * kRadToDeg);
  out += fmt::format(
      "imu: rate {} Hz, gyroscope noise {:.4e} rad/s/sqrt(Hz), random walk {:.4e} rad/s^2/sqrt(Hz); "
      "accelerometer noise {:.4e} m/s^2/sqrt(Hz), random walk {:.4e} m/s^3/sqrt(Hz)",
      imu.rate_hz, imu.gyroscope_noise_density, imu.gyroscope_random_walk, imu.accelerometer_noise_density,
      imu.accelerometer_random_walk);
  return out;
}

}  // namespace mrvs::config
