// KLT on consecutive rendered frames against the ray-cast true flow (simulator.md section 6
// item 11), on pose pairs 50 ms apart from the real V1_01_easy ground truth.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "mrvs/core/stats.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

struct KltResult {
  int corners = 0;             ///< GFTT corners away from discontinuities with a valid true flow
  int tracked = 0;             ///< of those, LK status ok
  std::vector<double> errors;  ///< |LK - true| of the tracked ones, px
};

// GFTT in frame k, LK into frame k + 1 (10 GT samples = 50 ms later), compared with true_flow.
KltResult track_pair(const RenderTestWorld& w, std::size_t k) {
  KltResult out;
  const StereoRenderer& r = *w.renderer;
  const SE3d T0 = r.camera_pose(0, w.trajectory[k].T_w_b);
  const SE3d T1 = r.camera_pose(0, w.trajectory[k + 10].T_w_b);
  const StatusOr<cv::Mat> img0 = r.render(0, T0, FrameInfo{0, 1.0});
  const StatusOr<cv::Mat> img1 = r.render(0, T1, FrameInfo{1, 1.0});
  const StatusOr<TruthImage> truth = r.render_truth(0, T0);
  EXPECT_TRUE(img0.ok() && img1.ok() && truth.ok());
  if (!img0.ok() || !img1.ok() || !truth.ok()) return out;
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(*img0, corners, 400, 0.01, 10);
  std::vector<cv::Point2f> p0;
  std::vector<Vec2d> expected;
  for (const cv::Point2f& c : corners) {
    const int u = static_cast<int>(std::lround(c.x)), v = static_cast<int>(std::lround(c.y));
    // Drop corners within 2 px of a face (hence depth) discontinuity.
    if (!test::uniform_face(truth->face, u, v, 2)) continue;
    const std::optional<Vec2d> flow = r.true_flow(0, T0, T1, Vec2d(c.x, c.y));
    if (!flow) continue;
    p0.push_back(c);
    expected.push_back(Vec2d(c.x, c.y) + *flow);
  }
  out.corners = static_cast<int>(p0.size());
  if (p0.empty()) return out;
  std::vector<cv::Point2f> p1;
  std::vector<unsigned char> status;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(*img0, *img1, p0, p1, status, err, cv::Size(21, 21), 2);
  for (std::size_t i = 0; i < p0.size(); ++i) {
    if (status[i] == 0) continue;
    ++out.tracked;
    out.errors.push_back((Vec2d(p1[i].x, p1[i].y) - expected[i]).norm());
  }
  return out;
}

TEST(RenderFlow, KltMatchesTrueFlowOnRealMotion) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  std::vector<double> all;
  for (double seconds : {12.0, 30.0, 55.0}) {
    const std::size_t k = test::pose_index_at(w->trajectory, seconds);
    ASSERT_LT(k + 10, w->trajectory.size());
    ASSERT_NEAR(static_cast<double>(w->trajectory[k + 10].t_ns - w->trajectory[k].t_ns), 50e6, 1e5);
    const KltResult res = track_pair(*w, k);
    const double motion =
        (w->trajectory[k + 10].T_w_b.translation() - w->trajectory[k].T_w_b.translation()).norm();
    SCOPED_TRACE(testing::Message() << "t = " << seconds << " s, motion " << motion * 100 << " cm");
    EXPECT_GE(res.corners, 150);
    EXPECT_GE(res.tracked, res.corners * 8 / 10);
    EXPECT_LT(quantile(res.errors, 0.5), 0.15);
    EXPECT_LT(quantile(res.errors, 0.9), 0.5);
    all.insert(all.end(), res.errors.begin(), res.errors.end());
  }
  RecordProperty("klt_median_px", test::num(quantile(all, 0.5)));
  RecordProperty("klt_p90_px", test::num(quantile(all, 0.9)));
  RecordProperty("klt_tracks", static_cast<int>(all.size()));
}

}  // namespace
}  // namespace mrvs::sim
