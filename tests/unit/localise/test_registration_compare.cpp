// The measurement code behind localise_compare (tests/tools): request dumps read back what was
// written and name the file and line of what is wrong; the frame conversions between T_map_odom
// and PCL's transform of the aligned submap are inverse; and each method, started 0.2 m and 5
// deg off the truth in a cluttered room, converges to it (so that the comparison measures the
// methods, not a broken wiring); FPFH + sample consensus finds the room from nowhere.
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "localise_scene.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/localise/localiser.h"
#include "mrvs/test/temp_dir.h"
#include "mrvs/tools/pcl_registration.h"
#include "mrvs/tools/request_dump.h"

namespace mrvs::tools {
namespace {

struct Room {
  std::shared_ptr<map::VoxelMap> map;
  localisation::Request request;
  SE3d truth;  ///< T_m_o
};

const Room& room() {
  static const Room r = [] {
    Room x;
    const auto samples = localise::test::cluttered_room(14, 21).sample(0.01);
    x.map = localise::test::voxelise(samples, {0.03, 0.1});
    const SE3d T_o_m = localise::test::yaw_pose(0.7, Eigen::Vector3d(-2.0, 1.0, 0.4));
    x.request = localise::test::submap_request(samples, {2.5, 2.5, 1.3}, 4.0, 4000, 0.01, T_o_m, 3);
    x.truth = T_o_m.inverse();
    return x;
  }();
  return r;
}

double translation_error(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
  return (a.topRightCorner<3, 1>() - b.topRightCorner<3, 1>()).norm();
}

double angle_error_deg(const Eigen::Matrix4d& a, const Eigen::Matrix4d& b) {
  const Eigen::Matrix3d d = a.topLeftCorner<3, 3>() * b.topLeftCorner<3, 3>().transpose();
  return Eigen::AngleAxisd(d).angle() * kRadToDeg;
}

TEST(RequestDump, ReadsBackWhatWasWritten) {
  const test::TempDir dir;
  localisation::Request q = room().request;
  q.seq = 42;
  q.gravity_o = Eigen::Vector3d(0.1, 0.0, -1.0).normalized();
  q.prior = localisation::PriorRegion{{350000.5, 5800000.25, 40.0}, 12.5};
  q.viewpoints = {{Eigen::Vector3f(0.1f, 0.2f, 0.3f), 10}, {Eigen::Vector3f(-1.0f, 0.0f, 2.0f), 5}};
  q.brightness.clear();
  for (std::size_t i = 0; i < q.points.size(); ++i)
    q.brightness.push_back(static_cast<std::uint8_t>(i * 7 % 256));
  const SE3d answer = localise::test::yaw_pose(0.3, {1, 2, 3});
  ASSERT_TRUE(write_request_dump(dir.path().string(), q, answer, room().truth).ok());
  const auto files = request_dump_files(dir.path().string());
  ASSERT_EQ(files.size(), 1u);
  const auto d = read_request_dump(files[0]);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->request.points.size(), q.points.size());
  for (std::size_t i = 0; i < q.points.size(); ++i)
    ASSERT_LT((d->request.points[i] - q.points[i]).norm(), 1e-5f);
  EXPECT_LT((d->request.gravity_o - q.gravity_o).norm(), 1e-12);
  EXPECT_LT((d->request.anchor_o - q.anchor_o).norm(), 1e-12);
  ASSERT_TRUE(d->request.prior.has_value());
  EXPECT_LT((d->request.prior->centre_m - q.prior->centre_m).norm(), 1e-6);
  EXPECT_DOUBLE_EQ(d->request.prior->radius_m, 12.5);
  ASSERT_EQ(d->request.viewpoints.size(), 2u);
  EXPECT_EQ(d->request.viewpoints[1].count, 5u);
  EXPECT_EQ(d->request.brightness, q.brightness);
  EXPECT_LT((d->truth.matrix() - room().truth.matrix()).norm(), 1e-9);
  EXPECT_LT((d->answer.matrix() - answer.matrix()).norm(), 1e-9);
}

TEST(RequestDump, AMalformedFileNamesItsLine) {
  const test::TempDir dir;
  const std::string path = (dir / "req_1.txt").string();
  std::ofstream(path) << "TRUE 1 0 0 0\nTRUE 0 1 0 0\nTRUE 0 0 1 0\nTRUE 0 0 0 1\nP 1 2\n";
  const auto d = read_request_dump(path);
  ASSERT_FALSE(d.ok());
  EXPECT_NE(std::string(d.status().message()).find("req_1.txt:5"), std::string::npos) << d.status();
  std::ofstream(path) << "P 1 2 3\n";
  const auto none = read_request_dump(path);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(std::string(none.status().message()).find("TRUE"), std::string::npos) << none.status();
  EXPECT_FALSE(read_request_dump((dir / "missing.txt").string()).ok());
}

TEST(PclRegistration, FramesConvertBothWays) {
  localisation::Request q = room().request;
  q.gravity_o = Eigen::Vector3d(0.05, -0.1, -1.0).normalized();
  const AlignedSubmap s = align_submap(q, PclOptions{});
  const Vec3d origin(350000.0, 5800000.0, 40.0);
  const SE3d T(Quatd(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.1, 0.2, 1.0).normalized())), {3, -1, 2});
  const SE3d back = T_m_o_from(M_from(T, s, q, origin), s, q, origin);
  EXPECT_LT((back.matrix() - T.matrix()).norm(), 1e-9);
  // A submap point goes to the same map-local point either way.
  const Eigen::Vector3d p = q.points[10].cast<double>();
  const Eigen::Matrix4d M = M_from(T, s, q, origin);
  const Eigen::Vector3d via_m = M.topLeftCorner<3, 3>() * (s.R_g * p) + M.topRightCorner<3, 1>();
  EXPECT_LT((via_m - (T * (q.anchor_o + p) - origin)).norm(), 1e-6);
}

Eigen::Matrix4d offset_start(const Eigen::Matrix4d& truth) {
  Eigen::Matrix4d s = truth;
  s.topLeftCorner<3, 3>() = Eigen::AngleAxisd(5.0 * kDegToRad, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                            truth.topLeftCorner<3, 3>();
  s.topRightCorner<3, 1>() += Eigen::Vector3d(0.14, -0.14, 0.0);
  return s;
}

TEST(PclRegistration, FineMethodsConvergeFromAnOffsetStart) {
  const Room& r = room();
  auto pcl_map = PclMap::build(*r.map, PclOptions{}, false);
  ASSERT_TRUE(pcl_map.ok()) << pcl_map.status();
  const AlignedSubmap s = align_submap(r.request, PclOptions{});
  const Eigen::Matrix4d truth = M_from(r.truth, s, r.request, r.map->origin);
  const Eigen::Matrix4d start = offset_start(truth);
  ASSERT_GT(translation_error(start, truth), 0.19);
  for (PclMethod m : {PclMethod::kGicp, PclMethod::kPointToPlane, PclMethod::kNdt}) {
    const PclResult res = pcl_map->register_fine(m, s, start);
    EXPECT_TRUE(res.converged) << pcl_method_name(m);
    EXPECT_LT(translation_error(res.M, truth), 0.02) << pcl_method_name(m);
    EXPECT_LT(angle_error_deg(res.M, truth), 1.0) << pcl_method_name(m);
    EXPECT_GT(res.fitness, 0.8) << pcl_method_name(m);
  }
  // The localiser's own fine stage from the same start.
  auto loc = localise::Localiser::create(r.map, localise::LocaliserOptions{});
  ASSERT_TRUE(loc.ok()) << loc.status();
  const auto ours = loc->refine(r.request, T_m_o_from(start, s, r.request, r.map->origin));
  ASSERT_EQ(ours.status, localisation::Status::kOk) << ours.detail;
  const Eigen::Matrix4d M = M_from(ours.T_m_o, s, r.request, r.map->origin);
  EXPECT_LT(translation_error(M, truth), 0.02);
  EXPECT_LT(angle_error_deg(M, truth), 0.5);
}

TEST(PclRegistration, FpfhSampleConsensusFindsAMovedCopyOfTheMapFromNowhere) {
  // The wiring of the global method: the map's own points near a viewpoint, turned and shifted,
  // are found from nowhere (same points, same normals: FPFH describes them alike). On real
  // submaps (stereo points resampled, noisy) FPFH describes the planes of a room poorly; that is
  // what localise_compare measures.
  const Room& r = room();
  PclOptions o;
  o.map_level_m = 0.1;
  o.voxel_m = 0.1;
  o.fpfh_radius_m = 0.35;
  o.normal_radius_m = 0.2;
  o.sac_iterations = 20000;
  auto pcl_map = PclMap::build(*r.map, o, true);
  ASSERT_TRUE(pcl_map.ok()) << pcl_map.status();
  Eigen::Matrix4d truth = Eigen::Matrix4d::Identity();
  truth.topLeftCorner<3, 3>() = Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.topRightCorner<3, 1>() = Eigen::Vector3d(2.5, 2.5, 1.3);
  AlignedSubmap s;
  for (const auto& p : r.map->levels[1].points) {
    const Eigen::Vector3d x = p.position.cast<double>() - truth.topRightCorner<3, 1>();
    if (x.norm() <= 2.5) s.points.push_back(truth.topLeftCorner<3, 3>().transpose() * x);
  }
  ASSERT_GT(s.points.size(), 500u);
  const PclResult res = pcl_map->register_global(s);
  ASSERT_TRUE(res.converged);
  EXPECT_LT(translation_error(res.M, truth), 0.05);
  EXPECT_LT(angle_error_deg(res.M, truth), 1.0);
  EXPECT_GT(res.fitness, 0.9);
}

}  // namespace
}  // namespace mrvs::tools
