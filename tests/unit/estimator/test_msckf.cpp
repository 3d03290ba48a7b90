// MSCKF pieces: the null-space projection removes the feature exactly, feature rows match
// the measurement model, and an update with consistent features pulls a perturbed clone
// back.
#include <random>

#include <gtest/gtest.h>

#include "mrvs/edge/feature_measurement.h"
#include "mrvs/edge/msckf_updater.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/test/numeric_jacobian.h"
#include "msckf_scene.h"

namespace mrvs::edge {
namespace {

using test::make_scene;
using test::Scene;

TEST(Msckf, NullSpaceProjectionRemovesTheFeatureExactly) {
  const Scene s = make_scene();
  auto rows = feature_rows(s.state, s.track, s.p_w, s.p_w, 1.0);
  ASSERT_TRUE(rows.ok()) << rows.status();
  EXPECT_EQ(rows->m.rows(), 24);
  EXPECT_LT(rows->m.r.norm(), 1e-9);  // exact observations
  // Carry H_f along as extra columns: after the projection they must vanish.
  Measurement m = rows->m;
  m.vars.push_back(Slot{s.state.dim(), 3});
  m.H.conservativeResize(Eigen::NoChange, m.H.cols() + 3);
  m.H.rightCols<3>() = rows->H_f;
  auto split = split_by_new_variable(m, rows->H_f);
  ASSERT_TRUE(split.ok());
  EXPECT_EQ(split->rest.rows(), 24 - 3);
  EXPECT_LT(split->rest.H.rightCols<3>().cwiseAbs().maxCoeff(), 1e-9 * rows->H_f.cwiseAbs().maxCoeff());
  // The clone columns keep their information (rank 21 of 36).
  EXPECT_GT(split->rest.H.leftCols(36).norm(), 0.1 * rows->m.H.norm());
}

TEST(Msckf, FeatureRowsMatchTheMeasurementModelNumerically) {
  const Scene s = make_scene();
  auto rows = feature_rows(s.state, s.track, s.p_w, s.p_w, 1.0);
  ASSERT_TRUE(rows.ok());
  const auto residuals = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    return feature_rows(test::moved_state(s.state, rows->m.vars, d), s.track, s.p_w, s.p_w, 1.0)->m.r;
  };
  const Eigen::MatrixXd num =
      -mrvs::test::numeric_jacobian<double>(residuals, static_cast<int>(rows->m.H.cols()), 1e-6);
  EXPECT_TRUE(mrvs::test::matrices_near(rows->m.H, num, 1e-3));
  const auto point = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    return feature_rows(s.state, s.track, s.p_w + Vec3d(d), s.p_w + Vec3d(d), 1.0)->m.r;
  };
  EXPECT_TRUE(mrvs::test::matrices_near(
      rows->H_f, Eigen::MatrixXd(-mrvs::test::numeric_jacobian<double>(point, 3, 1e-6)), 1e-3));
}

TEST(Msckf, AnUpdatePullsAPerturbedCloneBack) {
  Scene s = make_scene(0.3);
  // Twenty more points, all seen by every clone.
  FeatureDatabase db;
  test::add_points(s.state, 20, 0.3, 2, &db);
  std::vector<FeatureId> ids;
  for (FeatureId id = 1; id <= 20; ++id) ids.push_back(id);
  // The last clone is off by 3 cm and 0.5 deg; the prior allows it.
  const TimestampNs last = s.state.newest_clone_ns();
  const SE3d truth = s.state.clones.at(last).T_w_b;
  CloneState& c = s.state.clones.at(last);
  c.T_w_b = SE3d(c.T_w_b.quaternion() * so3::exp_quat<double>(Vec3d(0.0, 0.0, 0.5 * M_PI / 180.0)),
                 c.T_w_b.translation() + Vec3d(0.0, 0.03, 0.0));
  c.fej = c.T_w_b;
  s.state.P.block<6, 6>(c.slot.offset, c.slot.offset) = Eigen::Matrix<double, 6, 6>::Identity() * 1e-2;
  const MsckfUpdater updater(MsckfOptions{}, TriangulationOptions{});
  const MsckfStats stats = updater.update(s.state, db, ids);
  ASSERT_TRUE(stats.status.ok()) << stats.status;
  EXPECT_EQ(stats.used, 20);
  const SE3d& after = s.state.clones.at(last).T_w_b;
  EXPECT_LT((after.translation() - truth.translation()).norm(), 0.01);
  EXPECT_LT(so3::log<double>(after.quaternion().conjugate() * truth.quaternion()).norm(), 0.2 * M_PI / 180.0);
}

}  // namespace
}  // namespace mrvs::edge
