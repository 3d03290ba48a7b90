// Ray tables: the float32 round trip over every pixel centre and subsample (simulator.md
// section 6 item 8), pixel footprint angles, and errors.
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

#include "mrvs/camera/camera_model.h"
#include "mrvs/sim/ray_table.h"
#include "render_test_world.h"

namespace mrvs::sim {
namespace {

TEST(RayTable, SubsampleOffsetsAreTheQuarterPixelPattern) {
  EXPECT_EQ(RayTable::subsample_offset(0), Vec2d(-0.25, -0.25));
  EXPECT_EQ(RayTable::subsample_offset(1), Vec2d(0.25, -0.25));
  EXPECT_EQ(RayTable::subsample_offset(2), Vec2d(-0.25, 0.25));
  EXPECT_EQ(RayTable::subsample_offset(3), Vec2d(0.25, 0.25));
}

TEST(RayTable, EurocRoundTripBelowOneThousandthPixelOverAllPixels) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  for (const config::CameraCalibration& cam : rig->cameras) {
    const StatusOr<RayTable> table = RayTable::build(*cam.model);
    ASSERT_TRUE(table.ok()) << table.status();
    ASSERT_EQ(table->width(), 752);
    ASSERT_EQ(table->height(), 480);
    const double err = table->max_round_trip_error(*cam.model);
    RecordProperty(cam.name + "_max_round_trip_px", test::num(err));
    EXPECT_LT(err, 1e-3) << cam.name;
    // Unit rays in front of the camera; the image corner is about 53 degrees off axis.
    EXPECT_NEAR(table->center(0, 0).norm(), 1.0f, 1e-6f);
    EXPECT_GT(table->center(0, 0).z(), 0.5f);
    EXPECT_LT(table->center(0, 0).z(), 0.7f);
  }
}

TEST(RayTable, EquidistantRoundTrip) {
  camera::Params p;
  p << 280.0, 280.0, 320.0, 240.0, -0.01, 0.02, -0.005, 0.001;  // corners about 80 degrees off axis
  const auto cam = camera::make_camera(camera::DistortionModel::kEquidistant, 640, 480, p);
  ASSERT_TRUE(cam.ok()) << cam.status();
  const StatusOr<RayTable> table = RayTable::build(**cam);
  ASSERT_TRUE(table.ok()) << table.status();
  EXPECT_LT(table->max_round_trip_error(**cam), 1e-3);
  EXPECT_LT(table->center(0, 0).z(), 0.3f);  // far off axis
}

TEST(RayTable, PixelAngleMatchesTheFocalLengthAtTheCentre) {
  const StatusOr<config::StereoRigCalibration> rig = test::euroc_rig();
  ASSERT_TRUE(rig.ok()) << rig.status();
  const camera::CameraModel& cam = *rig->cameras[0].model;
  const StatusOr<RayTable> table = RayTable::build(cam);
  ASSERT_TRUE(table.ok()) << table.status();
  const int u = static_cast<int>(std::lround(cam.cx())), v = static_cast<int>(std::lround(cam.cy()));
  EXPECT_NEAR(table->pixel_angle(u, v), 1.0 / std::sqrt(cam.fx() * cam.fy()), 0.01 / cam.fx());
  // Brute force: the angle between the centre rays of the 4-neighbours, near the centre and in
  // a corner (there the perspective compression outweighs the barrel distortion).
  for (const auto& [pu, pv] : {std::pair{u, v}, std::pair{10, 100}, std::pair{1, 1}}) {
    const Vec3d l = table->center(pu - 1, pv).cast<double>(), r = table->center(pu + 1, pv).cast<double>();
    const Vec3d t = table->center(pu, pv - 1).cast<double>(), b = table->center(pu, pv + 1).cast<double>();
    const double brute = std::sqrt(std::acos(l.dot(r)) * std::acos(t.dot(b))) / 2.0;
    EXPECT_NEAR(table->pixel_angle(pu, pv), brute, 0.02 * brute) << pu << "," << pv;
  }
  EXPECT_LT(table->pixel_angle(0, 0), 0.8 * table->pixel_angle(u, v));
}

TEST(RayTable, FoldingDistortionInsideTheImageIsAnError) {
  camera::Params p;
  p << 200.0, 200.0, 320.0, 240.0, -0.8, 0.0, 0.0, 0.0;  // folds over at r = 0.65 (130 px)
  const auto cam = camera::make_camera(camera::DistortionModel::kRadTan, 640, 480, p);
  ASSERT_TRUE(cam.ok()) << cam.status();
  const StatusOr<RayTable> table = RayTable::build(**cam);
  ASSERT_FALSE(table.ok());
  EXPECT_EQ(table.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(table.status().message().find("row"), absl::string_view::npos) << table.status();
}

}  // namespace
}  // namespace mrvs::sim
