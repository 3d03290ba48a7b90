#include "mrvs/edge/feature_tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <unordered_set>

#include <fmt/format.h>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "mrvs/core/time.h"
#include "mrvs/edge/pixel_selector.h"
#include "mrvs/edge/stereo_geometry.h"

namespace mrvs::edge {
namespace {

using Clock = std::chrono::steady_clock;

Vec2d to_vec(const cv::Point2f& p) { return Vec2d(p.x, p.y); }

/// Undistorted normalised coordinates, nullopt when the camera cannot undistort the pixel.
std::optional<Vec2d> normalised(const camera::CameraModel& cam, const cv::Point2f& uv) {
  StatusOr<Vec2d> xn = cam.undistort(to_vec(uv));
  if (!xn.ok()) return std::nullopt;
  return *xn;
}

/// KLT of `from` (pixels in `from_pyr`) into `to_pyr`, starting at `to`, over the features
/// `which`; writes `to` and `ok` of those features only. `min_eig` is OpenCV's minEigThreshold.
void klt_subset(const std::vector<cv::Mat>& from_pyr, const std::vector<cv::Mat>& to_pyr,
                const std::vector<cv::Point2f>& from, std::vector<cv::Point2f>* to,
                std::vector<unsigned char>* ok, const std::vector<std::size_t>& which,
                const TrackerOptions& o, int max_level, double min_eig = kOpenCvMinEigenvalue) {
  if (which.empty()) return;
  std::vector<cv::Point2f> a, b;
  for (std::size_t i : which) a.push_back(from[i]), b.push_back((*to)[i]);
  std::vector<unsigned char> status;
  std::vector<float> err;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, o.klt_iterations,
                                  o.klt_epsilon);
  cv::calcOpticalFlowPyrLK(from_pyr, to_pyr, a, b, status, err, cv::Size(o.klt_window, o.klt_window),
                           max_level, criteria, cv::OPTFLOW_USE_INITIAL_FLOW, min_eig);
  for (std::size_t j = 0; j < which.size(); ++j) (*to)[which[j]] = b[j], (*ok)[which[j]] = status[j];
}

std::vector<std::size_t> all_indices(std::size_t n) {
  std::vector<std::size_t> out(n);
  std::iota(out.begin(), out.end(), std::size_t{0});
  return out;
}

}  // namespace

FeatureTracker::FeatureTracker(const TrackerOptions& options, const config::StereoRigCalibration& rig)
    : options_(options), rig_(rig), T_c1_c0_(rig.T_c0_c1().inverse()) {}

StatusOr<FeatureTracker> FeatureTracker::create(const TrackerOptions& options,
                                                const config::StereoRigCalibration& rig) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options));
  for (int c = 0; c < 2; ++c) {
    if (!rig.cameras[static_cast<std::size_t>(c)].model) {
      return absl::InvalidArgumentError(
          fmt::format("feature tracker: camera {} has no model (calibration)", c));
    }
  }
  const auto& cam0 = *rig.cameras[0].model;
  if (cam0.width() < 64 || cam0.height() < 64) {
    return absl::InvalidArgumentError(fmt::format(
        "feature tracker: images of {}x{} px are too small (at least 64x64)", cam0.width(), cam0.height()));
  }
  return FeatureTracker(options, rig);
}

void FeatureTracker::reset() {
  tracks_.clear();
  prev_pyramid_.clear();
}

Status FeatureTracker::check_input(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right) const {
  const std::array<const cv::Mat*, 2> images = {&left, &right};
  for (std::size_t c = 0; c < 2; ++c) {
    const auto& cam = *rig_.cameras[c].model;
    const cv::Mat& img = *images[c];
    if (img.empty() || img.type() != CV_8UC1 || img.cols != cam.width() || img.rows != cam.height()) {
      return absl::InvalidArgumentError(fmt::format(
          "frame {} ns: cam{} image is {}x{} of type {}, the calibration expects {}x{} 8-bit grey", t_ns, c,
          img.cols, img.rows, img.type(), cam.width(), cam.height()));
    }
  }
  if (last_t_ns_ && t_ns <= *last_t_ns_) {
    return absl::InvalidArgumentError(
        fmt::format("frame {} ns is not after the previous frame ({} ns)", t_ns, *last_t_ns_));
  }
  return absl::OkStatus();
}

bool FeatureTracker::in_border(const cv::Point2f& uv) const {
  const auto& cam = *rig_.cameras[0].model;
  return cam.in_image(to_vec(uv), options_.border_px);
}

std::vector<cv::Point2f> FeatureTracker::predict(const std::optional<SE3d>& T_c_cprev) const {
  std::vector<cv::Point2f> out;
  out.reserve(tracks_.size());
  const auto& cam = *rig_.cameras[0].model;
  for (const Track& t : tracks_) {
    std::optional<Vec2d> uv;
    if (T_c_cprev) {
      const Vec3d bearing(t.xn.x(), t.xn.y(), 1.0);
      // Known depth: the point itself; else the direction only (a point at infinity).
      const Vec3d p_c = t.depth ? *T_c_cprev * (*t.depth * bearing) : T_c_cprev->rotation_matrix() * bearing;
      uv = cam.project(p_c);
    }
    out.push_back(uv && cam.in_image(*uv)
                      ? cv::Point2f(static_cast<float>(uv->x()), static_cast<float>(uv->y()))
                      : t.uv);
  }
  return out;
}

std::vector<FeatureTracker::Track> FeatureTracker::track_temporal(const std::vector<cv::Mat>& pyramid,
                                                                  const std::optional<SE3d>& T_c_cprev,
                                                                  TrackerStats* stats) const {
  std::vector<Track> out;
  if (tracks_.empty() || prev_pyramid_.empty()) return out;
  std::vector<cv::Point2f> prev;
  // With a motion prior, features of known depth are predicted within a few pixels: the
  // finest levels suffice, and coarse levels (where fine periodic texture vanishes) cannot
  // pull them onto the wrong period. The others use the whole pyramid.
  std::vector<std::size_t> guided, full;
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    prev.push_back(tracks_[i].uv);
    (T_c_cprev && tracks_[i].depth ? guided : full).push_back(i);
  }
  const int guided_levels = std::min(1, options_.klt_max_level);
  std::vector<cv::Point2f> cur = predict(T_c_cprev);
  std::vector<unsigned char> ok(prev.size(), 0), back_ok(prev.size(), 1);
  // Windows whose gradients span one direction only (edges: KLT slides along them) are lost.
  const double min_eig = options_.temporal_min_eigenvalue;
  klt_subset(prev_pyramid_, pyramid, prev, &cur, &ok, guided, options_, guided_levels, min_eig);
  klt_subset(prev_pyramid_, pyramid, prev, &cur, &ok, full, options_, options_.klt_max_level, min_eig);
  std::vector<cv::Point2f> back = prev;
  if (options_.temporal_round_trip_px > 0.0) {
    // Back from the new pixel: a KLT that slid along a repetitive texture or the epipolar
    // line (forward motion, which RANSAC on F cannot see) does not come back.
    // It starts at the previous pixel, where a right match returns to: two levels suffice.
    klt_subset(pyramid, prev_pyramid_, cur, &back, &back_ok, all_indices(prev.size()), options_,
               guided_levels);
  }
  for (std::size_t i = 0; i < tracks_.size(); ++i) {
    if (ok[i] == 0 || !in_border(cur[i])) {
      ++stats->lost_klt;
      continue;
    }
    if (options_.temporal_round_trip_px > 0.0 &&
        (back_ok[i] == 0 || cv::norm(back[i] - prev[i]) > options_.temporal_round_trip_px)) {
      ++stats->rejected_round_trip;
      continue;
    }
    Track t = tracks_[i];
    t.right.reset();
    t.depth.reset();
    if (tracks_[i].right) t.right = *tracks_[i].right + (cur[i] - prev[i]);  // stereo guess
    t.uv = cur[i];
    out.push_back(t);
  }
  return out;
}

std::vector<FeatureTracker::Track> FeatureTracker::reject_temporal_outliers(const std::vector<Track>& tracked,
                                                                            TrackerStats* stats) const {
  // `tracked` holds the new pixel and the previous frame's xn of each feature.
  std::vector<cv::Point2f> x_prev, x_cur;
  std::vector<Track> candidates;
  const auto& cam = *rig_.cameras[0].model;
  for (const Track& t : tracked) {
    const std::optional<Vec2d> xn = normalised(cam, t.uv);
    if (!xn) {
      ++stats->rejected_temporal;
      continue;
    }
    x_prev.emplace_back(static_cast<float>(t.xn.x()), static_cast<float>(t.xn.y()));
    x_cur.emplace_back(static_cast<float>(xn->x()), static_cast<float>(xn->y()));
    candidates.push_back(t);
    candidates.back().xn = *xn;
  }
  if (static_cast<int>(candidates.size()) < options_.min_ransac_points) {
    stats->rejected_temporal += static_cast<int>(candidates.size());
    return {};
  }
  const double focal = std::max(cam.fx(), cam.fy());
  std::vector<unsigned char> inlier;
  const cv::Mat F = cv::findFundamentalMat(x_prev, x_cur, cv::FM_RANSAC, options_.temporal_ransac_px / focal,
                                           options_.temporal_ransac_confidence, inlier);
  std::vector<Track> out;
  if (F.empty() || inlier.size() != candidates.size()) {
    stats->rejected_temporal += static_cast<int>(candidates.size());
    return out;
  }
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (inlier[i] == 0) {
      ++stats->rejected_temporal;
      continue;
    }
    out.push_back(candidates[i]);
    ++out.back().length;
  }
  return out;
}

void FeatureTracker::enforce_spacing(std::vector<Track>* tracks, TrackerStats* stats) const {
  // Longest tracks first: they keep their cell.
  std::stable_sort(tracks->begin(), tracks->end(),
                   [](const Track& a, const Track& b) { return a.length > b.length; });
  const int cell = options_.min_px_dist;
  const int cols = rig_.cameras[0].model->width() / cell + 1;
  std::unordered_set<int> taken;
  std::vector<Track> kept;
  kept.reserve(tracks->size());
  for (const Track& t : *tracks) {
    const int key = static_cast<int>(t.uv.y) / cell * cols + static_cast<int>(t.uv.x) / cell;
    if (!taken.insert(key).second) {
      ++stats->dropped_crowded;
      continue;
    }
    kept.push_back(t);
  }
  tracks->swap(kept);
}

cv::Mat FeatureTracker::detection_mask(const std::vector<Track>& tracks) const {
  const auto& cam = *rig_.cameras[0].model;
  const int w = cam.width(), h = cam.height(), b = options_.border_px, d = options_.min_px_dist;
  cv::Mat mask(h, w, CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(b, b, std::max(0, w - 2 * b), std::max(0, h - 2 * b))).setTo(0);
  const bool row_band = options_.mask_mode == "row_band";
  for (const Track& t : tracks) {
    const int x = static_cast<int>(t.uv.x), y = static_cast<int>(t.uv.y);
    if (row_band) {
      // The reference code's linear index range (x - d, y - d) .. (x + d, y + d): whole rows.
      const long first = std::max(0L, static_cast<long>(y - d) * w + (x - d));
      const long last = std::min(static_cast<long>(w) * h - 1, static_cast<long>(y + d) * w + (x + d));
      for (long i = first; i <= last; ++i) mask.data[i] = 255;
    } else {
      const cv::Rect r = cv::Rect(x - d, y - d, 2 * d + 1, 2 * d + 1) & cv::Rect(0, 0, w, h);
      mask(r).setTo(255);
    }
  }
  return mask;
}

void FeatureTracker::detect(const cv::Mat& equalized, std::vector<Track>* tracks, TrackerStats* stats,
                            double* image_ms) {
  const int missing = options_.max_features - static_cast<int>(tracks->size());
  if (missing <= std::min(options_.detect_min_missing, options_.max_features / 2)) return;
  stats->detected = true;
  const Clock::time_point t0 = Clock::now();
  const Status built = build_gradient_pyramid(equalized, 3, &gradients_);
  *image_ms += ms_since(t0);
  if (!built.ok()) return;  // images are at least 64 px a side (create): cannot happen
  // Cell size from the density the selector found last time (about one point per (pot + 1)^2
  // free pixels): one pass instead of two.
  const cv::Mat mask = detection_mask(*tracks);
  const double free_px = static_cast<double>(mask.total() - static_cast<std::size_t>(cv::countNonZero(mask)));
  const int hint =
      density_ > 0.0 ? static_cast<int>(std::lround(std::sqrt(density_ * free_px / missing) - 1.0)) : 0;
  const SelectorResult selected =
      select_pixels(gradients_, mask, missing, options_.selector, std::max(hint, 1));
  if (selected.found > 0 && free_px > 0.0) {
    density_ = static_cast<double>(selected.found) * (selected.pot + 1) * (selected.pot + 1) / free_px;
  }
  const auto& cam = *rig_.cameras[0].model;
  std::vector<Track> fresh;
  for (const SelectedPixel& p : selected.pixels) {
    const std::optional<Vec2d> xn = normalised(cam, p.uv);
    if (!xn || !in_border(p.uv)) continue;
    Track t;
    t.uv = p.uv;
    t.xn = *xn;
    fresh.push_back(t);
  }
  // New features only take cells the kept ones leave free (kept ones sort first: longer).
  const std::size_t before = tracks->size();
  tracks->insert(tracks->end(), fresh.begin(), fresh.end());
  TrackerStats ignored;
  enforce_spacing(tracks, &ignored);
  for (std::size_t i = 0; i < tracks->size(); ++i) {
    Track& t = (*tracks)[i];
    if (t.id == 0) t.id = next_id_++;
  }
  stats->created = static_cast<int>(tracks->size() - std::min(before, tracks->size()));
}

namespace {

/// Mean of the (2 kPatchHalf + 1)^2 pixels of the input image (not equalised: the same scene
/// brightness gives the same value in every frame) around uv, clipped at the border, 1-255: the
/// feature's appearance for the localisation submap (FeatureObservation::brightness).
float patch_brightness(const cv::Mat& image, const Vec2d& uv) {
  constexpr int kPatchHalf = 3;
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  const cv::Rect patch = cv::Rect(u - kPatchHalf, v - kPatchHalf, 2 * kPatchHalf + 1, 2 * kPatchHalf + 1) &
                         cv::Rect(0, 0, image.cols, image.rows);
  if (patch.area() == 0) return 0.0f;
  return std::max(1.0f, static_cast<float>(cv::mean(image(patch))[0]));
}

}  // namespace

std::vector<FeatureObservation> FeatureTracker::match_stereo(const std::vector<cv::Mat>& left_pyr,
                                                             const std::vector<cv::Mat>& right_pyr,
                                                             std::vector<Track>* tracks,
                                                             TrackerStats* stats) const {
  std::vector<FeatureObservation> out(tracks->size());
  if (tracks->empty()) return out;
  // Features matched in the previous frame start from that match moved with the left flow,
  // which is within a pixel or two: the two finest levels suffice. The others (new, or lost
  // last frame) start at the same pixel and use the whole pyramid.
  std::vector<cv::Point2f> left, right;
  std::vector<std::size_t> guided, fresh;
  for (std::size_t i = 0; i < tracks->size(); ++i) {
    const Track& t = (*tracks)[i];
    left.push_back(t.uv);
    right.push_back(t.right.value_or(t.uv));
    (t.right ? guided : fresh).push_back(i);
  }
  const int guided_levels = std::min(1, options_.klt_max_level);
  std::vector<unsigned char> status_lr(left.size(), 0), status_rl(left.size(), 0);
  klt_subset(left_pyr, right_pyr, left, &right, &status_lr, guided, options_, guided_levels);
  klt_subset(left_pyr, right_pyr, left, &right, &status_lr, fresh, options_, options_.klt_max_level);
  std::vector<cv::Point2f> back = left;  // the round trip starts at the left pixel
  klt_subset(right_pyr, left_pyr, right, &back, &status_rl, all_indices(left.size()), options_,
             guided_levels);
  const auto& cam1 = *rig_.cameras[1].model;
  const double focal1 = 0.5 * (cam1.fx() + cam1.fy());
  for (std::size_t i = 0; i < tracks->size(); ++i) {
    Track& t = (*tracks)[i];
    FeatureObservation& o = out[i];
    o.id = t.id;
    o.uv_left = to_vec(t.uv);
    o.xn_left = t.xn;
    o.track_length = t.length;
    t.right.reset();
    std::optional<Vec2d> xn1;
    if (status_lr[i] == 0 || !cam1.in_image(to_vec(right[i]), 1.0) || !(xn1 = normalised(cam1, right[i]))) {
      ++stats->stereo_failed_klt;
      continue;
    }
    if (status_rl[i] == 0 || cv::norm(back[i] - left[i]) > options_.stereo_lr_px) {
      ++stats->stereo_rejected_lr;
      continue;
    }
    if (epipolar_distance(T_c1_c0_, t.xn, *xn1) * focal1 > options_.stereo_epipolar_px) {
      ++stats->stereo_rejected_epipolar;
      continue;
    }
    const std::optional<Vec2d> depths = triangulate_depths(T_c1_c0_, t.xn, *xn1);
    if (!depths || depths->x() < options_.stereo_min_depth_m || depths->y() < options_.stereo_min_depth_m) {
      ++stats->stereo_rejected_depth;
      continue;
    }
    o.stereo = true;
    o.uv_right = to_vec(right[i]);
    o.xn_right = *xn1;
    t.right = right[i];
    t.depth = depths->x();
    ++stats->stereo;
  }
  return out;
}

struct FeatureTracker::Images {
  cv::Mat left, right;  ///< equalised (or the inputs)
  std::vector<cv::Mat> left_pyr, right_pyr;
};

StatusOr<TrackedFrame> FeatureTracker::process(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right,
                                               const std::optional<SE3d>& T_c_cprev) {
  MRVS_RETURN_IF_ERROR(check_input(t_ns, left, right));
  TrackedFrame frame;
  frame.t_ns = t_ns;
  const Clock::time_point t0 = Clock::now();
  Images img;
  if (options_.histogram_equalization) {
    cv::equalizeHist(left, img.left);
    cv::equalizeHist(right, img.right);
  } else {
    img.left = left;
    img.right = right;
  }
  const cv::Size win(options_.klt_window, options_.klt_window);
  cv::buildOpticalFlowPyramid(img.left, img.left_pyr, win, options_.klt_max_level);
  cv::buildOpticalFlowPyramid(img.right, img.right_pyr, win, options_.klt_max_level);
  frame.timing.image_ms = ms_since(t0);

  const Clock::time_point t1 = Clock::now();
  TrackerStats& stats = frame.stats;
  std::vector<Track> tracks =
      reject_temporal_outliers(track_temporal(img.left_pyr, T_c_cprev, &stats), &stats);
  enforce_spacing(&tracks, &stats);
  stats.tracked = static_cast<int>(tracks.size());
  frame.timing.temporal_ms = ms_since(t1);
  const Clock::time_point t2 = Clock::now();
  double detect_image_ms = 0.0;
  detect(img.left, &tracks, &stats, &detect_image_ms);
  frame.timing.detection_ms = ms_since(t2) - detect_image_ms;
  const Clock::time_point t3 = Clock::now();
  frame.features = match_stereo(img.left_pyr, img.right_pyr, &tracks, &stats);
  for (FeatureObservation& o : frame.features) o.brightness = patch_brightness(left, o.uv_left);
  frame.timing.stereo_ms = ms_since(t3);
  frame.timing.image_ms += detect_image_ms;
  frame.timing.tracking_ms = ms_since(t1) - detect_image_ms;

  tracks_ = std::move(tracks);
  prev_pyramid_ = std::move(img.left_pyr);
  last_t_ns_ = t_ns;
  return frame;
}

}  // namespace mrvs::edge
