#pragma once
// Dense stereo: 3-D points of one raw stereo pair in the cam0 frame, for a local submap the
// cloud can register against its prior map. The pair is down-sampled (INTER_AREA), rectified
// with maps built once from the project's camera models (radtan or equidistant), matched
// with OpenCV's block matcher (or SGBM), filtered (texture, uniqueness, left-right, speckles,
// depth range) and reprojected.
//
// Frames: c0 / c1 the raw cameras, r the rectified frame of cam0 (same centre as c0, x along
// the baseline towards c1, both rectified cameras share its orientation); c1's centre is at
// (baseline_m, 0, 0) in r, so a point at depth z has disparity f * baseline_m / z.
// Pixels: (0, 0) is the centre of the top-left pixel. Level-L pixels (downsample s) relate to
// full-resolution ones by u_L = (u + 0.5) / s - 0.5.
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "mrvs/config/calibration.h"
#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/geometry/types.h"

namespace cv {
class StereoMatcher;
}  // namespace cv

namespace mrvs::edge {

/// Options of DenseStereo. Defaults measured on the realistic indoor sequence (EuRoC rig,
/// 752x480, 0.11 m baseline): see edge_client/README.md, "Dense stereo".
struct DenseStereoOptions : config::OptionsEquality<DenseStereoOptions> {
  int downsample = 2;        ///< image pyramid level the matcher runs on: 1, 2 or 4
  double min_depth_m = 0.5;  ///< nearer points are dropped, m (and the disparity range, see below)
  double max_depth_m = 5.0;  ///< farther points are dropped, m
  /// Disparity search range at the level, px, a multiple of 16; 0: the disparity of
  /// min_depth_m rounded up (64 at downsample 2 on the EuRoC rig).
  int num_disparities = 0;
  /// "bm" (block matching), "sgbm" (semi-global, 5 paths) or "sgbm_3way" (3 paths).
  std::string matcher = "bm";
  int block_size = 15;        ///< matching window side at the level, px (odd; bm: at least 5)
  int pre_filter_cap = 63;    ///< clip of the matcher's x-Sobel pre-filter (1-63)
  int uniqueness_ratio = 10;  ///< the best cost must beat the second best by this many percent
  int speckle_window = 50;    ///< disparity blobs smaller than this are removed, px at the level (0 = off)
  int speckle_range = 1;      ///< disparity spread inside one blob, px at the level
  int lr_max_diff = 1;        ///< left-right consistency, px at the level (-1 = off)
  /// Pixels whose matching window has a mean |d/dx| of the rectified left image below this
  /// are dropped, grey levels per px at the level (0 = off): the matchers fill textureless
  /// surfaces with guesses.
  double min_texture = 3.0;
  int pixel_step = 4;     ///< one point per pixel_step x pixel_step pixels of the level
  int max_points = 4000;  ///< more are thinned evenly (deterministic), 0 = all

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("downsample", downsample, in_range(1, 4), "matcher image level: 1, 2 or 4 (full size / downsample)");
    v("min_depth_m", min_depth_m, in_range(0.01, 1000.0),
      "nearest point kept, m; sets the disparity range when num_disparities is 0");
    v("max_depth_m", max_depth_m, in_range(0.02, 10000.0), "farthest point kept, m");
    v("num_disparities", num_disparities, in_range(0, 512),
      "disparity range at the level, px, a multiple of 16 (0 = from min_depth_m)");
    v("matcher", matcher, one_of({"bm", "sgbm", "sgbm_3way"}), "OpenCV stereo matcher");
    v("block_size", block_size, in_range(1, 31), "matching window side at the level, px (odd; bm: >= 5)");
    v("pre_filter_cap", pre_filter_cap, in_range(1, 63), "matcher pre-filter clip");
    v("uniqueness_ratio", uniqueness_ratio, in_range(0, 100), "uniqueness margin, percent");
    v("speckle_window", speckle_window, in_range(0, 10000), "speckle filter blob size, px (0 = off)");
    v("speckle_range", speckle_range, in_range(0, 64), "speckle filter disparity spread, px");
    v("lr_max_diff", lr_max_diff, in_range(-1, 64), "left-right consistency, px (-1 = off)");
    v("min_texture", min_texture, in_range(0.0, 255.0),
      "mean |x-gradient| of the matching window, grey levels per px (0 = off)");
    v("pixel_step", pixel_step, in_range(1, 64), "one point per step x step pixels of the level");
    v("max_points", max_points, in_range(0, 10000000), "at most this many points (0 = all)");
  }
};

/// The rectified pair at one image level.
struct StereoRectification {
  int downsample = 1;  ///< level scale s: level pixels = full-size pixels / s
  int width = 0;       ///< rectified image size at the level, px
  int height = 0;
  double f = 0.0;   ///< focal length of both rectified cameras, level px
  double cx = 0.0;  ///< principal point of both rectified cameras, level px
  double cy = 0.0;
  double baseline_m = 0.0;           ///< |p_c0_c1|: c1's centre is at (baseline_m, 0, 0) in r
  Mat3d R_c0_r = Mat3d::Identity();  ///< rectified frame -> cam0 (cam1: R_c1_c0 * R_c0_r)
  std::array<cv::Size, 2> raw_size;  ///< full-size raw image of each camera (the calibrated size)
  /// Per camera, CV_32FC2: the raw (distorted) pixel at the level, (x, y), of each rectified
  /// pixel; (-1, -1) where the rectified ray does not reach the raw image.
  std::array<cv::Mat, 2> map;
  /// Per camera, CV_8UC1: 255 where `map` lies inside the raw image.
  std::array<cv::Mat, 2> valid;

  /// Rectified pixel (level) of the full-size raw pixel `uv` of camera `cam`; nullopt when
  /// the camera cannot undistort it or its ray points away from the rectified image plane.
  std::optional<Vec2d> rectified_pixel(const config::StereoRigCalibration& rig, int cam,
                                       const Vec2d& uv) const;
};

/// Rectification of `rig` at level `downsample` (1, 2 or 4). The rectified cameras keep the
/// smallest focal length of the two raw ones (scaled to the level), principal point at the
/// image centre, x along the baseline and z closest to the mean of the two optical axes.
/// Errors name what is wrong: a camera without a model or too small, a zero baseline, cam1
/// not to the right of cam0 (vertical rigs are not supported).
StatusOr<StereoRectification> rectify_stereo_rig(const config::StereoRigCalibration& rig, int downsample);

/// Dense stereo points of raw pairs. Rectification maps and the matcher are built once in
/// create(). points() reuses the matcher's buffers: one object must not be used by two
/// threads at once (give each thread its own).
class DenseStereo {
 public:
  /// Validates the options (ranges, downsample 1 | 2 | 4, odd block size, a multiple-of-16
  /// disparity range) and the calibration, builds the rectification and the matcher.
  static StatusOr<DenseStereo> create(const DenseStereoOptions& options,
                                      const config::StereoRigCalibration& rig);

  DenseStereo(DenseStereo&&) = default;
  DenseStereo& operator=(DenseStereo&&) = default;
  DenseStereo(const DenseStereo&) = delete;  ///< copies would share the matcher's buffers
  DenseStereo& operator=(const DenseStereo&) = delete;

  /// 3-D points (metres) in the cam0 frame from one raw (distorted) stereo pair, CV_8UC1 of
  /// the calibrated sizes: one per pixel_step x pixel_step level pixels with a valid,
  /// consistent disparity whose depth lies in [min_depth_m, max_depth_m], in row-major
  /// order of their pixels, evenly thinned to max_points. InvalidArgument naming the image
  /// and the expected size and type otherwise; Internal when OpenCV fails. `brightness`, when
  /// given, gets one value per point: the rectified left image's mean over the 3 x 3 level
  /// pixels around it (1-255; the map's intensity is compared with it).
  StatusOr<std::vector<Eigen::Vector3f>> points(const cv::Mat& left, const cv::Mat& right,
                                                std::vector<std::uint8_t>* brightness = nullptr) const;

  /// The rectified pair of one raw pair at the level (CV_8UC1 of rectification().width x
  /// height, 0 outside the raw images). Same errors as points().
  StatusOr<std::array<cv::Mat, 2>> rectify(const cv::Mat& left, const cv::Mat& right) const;

  /// Disparity of a rectified pair at the level, CV_16SC1 in 1/16 px (OpenCV's fixed point),
  /// negative where the matcher gave none. Errors: Internal when OpenCV fails.
  StatusOr<cv::Mat> disparity(const std::array<cv::Mat, 2>& rectified) const;

  const DenseStereoOptions& options() const { return options_; }
  const StereoRectification& rectification() const { return rect_; }
  /// The disparity range searched, level px (num_disparities or the one from min_depth_m).
  int num_disparities() const { return num_disparities_; }

 private:
  DenseStereo(const DenseStereoOptions& options, StereoRectification rect, int num_disparities);

  Status check_input(const cv::Mat& left, const cv::Mat& right) const;
  /// CV_8UC1, 255 where the window around a pixel of the rectified left image has
  /// min_texture; empty when the filter is off.
  StatusOr<cv::Mat> texture_mask(const cv::Mat& left) const;

  DenseStereoOptions options_;
  StereoRectification rect_;
  int num_disparities_ = 0;
  std::array<cv::Mat, 2> fixed_map_;   ///< rect_.map as CV_16SC2 (fast remap)
  std::array<cv::Mat, 2> fixed_frac_;  ///< its CV_16UC1 interpolation table
  cv::Ptr<cv::StereoMatcher> matcher_;
};

}  // namespace mrvs::edge
