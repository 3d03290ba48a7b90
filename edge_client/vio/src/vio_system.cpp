#include "mrvs/edge/vio_system.h"

#include <chrono>

#include <spdlog/spdlog.h>

namespace mrvs::edge {

StatusOr<VioSystem> VioSystem::create(const EdgeOptions& options, const config::StereoRigCalibration& rig,
                                      io::Trajectory groundtruth) {
  MRVS_ASSIGN_OR_RETURN(FeatureTracker tracker, FeatureTracker::create(options.tracker, rig));
  MRVS_ASSIGN_OR_RETURN(VioEstimator estimator,
                        VioEstimator::create(options.estimator, rig, std::move(groundtruth)));
  std::optional<DenseStereo> dense;
  if (options.estimator.localisation.submap_source != "tracks") {
    MRVS_ASSIGN_OR_RETURN(dense, DenseStereo::create(options.dense_stereo, rig));
  }
  return VioSystem(std::move(tracker), std::move(estimator), std::move(dense));
}

StatusOr<StereoOutput> VioSystem::feed_stereo(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right) {
  StereoOutput out;
  MRVS_ASSIGN_OR_RETURN(out.tracked, tracker_.process(t_ns, left, right, estimator_.predict_T_c_cprev(t_ns)));
  FeatureFrame frame;
  frame.t_ns = t_ns;
  frame.features = out.tracked.features;
  MRVS_ASSIGN_OR_RETURN(out.estimate, estimator_.feed_frame(frame));
  if (dense_ && estimator_.wants_dense_submap(t_ns)) {
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::uint8_t> brightness;
    auto points = dense_->points(left, right, &brightness);
    if (points.ok()) {
      estimator_.add_dense_submap(t_ns, *points, brightness);
    } else {
      spdlog::warn("dense stereo at {} ns: {}", t_ns, std::string(points.status().message()));
    }
    out.dense_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    out.tracked.timing.image_ms += out.dense_ms;
  }
  return out;
}

}  // namespace mrvs::edge
