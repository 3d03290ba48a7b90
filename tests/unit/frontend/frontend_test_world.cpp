#include "frontend_test_world.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <unordered_map>

#include <gtest/gtest.h>
#include <Eigen/SVD>

#include "mrvs/config/options.h"
#include "mrvs/sim/photometry.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::edge::test {
namespace {

std::unique_ptr<TestSequence> build(sim::SceneProfile profile, const std::string& preset, int frames) {
  sim::GeneratorRequest r;
  r.profile = profile;
  r.preset = preset;
  r.options = sim::default_options(profile);
  EXPECT_TRUE(sim::apply_preset(preset, profile, r.options).ok());
  const double rate = profile == sim::SceneProfile::kIndoor ? 20.0 : 10.0;
  if (profile == sim::SceneProfile::kIndoor) {
    r.trajectory = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
    r.options.trajectory.window_start_s = 20.0;  // V1_01 is moving here
  } else {
    r.options.trajectory.window_start_s = 8.0;  // the car has left its 3 s rest and is cruising
  }
  r.options.trajectory.window_duration_s = (frames + 1) / rate;
  r.options.map.spacing_near_m = r.options.map.spacing_far_m = 0.2;  // the map is not used here
  StatusOr<sim::World> world = sim::build_world(r);
  EXPECT_TRUE(world.ok()) << world.status();
  if (!world.ok()) return nullptr;
  auto seq = std::make_unique<TestSequence>();
  seq->world = std::move(*world);
  auto renderer = sim::StereoRenderer::create(*seq->world.scene, seq->world.calibration, r.options.render,
                                              static_cast<std::uint64_t>(r.options.seed));
  EXPECT_TRUE(renderer.ok()) << renderer.status();
  if (!renderer.ok()) return nullptr;
  seq->renderer = std::make_unique<sim::StereoRenderer>(std::move(*renderer));
  const auto n =
      std::min<std::size_t>(static_cast<std::size_t>(frames), seq->world.grid.camera_true_ns.size());
  const std::vector<double> gains = sim::exposure_gains(
      static_cast<std::uint64_t>(r.options.seed), static_cast<std::int64_t>(n), seq->renderer->options());
  for (std::size_t k = 0; k < n; ++k) {
    auto images = seq->renderer->render_stereo(seq->world.frame_pose(k),
                                               sim::FrameInfo{static_cast<std::int64_t>(k), gains[k]});
    EXPECT_TRUE(images.ok()) << images.status();
    if (!images.ok()) return nullptr;
    seq->images.push_back(*images);
    seq->t_ns.push_back(seq->world.grid.camera_stamp_ns[k]);
  }
  return seq;
}

}  // namespace

const TestSequence* sequence(sim::SceneProfile profile, const std::string& preset, int frames) {
  // One cache per test binary (tests run one at a time within it).
  static std::map<std::tuple<int, std::string, int>, std::unique_ptr<TestSequence>> cache;
  const auto key = std::make_tuple(static_cast<int>(profile), preset, frames);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, build(profile, preset, frames)).first;
  return it->second.get();
}

TrackerOptions tracker_options(sim::SceneProfile profile) {
  const std::string file = profile == sim::SceneProfile::kIndoor ? "euroc.yaml" : "kaist.yaml";
  auto options =
      config::load_options_file<TrackerOptions>(std::filesystem::path(MRVS_CONFIG_DIR) / file, "tracker");
  EXPECT_TRUE(options.ok()) << options.status();
  return options.ok() ? *options : TrackerOptions{};
}

namespace {

/// The true T_c_cprev of cam0 between frames k - 1 and k, perturbed (Prior::kNoisy).
SE3d noisy_motion(const TestSequence& seq, std::size_t k, std::mt19937_64* rng) {
  const SE3d truth = seq.T_w_c(0, k).inverse() * seq.T_w_c(0, k - 1);
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec3d rot_error = Vec3d(n(*rng), n(*rng), n(*rng)).normalized() * (0.2 * M_PI / 180.0);
  const Vec3d dir = Vec3d(n(*rng), n(*rng), n(*rng)).normalized();
  const Vec3d trans_error = dir * (0.05 * truth.translation().norm() + 0.005);
  return SE3d(
      truth.quaternion() * Eigen::Quaterniond(Eigen::AngleAxisd(rot_error.norm(), rot_error.normalized())),
      truth.translation() + trans_error);
}

/// FlowErrors::deformation of the patch at `uv` of frame k - 1 (central differences, 2 px).
double true_deformation(const TestSequence& seq, std::size_t k, const Vec2d& uv) {
  Mat2d J;
  for (int d = 0; d < 2; ++d) {
    const Vec2d du = 2.0 * Vec2d::Unit(d);
    const auto plus = seq.renderer->true_flow(0, seq.T_w_c(0, k - 1), seq.T_w_c(0, k), uv + du);
    const auto minus = seq.renderer->true_flow(0, seq.T_w_c(0, k - 1), seq.T_w_c(0, k), uv - du);
    if (!plus || !minus) return std::numeric_limits<double>::quiet_NaN();
    J.col(d) = Vec2d::Unit(d) + (*plus - *minus) / 4.0;
  }
  const Vec2d sv = Eigen::JacobiSVD<Mat2d>(J).singularValues();
  if (!(sv[1] > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return std::max(std::abs(std::log(sv[0])), std::abs(std::log(sv[1])));
}

}  // namespace

std::vector<TrackedFrame> run_tracker(const TestSequence& seq, const TrackerOptions& options,
                                      const std::vector<std::array<cv::Mat, 2>>& images, Prior prior) {
  std::mt19937_64 rng(5);
  std::vector<TrackedFrame> out;
  auto tracker = FeatureTracker::create(options, seq.world.calibration);
  EXPECT_TRUE(tracker.ok()) << tracker.status();
  if (!tracker.ok()) return out;
  for (std::size_t k = 0; k < images.size(); ++k) {
    std::optional<SE3d> T_c_cprev;
    if (prior == Prior::kNoisy && k > 0) T_c_cprev = noisy_motion(seq, k, &rng);
    auto frame = tracker->process(seq.t_ns[k], images[k][0], images[k][1], T_c_cprev);
    EXPECT_TRUE(frame.ok()) << frame.status();
    if (!frame.ok()) return out;
    out.push_back(std::move(*frame));
  }
  return out;
}

FlowErrors temporal_errors(const TestSequence& seq, const std::vector<TrackedFrame>& frames) {
  FlowErrors out;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    std::unordered_map<FeatureId, Vec2d> previous;
    for (const FeatureObservation& o : frames[k - 1].features) previous[o.id] = o.uv_left;
    for (const FeatureObservation& o : frames[k].features) {
      const auto it = previous.find(o.id);
      if (it == previous.end()) continue;
      const auto flow = seq.renderer->true_flow(0, seq.T_w_c(0, k - 1), seq.T_w_c(0, k), it->second);
      if (!flow) {
        ++out.invalid;
        continue;
      }
      out.errors.push_back((o.uv_left - (it->second + *flow)).norm());
      out.motion.push_back(flow->norm());
      out.deformation.push_back(true_deformation(seq, k, it->second));
    }
  }
  return out;
}

}  // namespace mrvs::edge::test
