// Moving people against brute force: the walk's ping-pong timing, the ray-box test against
// ray marching, and the counted people pixels against every pixel's ray tested with no
// culling; people occlude the scene and leave it untouched elsewhere.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "mrvs/sim/people.h"
#include "mrvs/sim/rng.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

using test::RenderTestWorld;
using test::world;

TEST(Walker, WalksBackAndForthAtItsSpeedFacingWhereItGoes) {
  Walker w;
  w.a = Eigen::Vector2d(1.0, 2.0);
  w.b = Eigen::Vector2d(4.0, 6.0);  // 5 m
  w.speed_mps = 1.25;               // 4 s one way
  w.at_a_ns = 1'000'000'000;
  w.height_m = 1.8;
  Eigen::Vector2d heading;
  const auto at = [&](double s) { return w.centre(w.at_a_ns + static_cast<TimestampNs>(s * 1e9), &heading); };
  EXPECT_LT((at(0.0).head<2>() - w.a).norm(), 1e-9);
  EXPECT_NEAR(at(0.0).z(), 0.9, 1e-12);
  EXPECT_LT((at(2.0).head<2>() - Eigen::Vector2d(2.5, 4.0)).norm(), 1e-9);
  EXPECT_LT((heading - Eigen::Vector2d(0.6, 0.8)).norm(), 1e-12);
  EXPECT_LT((at(4.0).head<2>() - w.b).norm(), 1e-9);
  EXPECT_LT((at(5.0).head<2>() - Eigen::Vector2d(3.25, 5.0)).norm(), 1e-9);  // on the way back
  EXPECT_LT((heading + Eigen::Vector2d(0.6, 0.8)).norm(), 1e-12);
  EXPECT_LT((at(8.0).head<2>() - w.a).norm(), 1e-9);
  EXPECT_LT((at(-1.0).head<2>() - Eigen::Vector2d(1.75, 3.0)).norm(), 1e-9);  // before at_a: coming back
}

TEST(PersonBox, TheRayTestIsTheFirstPointInsideTheBox) {
  Walker w;
  w.a = Eigen::Vector2d(0.0, 0.0);
  w.b = Eigen::Vector2d(1.0, 1.0);
  const PersonBox box = people_at({w}, 300'000'000).front();
  const CounterRng rng(5, Stream::kPeople);
  int hits = 0;
  for (std::uint64_t k = 0; k < 2000; ++k) {
    const Eigen::Vector3f origin(static_cast<float>(rng.uniform(-3.0, 3.0, k, 0)),
                                 static_cast<float>(rng.uniform(-3.0, 3.0, k, 1)),
                                 static_cast<float>(rng.uniform(-1.0, 3.0, k, 2)));
    const Eigen::Vector3f target =
        box.centre_w + Eigen::Vector3f(static_cast<float>(rng.uniform(-0.6, 0.6, k, 3)),
                                       static_cast<float>(rng.uniform(-0.6, 0.6, k, 4)),
                                       static_cast<float>(rng.uniform(-1.2, 1.2, k, 5)));
    const Eigen::Vector3f d = (target - origin).normalized();
    const auto inside = [&](float t) {
      const Eigen::Vector3f p = box.R_p_w * (origin + t * d - box.centre_w);
      return (p.cwiseAbs() - box.half).maxCoeff() <= 0.0f;
    };
    if (inside(0.0f)) continue;
    std::optional<float> marched;  // 0.1 mm steps
    for (float t = 0.0f; t < 10.0f && !marched; t += 1e-4f) {
      if (inside(t)) marched = t;
    }
    const std::optional<float> t = box.intersect(origin, d, 10.0f);
    ASSERT_EQ(t.has_value(), marched.has_value()) << k;
    if (!t) continue;
    ++hits;
    EXPECT_NEAR(*t, *marched, 2e-4f) << k;
    const float a = box.albedo(origin + *t * d);
    EXPECT_GE(a, 0.03f);
    EXPECT_LE(a, 0.97f);
  }
  EXPECT_GT(hits, 500);
}

TEST(RenderPeople, CountedPixelsAreThoseWhoseRayMeetsAPersonFirst) {
  const RenderTestWorld* w = world();
  ASSERT_NE(w, nullptr);
  const StereoRenderer& plain = *w->renderer;
  const TimestampNs t = 2'000'000'000;
  const SE3d T_w_c = plain.camera_pose(0, w->trajectory[test::pose_index_at(w->trajectory, 20.0)].T_w_b);
  // One person 2 m ahead (levelled), walking across the view, and one behind the camera.
  const Vec3d ahead = T_w_c.translation() + 2.0 * T_w_c.rotation_matrix().col(2);
  const Vec3d right = T_w_c.rotation_matrix().col(0);
  Walker front;
  front.a = (ahead - 1.5 * right).head<2>();
  front.b = (ahead + 1.5 * right).head<2>();
  front.floor_z = 0.0;
  front.at_a_ns = t - 1'000'000'000;  // 1.3 m along: near the middle at t
  Walker back = front;
  back.a = (T_w_c.translation() - 3.0 * T_w_c.rotation_matrix().col(2)).head<2>();
  back.b = back.a + Eigen::Vector2d(0.5, 0.0);
  const StereoRenderer r = plain.with_people({front, back});
  const std::int64_t counted = r.people_pixels(0, T_w_c, t);
  // Brute force: every pixel's ray (camera unproject) against the scene and both people.
  const std::vector<PersonBox> boxes = people_at({front, back}, t);
  const camera::CameraModel& model = r.camera(0);
  std::int64_t brute = 0;
  for (int v = 0; v < model.height(); ++v) {
    for (int u = 0; u < model.width(); ++u) {
      const auto ray = model.unproject(Vec2d(u, v));
      if (!ray.ok()) continue;
      const Eigen::Vector3f d = (T_w_c.rotation_matrix() * ray->normalized()).cast<float>();
      const std::optional<PixelHit> hit = plain.cast_pixel(0, T_w_c, Vec2d(u, v));
      const float scene_t = hit ? hit->hit.distance : 1e9f;
      bool person = false;
      for (const PersonBox& b : boxes) {
        const std::optional<float> pt = b.intersect(T_w_c.translation().cast<float>(), d, scene_t);
        person = person || pt.has_value();
      }
      brute += person ? 1 : 0;
    }
  }
  ::testing::Test::RecordProperty("people_pixels", static_cast<int>(counted));
  EXPECT_GT(brute, 20000);  // a person 2 m away covers a good part of the image
  EXPECT_NEAR(static_cast<double>(counted), static_cast<double>(brute), 0.002 * static_cast<double>(brute));
  // The image changes where the person is, and only there (no noise in the default options).
  const StatusOr<cv::Mat> without = plain.render(0, T_w_c, FrameInfo{0, 1.0, 1.0, t});
  const StatusOr<cv::Mat> with = r.render(0, T_w_c, FrameInfo{0, 1.0, 1.0, t});
  ASSERT_TRUE(without.ok() && with.ok());
  cv::Mat diff;
  cv::compare(*without, *with, diff, cv::CMP_NE);
  const int changed = cv::countNonZero(diff);
  EXPECT_GT(changed, 0.8 * static_cast<double>(counted));
  EXPECT_LT(changed, 1.1 * static_cast<double>(counted));
  // Nobody in view at all: not one pixel.
  EXPECT_EQ(plain.with_people({back}).people_pixels(0, T_w_c, t), 0);
}

}  // namespace
}  // namespace mrvs::sim
