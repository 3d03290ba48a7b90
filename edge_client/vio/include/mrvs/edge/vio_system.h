#pragma once
// The edge client's VIO pipeline behind the facade of the design card: feed_imu and
// feed_stereo. The front-end (FeatureTracker) gets the IMU-predicted camera motion as its
// KLT prior; the estimator (VioEstimator) gets the tracked features. Timing per frame in the
// paper's columns: (a) image processing, (b) extraction and tracking, (c) state update.
#include <filesystem>
#include <optional>

#include <opencv2/core/mat.hpp>

#include "mrvs/config/options.h"
#include "mrvs/edge/dense_stereo.h"
#include "mrvs/edge/feature_tracker.h"
#include "mrvs/edge/vio_estimator.h"

namespace mrvs::edge {

/// Where the calibration comes from (config/<rig>/ Kalibr files, or the dataset's own
/// EuRoC sensor.yaml files when empty).
struct CalibrationOptions : config::OptionsEquality<CalibrationOptions> {
  std::filesystem::path camchain;  ///< Kalibr camchain-imucam.yaml; empty: the dataset's sensor.yaml
  std::filesystem::path imu;       ///< Kalibr imu.yaml; empty: the dataset's imu0/sensor.yaml

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("camchain", camchain, any(), "Kalibr camchain file (empty: the dataset's sensor.yaml)");
    v("imu", imu, any(), "Kalibr IMU file (empty: the dataset's imu0/sensor.yaml)");
  }
};

/// The whole tuning file of the edge client (config/euroc.yaml, config/kaist.yaml).
struct EdgeOptions : config::OptionsEquality<EdgeOptions> {
  CalibrationOptions calibration;
  TrackerOptions tracker;
  DenseStereoOptions dense_stereo;
  EstimatorOptions estimator;

  template <class V>
  void visit(V& v) {
    v.section("calibration", calibration, "calibration files");
    v.section("tracker", tracker, "front-end");
    v.section("dense_stereo", dense_stereo,
              "dense stereo (localisation submaps, estimator.localisation.submap_source)");
    v.section("estimator", estimator, "filter");
  }
};

struct StereoOutput {
  TrackedFrame tracked;   ///< features, tracker statistics, timing (a) and (b)
  FrameOutput estimate;   ///< pose, filter statistics, timing (c)
  double dense_ms = 0.0;  ///< dense stereo for the localisation submap (part of timing (a))
};

class VioSystem {
 public:
  static StatusOr<VioSystem> create(const EdgeOptions& options, const config::StereoRigCalibration& rig,
                                    io::Trajectory groundtruth = {});

  Status feed_imu(const io::ImuSample& sample) { return estimator_.feed_imu(sample); }
  /// A GNSS fix (the localisation's prior region only; VioEstimator::feed_gnss).
  void feed_gnss(const io::GnssFix& fix, const SE3d& T_b_antenna) { estimator_.feed_gnss(fix, T_b_antenna); }
  /// One stereo pair (cam0, cam1; CV_8UC1 of the calibrated sizes) taken at t_ns (camera
  /// clock). The IMU must cover imu_time(t_ns) (VioEstimator::feed_frame).
  StatusOr<StereoOutput> feed_stereo(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right);
  /// Camera stamp -> IMU clock at the current time-offset estimate (VioEstimator::imu_time).
  TimestampNs imu_time(TimestampNs t_cam_ns) const { return estimator_.imu_time(t_cam_ns); }

  /// The cloud map (not owned; nullptr: plain VIO).
  void set_map_service(MapService* service) { estimator_.set_map_service(service); }

  const VioEstimator& estimator() const { return estimator_; }

 private:
  VioSystem(FeatureTracker tracker, VioEstimator estimator, std::optional<DenseStereo> dense)
      : tracker_(std::move(tracker)), estimator_(std::move(estimator)), dense_(std::move(dense)) {}
  FeatureTracker tracker_;
  VioEstimator estimator_;
  std::optional<DenseStereo> dense_;  ///< with submap_source dense_stereo
};

}  // namespace mrvs::edge
