#include "mrvs/edge/vio_system.h"

namespace mrvs::edge {

StatusOr<VioSystem> VioSystem::create(const EdgeOptions& options, const config::StereoRigCalibration& rig,
                                      io::Trajectory groundtruth) {
  MRVS_ASSIGN_OR_RETURN(FeatureTracker tracker, FeatureTracker::create(options.tracker, rig));
  MRVS_ASSIGN_OR_RETURN(VioEstimator estimator,
                        VioEstimator::create(options.estimator, rig, std::move(groundtruth)));
  return VioSystem(std::move(tracker), std::move(estimator));
}

StatusOr<StereoOutput> VioSystem::feed_stereo(TimestampNs t_ns, const cv::Mat& left, const cv::Mat& right) {
  StereoOutput out;
  MRVS_ASSIGN_OR_RETURN(out.tracked, tracker_.process(t_ns, left, right, estimator_.predict_T_c_cprev(t_ns)));
  FeatureFrame frame;
  frame.t_ns = t_ns;
  frame.features = out.tracked.features;
  MRVS_ASSIGN_OR_RETURN(out.estimate, estimator_.feed_frame(frame));
  return out;
}

}  // namespace mrvs::edge
