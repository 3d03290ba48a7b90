#include "mrvs/camera/camera_model.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "mrvs/camera/pinhole_equidistant.h"
#include "mrvs/camera/pinhole_radtan.h"

namespace mrvs::camera {
namespace {

struct ModelName {
  const char* name;
  DistortionModel model;
};

// Every spelling accepted by distortion_model_from_string (lower case).
constexpr std::array<ModelName, 5> kModelNames = {{
    {"radtan", DistortionModel::kRadTan},
    {"radial-tangential", DistortionModel::kRadTan},
    {"equidistant", DistortionModel::kEquidistant},
    {"equi", DistortionModel::kEquidistant},
    {"fisheye", DistortionModel::kEquidistant},
}};

std::string accepted_model_names() {
  std::string out;
  for (const ModelName& entry : kModelNames) {
    if (!out.empty()) out += ", ";
    out += entry.name;
  }
  return out;
}

Status bad_param(DistortionModel model, int index, double value, const std::string& requirement) {
  return absl::InvalidArgumentError(fmt::format("camera ({}): {} = {} is invalid: {}", to_string(model),
                                                param_name(model, index), value, requirement));
}

}  // namespace

std::string to_string(DistortionModel model) {
  switch (model) {
    case DistortionModel::kRadTan:
      return "radtan";
    case DistortionModel::kEquidistant:
      return "equidistant";
  }
  return "unknown";
}

StatusOr<DistortionModel> distortion_model_from_string(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const ModelName& entry : kModelNames) {
    if (lower == entry.name) return entry.model;
  }
  return absl::InvalidArgumentError(
      fmt::format("unknown camera distortion model '{}' (accepted: {})", name, accepted_model_names()));
}

std::string param_name(DistortionModel model, int index) {
  static constexpr std::array<const char*, kNumParams> kRadtan = {"fx", "fy", "cx", "cy",
                                                                  "k1", "k2", "p1", "p2"};
  static constexpr std::array<const char*, kNumParams> kEquidistant = {"fx", "fy", "cx", "cy",
                                                                       "k1", "k2", "k3", "k4"};
  if (index < 0 || index >= kNumParams) return "?";
  const auto i = static_cast<std::size_t>(index);
  return model == DistortionModel::kRadTan ? kRadtan[i] : kEquidistant[i];
}

Status validate_camera(DistortionModel model, int width, int height, const Params& params) {
  if (width <= 0 || height <= 0) {
    return absl::InvalidArgumentError(
        fmt::format("camera ({}): image size {}x{} is invalid: width and height must be > 0 pixels",
                    to_string(model), width, height));
  }
  for (int i = 0; i < kNumParams; ++i) {
    if (!std::isfinite(params[i])) return bad_param(model, i, params[i], "must be finite");
  }
  for (int i : {0, 1}) {
    if (!(params[i] > 0.0)) return bad_param(model, i, params[i], "focal length must be > 0 pixels");
  }
  const std::array<int, 2> size = {width, height};
  for (int i : {2, 3}) {
    const double hi = size[static_cast<std::size_t>(i - 2)] - 0.5;
    if (params[i] < -0.5 || params[i] > hi) {
      return bad_param(model, i, params[i],
                       fmt::format("principal point must lie in the image, range [-0.5, {}] pixels", hi));
    }
  }
  return absl::OkStatus();
}

StatusOr<std::unique_ptr<CameraModel>> make_camera(DistortionModel model, int width, int height,
                                                   const Params& params) {
  switch (model) {
    case DistortionModel::kRadTan: {
      MRVS_ASSIGN_OR_RETURN(std::unique_ptr<CameraModel> cam, PinholeRadtan::create(width, height, params));
      return cam;
    }
    case DistortionModel::kEquidistant: {
      MRVS_ASSIGN_OR_RETURN(std::unique_ptr<CameraModel> cam,
                            PinholeEquidistant::create(width, height, params));
      return cam;
    }
  }
  return absl::InvalidArgumentError(
      fmt::format("make_camera: unknown distortion model value {}", static_cast<int>(model)));
}

std::optional<Vec2d> CameraModel::project(const Vec3d& p_c, Eigen::Matrix<double, 2, 3>* J_p,
                                          double min_depth) const {
  if (!p_c.allFinite() || !(p_c.z() >= min_depth)) return std::nullopt;
  const double inv_z = 1.0 / p_c.z();
  const Vec2d xn(p_c.x() * inv_z, p_c.y() * inv_z);
  if (J_p == nullptr) return distort(xn);
  Mat2d J_xn;
  const Vec2d uv = distort(xn, &J_xn);
  // d xn / d p_c = [1/z, 0, -x/z^2; 0, 1/z, -y/z^2]
  Eigen::Matrix<double, 2, 3> J_proj;
  J_proj << inv_z, 0.0, -xn.x() * inv_z, 0.0, inv_z, -xn.y() * inv_z;
  *J_p = J_xn * J_proj;
  return uv;
}

StatusOr<Vec3d> CameraModel::unproject(const Vec2d& uv) const {
  MRVS_ASSIGN_OR_RETURN(const Vec2d xn, undistort(uv));
  return Vec3d(xn.x(), xn.y(), 1.0).normalized();
}

bool CameraModel::in_image(const Vec2d& uv, double border) const {
  return uv.x() >= border && uv.y() >= border && uv.x() <= width_ - 1 - border &&
         uv.y() <= height_ - 1 - border;
}

std::string CameraModel::describe() const {
  std::string dist;
  for (int i = 4; i < kNumParams; ++i) {
    if (i > 4) dist += ", ";
    dist += fmt::format("{}", params_[i]);
  }
  return fmt::format("{} {}x{} fx={} fy={} cx={} cy={} d=[{}]", to_string(model()), width_, height_, fx(),
                     fy(), cx(), cy(), dist);
}

}  // namespace mrvs::camera
