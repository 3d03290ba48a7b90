#pragma once
// The edge front-end (paper IV-C, algorithm.md 5.1): per stereo frame, left-image features
// tracked by pyramidal KLT from the previous frame and checked by RANSAC on the epipolar
// geometry; new features selected by the DSO-style selector in the regions the kept ones do
// not cover; every feature matched into the right image by KLT and kept as stereo only when
// it passes the calibrated epipolar check, the left-right round trip and a positive depth.
//
// Not thread-safe: one thread feeds a tracker, frame after frame.
#include <cstdint>
#include <optional>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "mrvs/config/calibration.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/edge/feature_observation.h"
#include "mrvs/edge/image_pyramid.h"
#include "mrvs/edge/tracker_options.h"
#include "mrvs/geometry/types.h"

namespace mrvs::edge {

/// The paper's timing columns, ms of wall time.
struct FrontendTiming {
  double image_ms = 0.0;     ///< (a) image processing: equalisation, KLT pyramids, gradients
  double tracking_ms = 0.0;  ///< (b) feature extraction and tracking, outlier rejection
  // (b) split: temporal KLT + RANSAC, selection of new features, stereo KLT + checks.
  double temporal_ms = 0.0;
  double detection_ms = 0.0;
  double stereo_ms = 0.0;
};

/// What happened to the features in one frame.
struct TrackerStats {
  int tracked = 0;              ///< features carried over from the previous frame
  int lost_klt = 0;             ///< KLT failed or left the image (border)
  int rejected_temporal = 0;    ///< temporal RANSAC outliers (all when too few to fit)
  int rejected_round_trip = 0;  ///< previous -> current -> previous KLT did not come back
  int dropped_crowded = 0;      ///< tracked into a cell that already had a feature
  int created = 0;              ///< new features
  int stereo = 0;               ///< features with a right observation
  int stereo_failed_klt = 0;    ///< no right match (KLT failed or outside the image)
  int stereo_rejected_epipolar = 0;
  int stereo_rejected_lr = 0;  ///< left-right round trip too far
  int stereo_rejected_depth = 0;
  bool detected = false;  ///< the selector ran this frame
};

struct TrackedFrame {
  TimestampNs t_ns = 0;
  std::vector<FeatureObservation> features;
  TrackerStats stats;
  FrontendTiming timing;
};

class FeatureTracker {
 public:
  /// Validates the options and the calibration (both cameras with a model).
  static StatusOr<FeatureTracker> create(const TrackerOptions& options,
                                         const config::StereoRigCalibration& rig);

  /// Processes the stereo pair taken at t_ns (cam0, cam1; CV_8UC1 of the calibrated sizes).
  /// InvalidArgument for a wrong type or size, or a time not after the previous frame; the
  /// tracker state is unchanged then.
  ///
  /// `T_c_cprev` (optional) is the predicted motion of cam0 since the previous frame (maps
  /// points of the previous cam0 frame into the current one), e.g. from IMU propagation. KLT
  /// then starts each feature at its predicted pixel (stereo depth when known, else at
  /// infinity), which keeps fast forward motion and repetitive texture from breaking tracks.
  StatusOr<TrackedFrame> process(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right,
                                 const std::optional<SE3d>& T_c_cprev = std::nullopt);

  /// Forgets all tracks (the next frame starts from detection); ids keep increasing.
  void reset();

  const TrackerOptions& options() const { return options_; }

 private:
  struct Track {
    FeatureId id = 0;
    cv::Point2f uv;  ///< left pixel
    Vec2d xn = Vec2d::Zero();
    int length = 1;
    std::optional<cv::Point2f> right;  ///< right pixel when it was a stereo match
    std::optional<double> depth;       ///< z in cam0 from that match, m
  };
  struct Images;  // per-frame working images

  FeatureTracker(const TrackerOptions& options, const config::StereoRigCalibration& rig);
  Status check_input(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right) const;
  std::vector<Track> track_temporal(const std::vector<cv::Mat>& pyramid, const std::optional<SE3d>& T_c_cprev,
                                    TrackerStats* stats) const;
  /// Where each previous feature should appear under `T_c_cprev` (its pixel when no prior).
  std::vector<cv::Point2f> predict(const std::optional<SE3d>& T_c_cprev) const;
  std::vector<Track> reject_temporal_outliers(const std::vector<Track>& tracked, TrackerStats* stats) const;
  void enforce_spacing(std::vector<Track>* tracks, TrackerStats* stats) const;
  cv::Mat detection_mask(const std::vector<Track>& tracks) const;
  void detect(const cv::Mat& equalized, std::vector<Track>* tracks, TrackerStats* stats, double* image_ms);
  std::vector<FeatureObservation> match_stereo(const std::vector<cv::Mat>& left_pyr,
                                               const std::vector<cv::Mat>& right_pyr,
                                               std::vector<Track>* tracks, TrackerStats* stats) const;
  bool in_border(const cv::Point2f& uv) const;

  TrackerOptions options_;
  config::StereoRigCalibration rig_;
  SE3d T_c1_c0_;
  std::vector<Track> tracks_;
  std::vector<cv::Mat> prev_pyramid_;
  std::optional<TimestampNs> last_t_ns_;
  FeatureId next_id_ = 1;
  GradientPyramid gradients_;  ///< reused buffers
  /// Selector points per free pixel times (pot + 1)^2 in the last detection (0: none yet).
  double density_ = 0.0;
};

}  // namespace mrvs::edge
