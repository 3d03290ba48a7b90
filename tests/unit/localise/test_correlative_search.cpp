// The branch and bound against an exhaustive search over the same lattice (every yaw step,
// every anchor cell): the same best score; and on a cluttered room it finds the true pose.
#include <algorithm>

#include <gtest/gtest.h>

#include "correlative_search.h"
#include "localise_scene.h"
#include "mrvs/geometry/angles.h"

namespace mrvs::localise {
namespace {

/// The score of one pose on the lattice (the anchor's cell holding `anchor`), by brute force.
double exact_score(const LikelihoodPyramid& g, const std::vector<Eigen::Vector3d>& pts, double yaw,
                   const Eigen::Vector3d& anchor) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3i cell = g.cell_of(anchor);
  int s = 0;
  for (const auto& p : pts) {
    s += g.value(
        0,
        cell +
            ((R * p) / g.resolution() + Eigen::Vector3d::Constant(0.5)).array().floor().cast<int>().matrix());
  }
  return s / (255.0 * pts.size());
}

/// Every pose's score on the lattice, best first, by brute force.
std::vector<int> exhaustive_scores(const LikelihoodPyramid& g, const std::vector<Eigen::Vector3d>& pts,
                                   const SearchWindow& w) {
  const int yaws = static_cast<int>(std::ceil(2.0 * kPi / w.yaw_step_rad));
  std::vector<int> all;
  for (int k = 0; k < yaws; ++k) {
    const Eigen::Matrix3d R =
        Eigen::AngleAxisd(2.0 * kPi * k / yaws, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    std::vector<Eigen::Vector3i> off;
    for (const auto& p : pts) {
      off.push_back(((R * p) / g.resolution() + Eigen::Vector3d::Constant(0.5)).array().floor().cast<int>());
    }
    for (int z = w.anchor_min.z(); z <= w.anchor_max.z(); ++z)
      for (int y = w.anchor_min.y(); y <= w.anchor_max.y(); ++y)
        for (int x = w.anchor_min.x(); x <= w.anchor_max.x(); ++x) {
          int s = 0;
          for (const auto& o : off) s += g.value(0, Eigen::Vector3i(x, y, z) + o);
          all.push_back(s);
        }
  }
  std::sort(all.rbegin(), all.rend());
  return all;
}

double exhaustive_best(const LikelihoodPyramid& g, const std::vector<Eigen::Vector3d>& pts,
                       const SearchWindow& w) {
  return exhaustive_scores(g, pts, w).front() / (255.0 * pts.size());
}

TEST(CorrelativeSearch, BestScoreEqualsTheExhaustiveSearch) {
  const test::Scene scene = test::cluttered_room(6, 11);
  const auto samples = scene.sample(0.05);
  std::vector<Eigen::Vector3f> map_pts;
  for (const auto& p : samples) map_pts.push_back(p.cast<float>());
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(8.5, 6.5, 3.5));
  const auto g = LikelihoodPyramid::build(map_pts, box, 0.25, 4, 1.0);
  const auto q =
      test::submap_request(samples, {5.0, 2.0, 1.2}, 2.5, 150, 0.0, test::yaw_pose(0.7, {1, 2, 0}), 1);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : q.points) pts.push_back(p.cast<double>());
  SearchWindow w;
  w.anchor_min = g.cell_of({3.0, 0.5, 0.5});
  w.anchor_max = g.cell_of({7.0, 4.0, 2.0});
  w.yaw_step_rad = 10.0 * kDegToRad;
  SearchOptions o;
  o.max_hypotheses = 3;
  o.min_score = 0.05;
  SearchStats stats;
  const auto hyps = correlative_search(g, pts, w, o, &stats);
  ASSERT_FALSE(hyps.empty());
  EXPECT_NEAR(hyps.front().score, exhaustive_best(g, pts, w), 1e-12);
  for (std::size_t i = 1; i < hyps.size(); ++i) {
    EXPECT_LE(hyps[i].score, hyps[i - 1].score);
    EXPECT_FALSE(same_pose(hyps[i], hyps[0], o));
  }
  // Every hypothesis carries its pose's exact score, not a bound (windows whose scoring stops
  // early, once they cannot win, are scored in full before they become hypotheses).
  for (const Hypothesis& h : hyps) EXPECT_NEAR(h.score, exact_score(g, pts, h.yaw, h.anchor), 1e-12);
  const long long cells = (w.anchor_max - w.anchor_min + Eigen::Vector3i::Ones()).prod();
  EXPECT_LT(stats.nodes, cells * stats.yaws / 4) << "the bound prunes";
}

TEST(CorrelativeSearch, TheBestPosesAreTheExhaustiveSearchsWherePointsLeaveTheGrid) {
  // Anchors over the whole grid and past it, the submap near its corner: most windows put
  // points outside the grid, where the search reads cells clamped into it
  // (LikelihoodPyramid::clamped_linear). With no two poses the same, the search keeps the K
  // best of every pose on the lattice: the brute force's K best scores.
  const test::Scene scene = test::cluttered_room(6, 11);
  const auto samples = scene.sample(0.05);
  std::vector<Eigen::Vector3f> map_pts;
  for (const auto& p : samples) map_pts.push_back(p.cast<float>());
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(8.5, 6.5, 3.5));
  const auto q =
      test::submap_request(samples, {1.5, 1.0, 1.2}, 3.0, 120, 0.0, test::yaw_pose(-1.1, {2, 1, 0}), 4);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : q.points) pts.push_back(p.cast<double>());
  for (int levels : {1, 3, 4}) {
    const auto g = LikelihoodPyramid::build(map_pts, box, 0.25, levels, 1.0);
    SearchWindow w;
    w.anchor_min = g.cell_of(box.min()) - Eigen::Vector3i::Constant(3);
    w.anchor_max = g.cell_of(box.max()) + Eigen::Vector3i(2, 1, 3);
    w.yaw_step_rad = 20.0 * kDegToRad;
    SearchOptions o;
    o.max_hypotheses = 60;
    o.min_score = 0.05;
    o.distinct_m = 0.0;  // every pose is its own
    const auto hyps = correlative_search(g, pts, w, o);
    const std::vector<int> expect = exhaustive_scores(g, pts, w);
    ASSERT_EQ(hyps.size(), 60u) << levels << " levels";
    for (std::size_t i = 0; i < hyps.size(); ++i) {
      EXPECT_NEAR(hyps[i].score, expect[i] / (255.0 * pts.size()), 1e-12) << levels << " levels, " << i;
      EXPECT_NEAR(hyps[i].score, exact_score(g, pts, hyps[i].yaw, hyps[i].anchor), 1e-12);
    }
  }
}

TEST(CorrelativeSearch, FindsTheTruePoseInAClutteredRoom) {
  const test::Scene scene = test::cluttered_room(12, 4);
  const auto samples = scene.sample(0.03);
  std::vector<Eigen::Vector3f> map_pts;
  for (const auto& p : samples) map_pts.push_back(p.cast<float>());
  const Eigen::AlignedBox3d box(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(8.5, 6.5, 3.5));
  const auto g = LikelihoodPyramid::build(map_pts, box, 0.1, 5, 1.0);
  const Eigen::Vector3d view(2.5, 3.5, 1.4);
  const double yaw_o_m = -2.1;
  const auto q =
      test::submap_request(samples, view, 3.5, 600, 0.02, test::yaw_pose(yaw_o_m, {4, -1, 0.3}), 2);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : q.points) pts.push_back(p.cast<double>());
  SearchWindow w;
  w.anchor_min = g.cell_of(box.min());
  w.anchor_max = g.cell_of(box.max());
  w.yaw_step_rad = 1.5 * kDegToRad;
  SearchOptions o;
  const auto hyps = correlative_search(g, pts, w, o);
  ASSERT_FALSE(hyps.empty());
  EXPECT_LT((hyps[0].anchor - view).norm(), 0.15);
  EXPECT_LT(yaw_difference(hyps[0].yaw, -yaw_o_m) * kRadToDeg, 2.0);
}

}  // namespace
}  // namespace mrvs::localise
