#include "mrvs/edge/dense_stereo.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "mrvs/camera/pinhole_radtan.h"

namespace mrvs::edge {
namespace {

/// OpenCV's disparity fixed point: 4 fractional bits.
constexpr double kDisparityScale = 16.0;
/// StereoBM's sub-pixel disparity is rounded as floor((256 d + 15) / 16) / 16 (stereobm.cpp,
/// OpenCV 3.x-4.x): on average 15/32 of a sixteenth, 0.029 px, too large, which puts every
/// point 0.029 z^2 / (f b) too near (2 mm at 1.5 m on the EuRoC rig at downsample 2;
/// test_dense_stereo measures it on a rendered plane). Subtracted, in sixteenths.
constexpr double kBmRoundingBias = 15.0 / 32.0;

Status check_cameras(const config::StereoRigCalibration& rig) {
  for (std::size_t c = 0; c < 2; ++c) {
    const auto& model = rig.cameras[c].model;
    if (!model) {
      return absl::InvalidArgumentError(fmt::format("dense stereo: camera {} has no model (calibration)", c));
    }
    if (model->width() < 32 || model->height() < 32) {
      return absl::InvalidArgumentError(
          fmt::format("dense stereo: camera {} images of {}x{} px are too small", c, model->width(),
                      model->height()) +
          " (at least 32x32)");
    }
  }
  return absl::OkStatus();
}

/// Raw level pixel of the rectified ray `p_c` (camera frame) through `cam`; nullopt behind
/// the camera or, for radtan, beyond the radius where the model folds over.
std::optional<Vec2d> raw_level_pixel(const camera::CameraModel& cam, double max_radius, const Vec3d& p_c,
                                     int s) {
  if (!(p_c.z() > 1e-9)) return std::nullopt;
  const Vec2d xn = p_c.head<2>() / p_c.z();
  if (!(xn.norm() < max_radius)) return std::nullopt;
  const Vec2d uv = cam.distort(xn);
  return Vec2d((uv.x() + 0.5) / s - 0.5, (uv.y() + 0.5) / s - 0.5);
}

/// Fills rect->map[c] and rect->valid[c] for camera `cam` seen from the rectified frame
/// through R_c_r.
void build_map(const camera::CameraModel& cam, const Mat3d& R_c_r, StereoRectification* rect, std::size_t c) {
  const int s = rect->downsample;
  const auto* radtan = dynamic_cast<const camera::PinholeRadtan*>(&cam);
  const double max_radius = radtan ? radtan->max_monotonic_radius() : std::numeric_limits<double>::infinity();
  // The raw camera's level image (whole s x s blocks, see DenseStereo::rectify).
  const auto raw_w = static_cast<double>(cam.width() / s), raw_h = static_cast<double>(cam.height() / s);
  cv::Mat map(rect->height, rect->width, CV_32FC2);
  cv::Mat valid(rect->height, rect->width, CV_8UC1);
  for (int v = 0; v < rect->height; ++v) {
    auto* m = map.ptr<cv::Vec2f>(v);
    auto* ok = valid.ptr<std::uint8_t>(v);
    for (int u = 0; u < rect->width; ++u) {
      const Vec3d ray((u - rect->cx) / rect->f, (v - rect->cy) / rect->f, 1.0);
      const std::optional<Vec2d> uv = raw_level_pixel(cam, max_radius, R_c_r * ray, s);
      const bool inside =
          uv && uv->x() >= 0.0 && uv->y() >= 0.0 && uv->x() <= raw_w - 1.0 && uv->y() <= raw_h - 1.0;
      m[u] = inside ? cv::Vec2f(static_cast<float>(uv->x()), static_cast<float>(uv->y()))
                    : cv::Vec2f(-1.0f, -1.0f);
      ok[u] = inside ? 255 : 0;
    }
  }
  rect->map[c] = map;
  rect->valid[c] = valid;
}

/// Rotation of the rectified frame into c0: x along the baseline p_c0_c1, z closest to the
/// mean optical axis of the two cameras.
StatusOr<Mat3d> rectifying_rotation(const SE3d& T_c0_c1) {
  const Vec3d t = T_c0_c1.translation();
  if (!(t.norm() > 1e-6)) {
    return absl::InvalidArgumentError(fmt::format(
        "dense stereo: the baseline |p_c0_c1| is {} m: the calibration's T_b_c of cam0 and cam1 must differ",
        t.norm()));
  }
  const Vec3d x = t.normalized();
  if (x.x() < std::cos(M_PI / 4.0)) {
    return absl::InvalidArgumentError(fmt::format(
        "dense stereo: cam1 must lie to the right of cam0 (baseline direction within 45 deg of cam0's +x), "
        "p_c0_c1 = ({:.4f}, {:.4f}, {:.4f}) m",
        t.x(), t.y(), t.z()));
  }
  const Vec3d z_mean = (Vec3d::UnitZ() + T_c0_c1.rotation_matrix() * Vec3d::UnitZ()).normalized();
  const Vec3d y = z_mean.cross(x).normalized();
  Mat3d R_c0_r;
  R_c0_r.col(0) = x;
  R_c0_r.col(1) = y;
  R_c0_r.col(2) = x.cross(y);
  return R_c0_r;
}

/// The matcher of `o` over `num_disparities` level pixels.
StatusOr<cv::Ptr<cv::StereoMatcher>> make_matcher(const DenseStereoOptions& o, int num_disparities) {
  try {
    if (o.matcher == "bm") {
      cv::Ptr<cv::StereoBM> bm = cv::StereoBM::create(num_disparities, o.block_size);
      bm->setPreFilterCap(o.pre_filter_cap);
      bm->setUniquenessRatio(o.uniqueness_ratio);
      bm->setTextureThreshold(0);  // min_texture instead (same units for every matcher)
      bm->setSpeckleWindowSize(o.speckle_window);
      bm->setSpeckleRange(o.speckle_range);
      bm->setDisp12MaxDiff(o.lr_max_diff);
      return cv::Ptr<cv::StereoMatcher>(bm);
    }
    const int area = o.block_size * o.block_size;
    const int mode = o.matcher == "sgbm_3way" ? cv::StereoSGBM::MODE_SGBM_3WAY : cv::StereoSGBM::MODE_SGBM;
    return cv::Ptr<cv::StereoMatcher>(cv::StereoSGBM::create(
        0, num_disparities, o.block_size, 8 * area, 32 * area, o.lr_max_diff, o.pre_filter_cap,
        o.uniqueness_ratio, o.speckle_window, o.speckle_range, mode));
  } catch (const cv::Exception& e) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: OpenCV rejected the matcher options: {}", e.what()));
  }
}

/// Checks what visit() cannot express; returns the disparity range to search.
StatusOr<int> checked_disparities(const DenseStereoOptions& o, const StereoRectification& rect) {
  if (o.block_size % 2 == 0) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: block_size must be odd, got {}", o.block_size));
  }
  if (o.matcher == "bm" && o.block_size < 5) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: matcher 'bm' needs block_size >= 5, got {}", o.block_size));
  }
  if (o.min_depth_m >= o.max_depth_m) {
    return absl::InvalidArgumentError(fmt::format(
        "dense stereo: min_depth_m ({}) must be below max_depth_m ({})", o.min_depth_m, o.max_depth_m));
  }
  if (o.num_disparities % 16 != 0) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: num_disparities must be a multiple of 16 (or 0: from min_depth_m), got {}",
                    o.num_disparities));
  }
  int n = o.num_disparities;
  if (n == 0) n = 16 * static_cast<int>(std::ceil(rect.f * rect.baseline_m / o.min_depth_m / 16.0));
  const int most = std::min(512, rect.width / 2);
  if (n > most) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: {} px of disparity at downsample {} ({}x{} px), at most {}: ", n,
                    rect.downsample, rect.width, rect.height, most) +
        fmt::format("raise min_depth_m ({} m) or downsample, or set num_disparities", o.min_depth_m));
  }
  return n;
}

/// Keeps `max` of `points` (all when fewer): the floor(i n / max)-th for i = 0 .. max - 1.
template <class T>
void thin_evenly(std::size_t max, std::vector<T>* points) {
  const std::size_t n = points->size();
  if (n <= max) return;
  // Index i * n / max >= i: every point is read before its slot is overwritten.
  for (std::size_t i = 0; i < max; ++i) (*points)[i] = (*points)[i * n / max];
  points->resize(max);
}

}  // namespace

std::optional<Vec2d> StereoRectification::rectified_pixel(const config::StereoRigCalibration& rig, int cam,
                                                          const Vec2d& uv) const {
  if (cam < 0 || cam > 1 || !rig.cameras[static_cast<std::size_t>(cam)].model) return std::nullopt;
  StatusOr<Vec3d> bearing = rig.cameras[static_cast<std::size_t>(cam)].model->unproject(uv);
  if (!bearing.ok()) return std::nullopt;
  const Mat3d R_c0_c = cam == 0 ? Mat3d::Identity() : rig.T_c0_c1().rotation_matrix();
  const Vec3d p_r = R_c0_r.transpose() * (R_c0_c * *bearing);
  if (!(p_r.z() > 1e-9)) return std::nullopt;
  return Vec2d(f * p_r.x() / p_r.z() + cx, f * p_r.y() / p_r.z() + cy);
}

StatusOr<StereoRectification> rectify_stereo_rig(const config::StereoRigCalibration& rig, int downsample) {
  if (downsample != 1 && downsample != 2 && downsample != 4) {
    return absl::InvalidArgumentError(
        fmt::format("dense stereo: downsample must be 1, 2 or 4, got {}", downsample));
  }
  MRVS_RETURN_IF_ERROR(check_cameras(rig));
  const SE3d T_c0_c1 = rig.T_c0_c1();
  MRVS_ASSIGN_OR_RETURN(const Mat3d R_c0_r, rectifying_rotation(T_c0_c1));
  const auto& cam0 = *rig.cameras[0].model;
  const auto& cam1 = *rig.cameras[1].model;
  StereoRectification rect;
  rect.downsample = downsample;
  rect.width = cam0.width() / downsample;
  rect.height = cam0.height() / downsample;
  rect.f = std::min({cam0.fx(), cam0.fy(), cam1.fx(), cam1.fy()}) / downsample;
  rect.cx = 0.5 * (rect.width - 1);
  rect.cy = 0.5 * (rect.height - 1);
  rect.baseline_m = T_c0_c1.translation().norm();
  rect.R_c0_r = R_c0_r;
  rect.raw_size = {cv::Size(cam0.width(), cam0.height()), cv::Size(cam1.width(), cam1.height())};
  build_map(cam0, R_c0_r, &rect, 0);
  build_map(cam1, T_c0_c1.rotation_matrix().transpose() * R_c0_r, &rect, 1);
  return rect;
}

DenseStereo::DenseStereo(const DenseStereoOptions& options, StereoRectification rect, int num_disparities)
    : options_(options), rect_(std::move(rect)), num_disparities_(num_disparities) {}

StatusOr<DenseStereo> DenseStereo::create(const DenseStereoOptions& options,
                                          const config::StereoRigCalibration& rig) {
  if (Status s = config::validate_options(options); !s.ok()) {
    return absl::InvalidArgumentError(fmt::format("dense stereo options: {}", std::string(s.message())));
  }
  MRVS_ASSIGN_OR_RETURN(StereoRectification rect, rectify_stereo_rig(rig, options.downsample));
  MRVS_ASSIGN_OR_RETURN(const int num_disparities, checked_disparities(options, rect));
  DenseStereo out(options, std::move(rect), num_disparities);
  MRVS_ASSIGN_OR_RETURN(out.matcher_, make_matcher(options, num_disparities));
  try {
    for (std::size_t c = 0; c < 2; ++c) {
      cv::convertMaps(out.rect_.map[c], cv::Mat(), out.fixed_map_[c], out.fixed_frac_[c], CV_16SC2);
    }
  } catch (const cv::Exception& e) {
    return absl::InternalError(
        fmt::format("dense stereo: cannot convert the rectification maps: {}", e.what()));
  }
  return out;
}

Status DenseStereo::check_input(const cv::Mat& left, const cv::Mat& right) const {
  const std::array<const cv::Mat*, 2> images = {&left, &right};
  for (std::size_t c = 0; c < 2; ++c) {
    const cv::Size& cam = rect_.raw_size[c];
    const cv::Mat& img = *images[c];
    if (img.empty() || img.type() != CV_8UC1 || img.cols != cam.width || img.rows != cam.height) {
      return absl::InvalidArgumentError(
          fmt::format("dense stereo: the {} image (cam{}) is {}x{} of type {}, ", c == 0 ? "left" : "right",
                      c, img.cols, img.rows, cv::typeToString(img.type())) +
          fmt::format("expected {}x{} CV_8UC1 (the calibrated size, 8-bit grey)", cam.width, cam.height));
    }
  }
  return absl::OkStatus();
}

StatusOr<std::array<cv::Mat, 2>> DenseStereo::rectify(const cv::Mat& left, const cv::Mat& right) const {
  MRVS_RETURN_IF_ERROR(check_input(left, right));
  const int s = rect_.downsample;
  std::array<cv::Mat, 2> out;
  try {
    const std::array<const cv::Mat*, 2> raw = {&left, &right};
    for (std::size_t c = 0; c < 2; ++c) {
      cv::Mat level = *raw[c];
      if (s > 1) {
        // INTER_AREA over whole s x s blocks: level pixel u_L covers raw pixels s u_L .. s u_L + s - 1.
        const cv::Rect whole(0, 0, level.cols / s * s, level.rows / s * s);
        cv::resize(level(whole), level, cv::Size(whole.width / s, whole.height / s), 0.0, 0.0,
                   cv::INTER_AREA);
      }
      cv::remap(level, out[c], fixed_map_[c], fixed_frac_[c], cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                cv::Scalar(0));
    }
  } catch (const cv::Exception& e) {
    return absl::InternalError(fmt::format("dense stereo: rectification failed: {}", e.what()));
  }
  return out;
}

StatusOr<cv::Mat> DenseStereo::disparity(const std::array<cv::Mat, 2>& rectified) const {
  cv::Mat disparity;
  try {
    matcher_->compute(rectified[0], rectified[1], disparity);
  } catch (const cv::Exception& e) {
    return absl::InternalError(fmt::format("dense stereo: the matcher failed: {}", e.what()));
  }
  return disparity;
}

StatusOr<cv::Mat> DenseStereo::texture_mask(const cv::Mat& left) const {
  if (options_.min_texture <= 0.0) return cv::Mat();
  cv::Mat gx, mask;
  try {
    cv::Sobel(left, gx, CV_32F, 1, 0, 3, 1.0 / 8.0);  // grey levels per px
    gx = cv::abs(gx);
    cv::boxFilter(gx, gx, CV_32F, cv::Size(options_.block_size, options_.block_size));
    mask = gx >= options_.min_texture;
  } catch (const cv::Exception& e) {
    return absl::InternalError(fmt::format("dense stereo: texture filter failed: {}", e.what()));
  }
  return mask;
}

StatusOr<std::vector<Eigen::Vector3f>> DenseStereo::points(const cv::Mat& left, const cv::Mat& right,
                                                           std::vector<std::uint8_t>* brightness) const {
  using Pair = std::array<cv::Mat, 2>;
  MRVS_ASSIGN_OR_RETURN(const Pair rectified, rectify(left, right));
  MRVS_ASSIGN_OR_RETURN(const cv::Mat disp, disparity(rectified));
  MRVS_ASSIGN_OR_RETURN(const cv::Mat textured, texture_mask(rectified[0]));
  cv::Mat smooth;  // the brightness around each pixel: a 3 x 3 box at the level (6 x 6 raw pixels at 2)
  if (brightness) {
    brightness->clear();
    try {
      cv::blur(rectified[0], smooth, cv::Size(3, 3));
    } catch (const cv::Exception& e) {
      return absl::InternalError(fmt::format("dense stereo: brightness blur failed: {}", e.what()));
    }
  }
  const int step = options_.pixel_step;
  const double fb = rect_.f * rect_.baseline_m;
  const double bias16 = options_.matcher == "bm" ? kBmRoundingBias : 0.0;
  std::vector<Eigen::Vector3f> out;
  for (int v = 0; v < disp.rows; v += step) {
    const auto* d16 = disp.ptr<std::int16_t>(v);
    const auto* left_ok = rect_.valid[0].ptr<std::uint8_t>(v);
    const auto* right_ok = rect_.valid[1].ptr<std::uint8_t>(v);
    for (int u = 0; u < disp.cols; u += step) {
      if (d16[u] <= 0 || left_ok[u] == 0) continue;
      if (!textured.empty() && textured.at<std::uint8_t>(v, u) == 0) continue;
      const double d = (d16[u] - bias16) / kDisparityScale;
      const int u_right = static_cast<int>(std::lround(u - d));
      if (u_right < 0 || right_ok[u_right] == 0) continue;
      const double z = fb / d;
      const Vec3d p_c0 = rect_.R_c0_r * Vec3d((u - rect_.cx) * z / rect_.f, (v - rect_.cy) * z / rect_.f, z);
      if (p_c0.z() < options_.min_depth_m || p_c0.z() > options_.max_depth_m) continue;
      out.push_back(p_c0.cast<float>());
      if (brightness) brightness->push_back(std::max<std::uint8_t>(1, smooth.at<std::uint8_t>(v, u)));
    }
  }
  if (options_.max_points > 0) {
    thin_evenly(static_cast<std::size_t>(options_.max_points), &out);
    if (brightness) thin_evenly(static_cast<std::size_t>(options_.max_points), brightness);
  }
  return out;
}

}  // namespace mrvs::edge
