// Renderer geometry against exact projection (simulator.md section 6 item 9): truth hits lie on
// their faces, project back to their pixel, land on the epipolar line of cam1; correspondences
// and true flow agree with direct projection.
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/sim/rng.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

struct ChainStats {
  int checked = 0;
  int in_cam1 = 0;
  double max_reprojection_px = 0.0;
  double max_face_distance_m = 0.0;
  double max_epipolar = 0.0;
  double max_depth_error_m = 0.0;
  double max_lod_error = 0.0;
  std::string worst_face;  ///< the pixel and face of max_face_distance_m
};

// Checks the projection chain of one pixel; updates `stats`.
void check_pixel(const RenderTestWorld& w, const TruthImage& truth, const SE3d& T_w_c0, const SE3d& T_w_c1,
                 int u, int v, ChainStats* stats) {
  const StereoRenderer& r = *w.renderer;
  const Face& face = w.scene->faces()[static_cast<std::size_t>(truth.face.at<int>(v, u))];
  const double range = truth.range.at<float>(v, u);
  const Vec3d d_c = r.rays(0).center(u, v).cast<double>();
  const Vec3d X = T_w_c0.translation() + range * (T_w_c0.quaternion() * d_c);
  // The hit lies on its face at its (u, v).
  const Vec3d on_face =
      face.origin + truth.u.at<float>(v, u) * face.axis_u + truth.v.at<float>(v, u) * face.axis_v;
  if ((X - on_face).norm() > stats->max_face_distance_m) {
    stats->max_face_distance_m = (X - on_face).norm();
    std::ostringstream out;
    out << "pixel (" << u << ", " << v << ") face " << face.id << " (object " << face.object_id << ", normal "
        << face.normal.transpose() << ", axis_u " << face.axis_u.transpose() << ", axis_v "
        << face.axis_v.transpose() << ", size " << face.size_u << " x " << face.size_v << "): hit (u, v) = ("
        << truth.u.at<float>(v, u) << ", " << truth.v.at<float>(v, u)
        << "), X - origin = " << (X - face.origin).transpose();
    stats->worst_face = out.str();
  }
  // Mip level, in double: log2(t * pixel angle / max(|n.d|, 0.2) / texel), >= 0.
  const double cos_incidence = std::max(std::abs(face.normal.dot(T_w_c0.quaternion() * d_c)), 0.2);
  const double footprint = range * r.rays(0).pixel_angle(u, v) / cos_incidence / w.scene->texel_size(face.id);
  const double lod = std::max(0.0, std::log2(footprint));
  stats->max_lod_error = std::max(stats->max_lod_error, std::abs(lod - truth.lod.at<float>(v, u)));
  // Back into cam0 with the forward model: the same pixel.
  const Vec3d X_c0 = T_w_c0.inverse() * X;
  const std::optional<Vec2d> uv0 = r.camera(0).project(X_c0);
  ASSERT_TRUE(uv0.has_value());
  stats->max_reprojection_px = std::max(stats->max_reprojection_px, (*uv0 - Vec2d(u, v)).norm());
  stats->max_depth_error_m =
      std::max(stats->max_depth_error_m, std::abs(X_c0.z() - truth.depth.at<float>(v, u)));
  // Into cam1: epipolar relation f1 . (t x R f0) = 0 with T_c1_c0 = (R, t).
  const std::optional<Vec2d> uv1 = r.camera(1).project(T_w_c1.inverse() * X);
  if (!uv1 || !r.camera(1).in_image(*uv1)) return;
  ++stats->in_cam1;
  const SE3d T_c1_c0 = T_w_c1.inverse() * T_w_c0;
  const StatusOr<Vec3d> f0 = r.camera(0).unproject(Vec2d(u, v));
  const StatusOr<Vec3d> f1 = r.camera(1).unproject(*uv1);
  ASSERT_TRUE(f0.ok() && f1.ok());
  const Vec3d t = T_c1_c0.translation().normalized();
  const double residual = std::abs(f1->dot(t.cross(T_c1_c0.quaternion() * *f0)));
  stats->max_epipolar = std::max(stats->max_epipolar, residual);
}

TEST(RenderGeometry, ProjectionChainAwayFromDiscontinuities) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const CounterRng rng(1, Stream::kScene);
  ChainStats stats;
  for (double seconds : {8.0, 25.0, 60.0}) {
    const SE3d& T_w_b = w->trajectory[test::pose_index_at(w->trajectory, seconds)].T_w_b;
    const SE3d T_w_c0 = w->renderer->camera_pose(0, T_w_b);
    const SE3d T_w_c1 = w->renderer->camera_pose(1, T_w_b);
    const StatusOr<TruthImage> truth = w->renderer->render_truth(0, T_w_c0);
    ASSERT_TRUE(truth.ok()) << truth.status();
    for (std::uint64_t i = 0; i < 3000; ++i) {
      const int u = static_cast<int>(rng.uniform(0.0, 752.0, i, 0)),
                v = static_cast<int>(rng.uniform(0.0, 480.0, i, 1));
      if (!test::uniform_face(truth->face, u, v, 1) || truth->face.at<int>(v, u) < 0) continue;
      ++stats.checked;
      check_pixel(*w, *truth, T_w_c0, T_w_c1, u, v, &stats);
    }
  }
  RecordProperty("max_reprojection_px", test::num(stats.max_reprojection_px));
  RecordProperty("max_epipolar", test::num(stats.max_epipolar));
  ASSERT_GT(stats.checked, 6000);
  EXPECT_LT(stats.max_reprojection_px, 1e-3);
  EXPECT_LT(stats.max_face_distance_m, 1e-4) << stats.worst_face;
  EXPECT_LT(stats.max_depth_error_m, 1e-4);
  EXPECT_LT(stats.max_lod_error, 1e-4);
  EXPECT_LT(stats.max_epipolar, 1e-6);
  // An 11 cm baseline: most of cam0's view is also in cam1.
  EXPECT_GT(stats.in_cam1, stats.checked * 8 / 10);
}

TEST(RenderGeometry, CorrespondenceAndFlowMatchDirectProjection) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  const std::size_t k = test::pose_index_at(w->trajectory, 30.0);
  const SE3d T_w_c0 = r.camera_pose(0, w->trajectory[k].T_w_b);
  const SE3d T_w_c0_next = r.camera_pose(0, w->trajectory[k + 10].T_w_b);
  const SE3d T_w_c1 = r.camera_pose(1, w->trajectory[k].T_w_b);
  int found = 0;
  for (int v = 20; v < 480; v += 37) {
    for (int u = 20; u < 752; u += 41) {
      const Vec2d uv(u + 0.3, v - 0.2);
      // Same pose: zero flow.
      const std::optional<Vec2d> zero = r.true_flow(0, T_w_c0, T_w_c0, uv);
      ASSERT_TRUE(zero.has_value());
      EXPECT_LT(zero->norm(), 1e-6);
      const std::optional<PixelHit> hit = r.cast_pixel(0, T_w_c0, uv);
      ASSERT_TRUE(hit.has_value());
      for (const auto& [cam, T_to] : {std::pair{0, T_w_c0_next}, std::pair{1, T_w_c1}}) {
        const std::optional<Correspondence> c = r.correspondence(0, T_w_c0, uv, cam, T_to);
        if (!c) continue;
        ++found;
        const std::optional<Vec2d> direct = r.camera(cam).project(T_to.inverse() * hit->point_w);
        ASSERT_TRUE(direct.has_value());
        EXPECT_LT((*direct - c->uv).norm(), 1e-9);
        EXPECT_NEAR(c->range_to, (hit->point_w - T_to.translation()).norm(), 1e-9);
      }
    }
  }
  EXPECT_GT(found, 300);
}

TEST(RenderGeometry, OccludedPointsHaveNoCorrespondence) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& r = *w->renderer;
  const SE3d T_w_c0 = r.camera_pose(0, w->trajectory[test::pose_index_at(w->trajectory, 30.0)].T_w_b);
  const StatusOr<TruthImage> truth = r.render_truth(0, T_w_c0);
  ASSERT_TRUE(truth.ok());
  // Move the camera 0.5 m back along its axis: every correspondence that survives must be
  // visible from there (its re-cast stops at the point), and the rejected ones were blocked.
  const SE3d T_w_back = T_w_c0 * SE3d(Quatd::Identity(), Vec3d(0.0, 0.0, -0.5));
  int visible = 0, rejected_in_image = 0;
  for (int v = 5; v < 480; v += 13) {
    for (int u = 5; u < 752; u += 13) {
      const Vec2d uv(u, v);
      const std::optional<PixelHit> hit = r.cast_pixel(0, T_w_c0, uv);
      if (!hit) continue;
      const std::optional<Correspondence> c = r.correspondence(0, T_w_c0, uv, 0, T_w_back);
      const Vec3d diff = hit->point_w - T_w_back.translation();
      const std::optional<Hit> recast =
          w->scene->intersect(T_w_back.translation().cast<float>(), diff.normalized().cast<float>(), 1000.0f);
      const bool blocked = recast && recast->distance < diff.norm() - std::max(1e-3, 1e-3 * diff.norm());
      if (c) {
        ++visible;
        EXPECT_FALSE(blocked);
      } else if (const auto uv_back = r.camera(0).project(T_w_back.inverse() * hit->point_w);
                 uv_back && r.camera(0).in_image(*uv_back)) {
        ++rejected_in_image;
        EXPECT_TRUE(blocked);
      }
    }
  }
  EXPECT_GT(visible, 500);
  RecordProperty("occluded", rejected_in_image);
}

}  // namespace
}  // namespace mrvs::sim
