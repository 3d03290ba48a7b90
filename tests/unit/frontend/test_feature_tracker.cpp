// The front-end on rendered sequences against the simulator's truth: temporal tracks vs the
// ray-cast true flow, stereo depths vs ground-truth depth, injected occlusions rejected,
// track lengths, and bad input.
#include <algorithm>
#include <numeric>
#include <unordered_map>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "frontend_test_world.h"
#include "mrvs/edge/stereo_geometry.h"

namespace mrvs::edge {
namespace {

using sim::SceneProfile;
using test::quantile;

constexpr int kIndoorFrames = 40;   // 2 s at 20 Hz
constexpr int kOutdoorFrames = 20;  // 2 s at 10 Hz

std::string num(double x) { return std::to_string(x); }

/// The errors of the tracks whose patch deforms by at most `max_deformation`.
std::vector<double> errors_up_to_deformation(const test::FlowErrors& e, double max_deformation) {
  std::vector<double> out;
  for (std::size_t i = 0; i < e.errors.size(); ++i) {
    if (e.deformation[i] <= max_deformation) out.push_back(e.errors[i]);  // NaN compares false
  }
  return out;
}

/// The length of every track that ended in `tracked`, checking on the way that IDs are unique
/// in a frame and that a feature's length grows by one a frame.
std::vector<double> ended_track_lengths(const std::vector<TrackedFrame>& tracked) {
  std::unordered_map<FeatureId, int> last_length;
  std::vector<double> final_lengths;
  for (const TrackedFrame& f : tracked) {
    std::unordered_map<FeatureId, int> now;
    for (const FeatureObservation& o : f.features) {
      EXPECT_TRUE(now.emplace(o.id, o.track_length).second) << "duplicate id " << o.id;
      const auto it = last_length.find(o.id);
      EXPECT_EQ(o.track_length, it == last_length.end() ? 1 : it->second + 1) << "id " << o.id;
    }
    for (const auto& [id, len] : last_length) {
      if (now.count(id) == 0) final_lengths.push_back(len);
    }
    last_length = std::move(now);
  }
  return final_lengths;
}

test::FlowErrors tracked_flow_errors(SceneProfile profile, int frames, test::Prior prior) {
  const test::TestSequence* seq = test::sequence(profile, "easy", frames);
  EXPECT_NE(seq, nullptr);
  if (seq == nullptr) return {};
  const auto tracked = test::run_tracker(*seq, test::tracker_options(profile), seq->images, prior);
  EXPECT_EQ(tracked.size(), seq->images.size());
  for (const TrackedFrame& f : tracked) EXPECT_LE(static_cast<int>(f.features.size()), 200);
  const test::FlowErrors e = test::temporal_errors(*seq, tracked);
  const std::vector<double> lengths = ended_track_lengths(tracked);
  testing::Test::RecordProperty("ended_track_median_len", num(quantile(lengths, 0.5)));
  testing::Test::RecordProperty(
      "ended_track_mean_len",
      num(std::accumulate(lengths.begin(), lengths.end(), 0.0) / std::max<std::size_t>(lengths.size(), 1)));
  EXPECT_GE(e.errors.size(), 100u * static_cast<std::size_t>(frames - 1));  // about 200 features a frame
  EXPECT_GT(quantile(e.motion, 0.5), 2.0);  // the camera does move: a static sequence proves nothing
  testing::Test::RecordProperty("flow_median_px", num(quantile(e.errors, 0.5)));
  testing::Test::RecordProperty("flow_p90_px", num(quantile(e.errors, 0.9)));
  testing::Test::RecordProperty("tracks", static_cast<int>(e.errors.size()));
  testing::Test::RecordProperty("vanished", e.invalid);
  testing::Test::RecordProperty("true_flow_median_px", num(quantile(e.motion, 0.5)));
  return e;
}

void expect_indoor_targets(test::Prior prior) {
  const test::FlowErrors e = tracked_flow_errors(SceneProfile::kIndoor, kIndoorFrames, prior);
  EXPECT_LT(quantile(e.errors, 0.5), 0.2);
  EXPECT_LT(quantile(e.errors, 0.9), 0.5);
  EXPECT_LT(e.invalid, static_cast<int>(e.errors.size() / 100));  // tracks of vanished points are dropped
}

TEST(FeatureTracker, IndoorTemporalTracksAgreeWithTheTrueFlow) { expect_indoor_targets(test::Prior::kNone); }

TEST(FeatureTracker, IndoorTemporalTracksWithAMotionPriorAgreeWithTheTrueFlow) {
  expect_indoor_targets(test::Prior::kNoisy);
}

// 10 Hz at 7.5 m/s: up to 90 px of flow on the road, whose 2 cm asphalt noise is nearly
// periodic in the image. Without a prediction KLT locks onto the wrong period on part of the
// road (the round trip and RANSAC cannot see errors along the epipolar line); with the
// prediction an IMU propagation gives (noisy), tracks are right. Patches on the road near the
// car and on facades along the street also stretch by 10-40 % from one frame to the next,
// which biases a translation-only KLT by a pixel or more: with the shipped checks the targets
// hold for the patches that deform by at most 10 % (about three quarters of the tracks), and
// the rest stay within a few pixels (the filter's chi-square gates see them). The next test
// shows the checks that reach the targets over all tracks.
TEST(FeatureTracker, OutdoorTemporalTracksWithAMotionPriorAgreeWithTheTrueFlow) {
  const test::FlowErrors e = tracked_flow_errors(SceneProfile::kOutdoor, kOutdoorFrames, test::Prior::kNoisy);
  const std::vector<double> rigid = errors_up_to_deformation(e, 0.10);
  testing::Test::RecordProperty("rigid_fraction", num(static_cast<double>(rigid.size()) / e.errors.size()));
  testing::Test::RecordProperty("rigid_median_px", num(quantile(rigid, 0.5)));
  testing::Test::RecordProperty("rigid_p90_px", num(quantile(rigid, 0.9)));
  EXPECT_GT(rigid.size(), e.errors.size() / 2);
  EXPECT_LT(quantile(rigid, 0.5), 0.2);
  EXPECT_LT(quantile(rigid, 0.9), 0.5);
  EXPECT_LT(quantile(e.errors, 0.5), 0.25);
  EXPECT_LT(quantile(e.errors, 0.9), 1.5);
  // Points that vanish (occlusion boundaries of buildings against the far street) stay rare.
  EXPECT_LT(e.invalid, static_cast<int>(3 * e.errors.size() / 100));
}

/// The same sequence with a 0.15 px round trip and a minimum eigenvalue of 0.02 (edge-like
/// windows, whose KLT slides along the edge, are lost): the stretching patches are dropped and
/// the targets hold over all tracks, at the cost of some tracks (edge_client/README.md: not
/// shipped, as the outdoor VIO was not better with them).
TEST(FeatureTracker, OutdoorStrictChecksMeetTheTargetsOverAllTracks) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kOutdoor, "easy", kOutdoorFrames);
  ASSERT_NE(seq, nullptr);
  TrackerOptions strict = test::tracker_options(SceneProfile::kOutdoor);
  strict.temporal_round_trip_px = 0.15;
  strict.temporal_min_eigenvalue = 0.02;
  const test::FlowErrors shipped =
      test::temporal_errors(*seq, test::run_tracker(*seq, test::tracker_options(SceneProfile::kOutdoor),
                                                    seq->images, test::Prior::kNoisy));
  const auto tracked = test::run_tracker(*seq, strict, seq->images, test::Prior::kNoisy);
  const test::FlowErrors e = test::temporal_errors(*seq, tracked);
  testing::Test::RecordProperty("strict_flow_median_px", num(quantile(e.errors, 0.5)));
  testing::Test::RecordProperty("strict_flow_p90_px", num(quantile(e.errors, 0.9)));
  testing::Test::RecordProperty("strict_tracks", static_cast<int>(e.errors.size()));
  testing::Test::RecordProperty("shipped_tracks", static_cast<int>(shipped.errors.size()));
  EXPECT_LT(quantile(e.errors, 0.5), 0.2);
  EXPECT_LT(quantile(e.errors, 0.9), 0.5);
  // The strict checks remove tracked steps (so they are on), but at most 15 % of them.
  EXPECT_LT(e.errors.size(), shipped.errors.size());
  EXPECT_GT(e.errors.size(), 85 * shipped.errors.size() / 100);
}

/// Relative errors of the stereo depths (z in cam0) against the ray-cast depth, features
/// nearer than `max_depth` only.
std::vector<double> stereo_depth_errors(const test::TestSequence& seq,
                                        const std::vector<TrackedFrame>& tracked, double max_depth,
                                        int* stereo_count) {
  std::vector<double> errors;
  const SE3d T_c1_c0 = seq.world.calibration.T_c0_c1().inverse();
  *stereo_count = 0;
  for (std::size_t k = 0; k < tracked.size(); ++k) {
    const SE3d T_w_c0 = seq.T_w_c(0, k);
    for (const FeatureObservation& o : tracked[k].features) {
      if (!o.stereo) continue;
      ++*stereo_count;
      const auto hit = seq.renderer->cast_pixel(0, T_w_c0, o.uv_left);
      if (!hit) continue;
      const double z_true = (T_w_c0.inverse() * hit->point_w).z();
      if (z_true > max_depth) continue;
      const auto depths = triangulate_depths(T_c1_c0, o.xn_left, o.xn_right);
      if (!depths) continue;
      errors.push_back(std::abs(depths->x() - z_true) / z_true);
    }
  }
  return errors;
}

TEST(FeatureTracker, IndoorStereoDepthsAgreeWithGroundTruth) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  const auto tracked = test::run_tracker(*seq, test::tracker_options(SceneProfile::kIndoor), seq->images);
  int stereo = 0;
  const std::vector<double> errors = stereo_depth_errors(*seq, tracked, 5.0, &stereo);
  int features = 0;
  for (const TrackedFrame& f : tracked) features += static_cast<int>(f.features.size());
  ASSERT_GE(errors.size(), 1000u);
  EXPECT_GT(stereo, features / 2);  // most features have a right observation
  EXPECT_LT(quantile(errors, 0.5), 0.02);
  EXPECT_LT(quantile(errors, 0.95), 0.10);
  testing::Test::RecordProperty("depth_rel_median", num(quantile(errors, 0.5)));
  testing::Test::RecordProperty("depth_rel_p95", num(quantile(errors, 0.95)));
  testing::Test::RecordProperty("stereo_fraction", num(static_cast<double>(stereo) / features));
}

/// `images` with a textured square (cut from elsewhere in the same image) pasted at a place
/// moving 9 px right and 6 px up per frame: an object the scene does not explain.
std::vector<std::array<cv::Mat, 2>> with_moving_occluder(const std::vector<std::array<cv::Mat, 2>>& images,
                                                         bool left, bool right) {
  std::vector<std::array<cv::Mat, 2>> out;
  for (std::size_t k = 0; k < images.size(); ++k) {
    std::array<cv::Mat, 2> pair = {images[k][0].clone(), images[k][1].clone()};
    const int x = 150 + 9 * static_cast<int>(k), y = 300 - 6 * static_cast<int>(k);
    const cv::Rect patch(x, y, 140, 120);
    for (int c = 0; c < 2; ++c) {
      if ((c == 0 && !left) || (c == 1 && !right)) continue;
      images[0][0](cv::Rect(20, 20, 140, 120))
          .copyTo(pair[static_cast<std::size_t>(c)](patch));  // same texture
    }
    out.push_back(pair);
  }
  return out;
}

double outlier_fraction(const test::FlowErrors& e) {
  const auto bad = std::count_if(e.errors.begin(), e.errors.end(), [](double x) { return x > 1.0; });
  return static_cast<double>(bad + e.invalid) / static_cast<double>(e.errors.size() + e.invalid);
}

TEST(FeatureTracker, TemporalOutliersFromAMovingOccluderAreRejected) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  const auto occluded = with_moving_occluder(seq->images, true, true);
  TrackerOptions options = test::tracker_options(SceneProfile::kIndoor);
  const test::FlowErrors checked = test::temporal_errors(*seq, test::run_tracker(*seq, options, occluded));
  options.temporal_ransac_px = 20.0;  // the check practically off: the occluder's tracks survive
  const test::FlowErrors unchecked = test::temporal_errors(*seq, test::run_tracker(*seq, options, occluded));
  testing::Test::RecordProperty("outliers_checked", num(outlier_fraction(checked)));
  testing::Test::RecordProperty("outliers_unchecked", num(outlier_fraction(unchecked)));
  EXPECT_GT(outlier_fraction(unchecked), 0.03);  // the injection does create outliers
  EXPECT_LT(outlier_fraction(checked), 0.01);
  EXPECT_LT(quantile(checked.errors, 0.9), 0.5);
}

TEST(FeatureTracker, StereoOutliersFromAnOccluderInOneCameraAreRejected) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  const auto occluded = with_moving_occluder(seq->images, false, true);  // only the right image
  TrackerOptions options = test::tracker_options(SceneProfile::kIndoor);
  int stereo = 0;
  const auto bad_share = [&](const TrackerOptions& o) {
    const std::vector<double> e =
        stereo_depth_errors(*seq, test::run_tracker(*seq, o, occluded), 100.0, &stereo);
    return static_cast<double>(std::count_if(e.begin(), e.end(), [](double x) { return x > 0.1; })) /
           static_cast<double>(std::max<std::size_t>(e.size(), 1));
  };
  const double checked = bad_share(options);
  options.stereo_epipolar_px = 20.0;
  options.stereo_lr_px = 20.0;
  const double unchecked = bad_share(options);
  testing::Test::RecordProperty("stereo_outliers_checked", num(checked));
  testing::Test::RecordProperty("stereo_outliers_unchecked", num(unchecked));
  EXPECT_GT(unchecked, checked);
  EXPECT_LT(checked, 0.01);
}

TEST(FeatureTracker, TrackLengthsAndIdsAreStable) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  const auto tracked = test::run_tracker(*seq, test::tracker_options(SceneProfile::kIndoor), seq->images);
  const std::vector<double> final_lengths = ended_track_lengths(tracked);
  ASSERT_FALSE(final_lengths.empty());
  testing::Test::RecordProperty("ended_track_median_len", num(quantile(final_lengths, 0.5)));
  EXPECT_GE(quantile(final_lengths, 0.5), 4.0);  // 20 Hz indoor: tracks last several frames
}

TEST(FeatureTracker, EachFeatureCarriesTheBrightnessAroundIt) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  const auto tracked = test::run_tracker(*seq, test::tracker_options(SceneProfile::kIndoor), seq->images);
  ASSERT_EQ(tracked.size(), seq->images.size());
  int checked = 0;
  for (std::size_t f = 0; f < tracked.size(); ++f) {
    const cv::Mat& left = seq->images[f][0];
    for (const FeatureObservation& o : tracked[f].features) {
      // The 7 x 7 pixels around the rounded pixel, summed by hand.
      const int u = static_cast<int>(std::lround(o.uv_left.x())),
                v = static_cast<int>(std::lround(o.uv_left.y()));
      double sum = 0.0;
      int n = 0;
      for (int dv = -3; dv <= 3; ++dv) {
        for (int du = -3; du <= 3; ++du) {
          if (u + du < 0 || v + dv < 0 || u + du >= left.cols || v + dv >= left.rows) continue;
          sum += left.at<std::uint8_t>(v + dv, u + du);
          ++n;
        }
      }
      ASSERT_GT(n, 0);
      ASSERT_NEAR(o.brightness, std::max(1.0, sum / n), 1e-3) << f << " " << o.id;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(FeatureTracker, WrongImageSizeOrTypeOrTimeIsAClearErrorAndStateIsKept) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  auto tracker = FeatureTracker::create(test::tracker_options(SceneProfile::kIndoor), seq->world.calibration);
  ASSERT_TRUE(tracker.ok());
  ASSERT_TRUE(tracker->process(seq->t_ns[0], seq->images[0][0], seq->images[0][1]).ok());
  cv::Mat small(100, 120, CV_8UC1, cv::Scalar(0));
  auto bad = tracker->process(seq->t_ns[1], seq->images[1][0], small);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("cam1 image is 120x100"), std::string::npos) << bad.status();
  EXPECT_NE(bad.status().message().find("752x480"), std::string::npos) << bad.status();
  cv::Mat colour;
  cv::cvtColor(seq->images[1][0], colour, cv::COLOR_GRAY2BGR);
  EXPECT_FALSE(tracker->process(seq->t_ns[1], colour, seq->images[1][1]).ok());
  auto stale = tracker->process(seq->t_ns[0], seq->images[1][0], seq->images[1][1]);
  ASSERT_FALSE(stale.ok());
  EXPECT_NE(stale.status().message().find("not after the previous frame"), std::string::npos);
  // The failed calls changed nothing: frame 1 tracks from frame 0.
  auto good = tracker->process(seq->t_ns[1], seq->images[1][0], seq->images[1][1]);
  ASSERT_TRUE(good.ok()) << good.status();
  EXPECT_GT(good->stats.tracked, 150);
}

TEST(FeatureTracker, InvalidOptionsAreRefused) {
  const test::TestSequence* seq = test::sequence(SceneProfile::kIndoor, "easy", kIndoorFrames);
  ASSERT_NE(seq, nullptr);
  TrackerOptions options;
  options.max_features = 0;
  auto tracker = FeatureTracker::create(options, seq->world.calibration);
  ASSERT_FALSE(tracker.ok());
  EXPECT_NE(tracker.status().message().find("max_features"), std::string::npos) << tracker.status();
  options = TrackerOptions{};
  options.temporal_min_eigenvalue = -1e-3;
  tracker = FeatureTracker::create(options, seq->world.calibration);
  ASSERT_FALSE(tracker.ok());
  EXPECT_NE(tracker.status().message().find("temporal_min_eigenvalue"), std::string::npos)
      << tracker.status();
}

}  // namespace
}  // namespace mrvs::edge
