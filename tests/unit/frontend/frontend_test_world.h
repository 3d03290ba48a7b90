#pragma once
// Rendered stereo sequences for the front-end tests, built in memory from the simulator
// (no files): the world (poses, calibration, scene), a renderer and the images.
#include <array>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "mrvs/core/stats.h"
#include "mrvs/edge/feature_tracker.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/stereo_renderer.h"

namespace mrvs::edge::test {

struct TestSequence {
  sim::World world;
  std::unique_ptr<sim::StereoRenderer> renderer;
  std::vector<std::array<cv::Mat, 2>> images;  ///< per frame: cam0, cam1
  std::vector<TimestampNs> t_ns;

  /// T_w_c of camera `cam` at frame k.
  SE3d T_w_c(int cam, std::size_t k) const { return renderer->camera_pose(cam, world.frame_pose(k)); }
};

/// Indoor (V1_01_easy from 20 s) or outdoor (the synthetic car route) sequence of `frames`
/// frames with the given preset ("easy" / "realistic"). Built once per argument set.
const TestSequence* sequence(sim::SceneProfile profile, const std::string& preset, int frames);

/// The tracker options of a profile: config/euroc.yaml or config/kaist.yaml.
TrackerOptions tracker_options(sim::SceneProfile profile);

/// How run_tracker predicts the camera motion between frames.
enum class Prior {
  kNone,   ///< no prediction (KLT starts at the previous pixel)
  kNoisy,  ///< the true motion with the error of an IMU propagation over one frame: 0.2 deg
           ///< rotation and 5 % + 5 mm translation (fixed seed)
};

/// Runs a tracker over `images` (with the sequence's times); fails the test on an error.
std::vector<TrackedFrame> run_tracker(const TestSequence& seq, const TrackerOptions& options,
                                      const std::vector<std::array<cv::Mat, 2>>& images,
                                      Prior prior = Prior::kNone);

/// |LK - true flow| of every feature tracked from frame k - 1 into frame k (cam0); features
/// whose true correspondence does not exist (occluded, left the image) count as `invalid`.
struct FlowErrors {
  std::vector<double> errors;  ///< px
  std::vector<double> motion;  ///< |true flow| of the same features, px
  /// True deformation of each feature's patch between the two frames: the largest |log
  /// singular value| of the Jacobian of the true flow map at the feature (0.1: a 10 %
  /// stretch). Translation-only KLT is biased on patches that deform; NaN where the
  /// Jacobian is undefined (the 2 px neighbourhood crosses an occlusion).
  std::vector<double> deformation;
  int invalid = 0;
};
FlowErrors temporal_errors(const TestSequence& seq, const std::vector<TrackedFrame>& frames);

using mrvs::quantile;

}  // namespace mrvs::edge::test
