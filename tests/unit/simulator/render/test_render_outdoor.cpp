// Outdoor rendering: rays that hit nothing see Scene::background() (the sky at the top rows).
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "render_test_world.h"

namespace mrvs::sim {
namespace {

TEST(RenderOutdoor, SkyAtTheTopRowsRoadAtTheBottom) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok());
  std::vector<Vec3d> route;
  for (int i = 0; i <= 200; ++i) route.emplace_back(i, 0.0, 1.7);
  StatusOr<Scene> scene = make_scene(SceneProfile::kOutdoor, SceneOptions{}, route, 3);
  ASSERT_TRUE(scene.ok()) << scene.status();
  const StatusOr<StereoRenderer> r = StereoRenderer::create(*scene, *rig, RenderOptions{}, 1);
  ASSERT_TRUE(r.ok()) << r.status();
  // Camera at the start of the route looking down it (+x), image x = -y, image y = -z.
  Mat3d R_w_c;
  R_w_c.col(0) = -Vec3d::UnitY();
  R_w_c.col(1) = -Vec3d::UnitZ();
  R_w_c.col(2) = Vec3d::UnitX();
  const SE3d T_w_c(R_w_c, Vec3d(20.0, 0.0, 1.7));
  const StatusOr<cv::Mat> image = r->render(0, T_w_c, FrameInfo{});
  const StatusOr<TruthImage> truth = r->render_truth(0, T_w_c);
  ASSERT_TRUE(image.ok() && truth.ok());
  int sky_top = 0, ground_bottom = 0, sky_exact = 0, sky_checked = 0;
  for (int u = 0; u < 752; ++u) {
    for (int v = 0; v < 10; ++v) {
      if (truth->face.at<int>(v, u) >= 0) continue;
      ++sky_top;
      if (!test::uniform_face(truth->face, u, v + 1, 1)) continue;  // away from edges: exact sky radiance
      const Eigen::Vector3f d_w = T_w_c.rotation_matrix().cast<float>() * r->rays(0).center(u, v + 1);
      ++sky_checked;
      sky_exact += image->at<std::uint8_t>(v + 1, u) == std::round(255.0 * scene->background(d_w));
    }
    ground_bottom += truth->face.at<int>(479, u) >= 0;
  }
  RecordProperty("sky_fraction_top_rows", test::num(sky_top / 7520.0));
  EXPECT_GT(sky_top, 7520 / 5);
  EXPECT_EQ(ground_bottom, 752);
  EXPECT_EQ(sky_exact, sky_checked);
  EXPECT_GT(sky_checked, 0);
}

}  // namespace
}  // namespace mrvs::sim
