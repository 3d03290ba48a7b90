// The 4-DoF point-to-plane refinement: converges from a perturbed start to the true pose, and
// its information matrix predicts the spread of the estimate over noise draws (independent
// noise: the uninflated covariance s^2 H^-1 is right within sampling error).
#include <random>

#include <gtest/gtest.h>

#include "correlative_search.h"
#include "localise_scene.h"
#include "map_surface.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/localise/localiser.h"
#include "point_to_plane.h"

namespace mrvs::localise {
namespace {

struct Fixture {
  std::vector<Eigen::Vector3d> samples;
  MapSurface surface;
};

const Fixture& room() {
  static const Fixture f = [] {
    Fixture out;
    out.samples = test::cluttered_room(10, 8).sample(0.02);
    std::vector<Eigen::Vector3f> pts;
    for (const auto& p : test::voxelise(out.samples, {0.03})->levels[0].points) pts.push_back(p.position);
    out.surface = MapSurface::build(std::move(pts), 12, 0.01);
    return out;
  }();
  return f;
}

std::vector<Eigen::Vector3d> submap(const Eigen::Vector3d& view, double sigma, std::uint64_t seed) {
  const auto q = test::submap_request(room().samples, view, 3.0, 2000, sigma, SE3d(), seed);
  std::vector<Eigen::Vector3d> pts;
  for (const auto& p : q.points) pts.push_back(p.cast<double>());
  return pts;
}

// The nearest map point within a radius, against brute force over the whole map: the search
// bounded by the radius finds the same point, and none when the nearest lies beyond it.
TEST(MapSurface, NearestWithinARadiusIsTheBruteForceNearest) {
  const MapSurface& s = room().surface;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.5, 8.5);
  int found = 0, none = 0;
  for (int k = 0; k < 400; ++k) {
    const Eigen::Vector3f q(static_cast<float>(u(rng)), static_cast<float>(0.8 * u(rng)),
                            static_cast<float>(0.4 * u(rng)));
    float best_d = INFINITY;
    for (std::uint32_t i = 0; i < s.size(); ++i) best_d = std::min(best_d, (s.point(i) - q).norm());
    for (const float radius : {0.02f, 0.1f, 0.3f, 10.0f}) {
      const auto nb = s.nearest(q, radius);
      if (best_d < radius * (1.0f - 1e-5f)) {
        ASSERT_TRUE(nb.has_value()) << k << " " << radius;
        EXPECT_NEAR(nb->distance_m, best_d, 1e-5f);
        EXPECT_NEAR((s.point(nb->index) - q).norm(), best_d, 1e-5f);
        ++found;
      } else if (best_d > radius * (1.0f + 1e-5f)) {
        EXPECT_FALSE(nb.has_value()) << k << " " << radius << " " << best_d;
        ++none;
      }
    }
  }
  EXPECT_GT(found, 400);
  EXPECT_GT(none, 400);
}

TEST(PointToPlane, ConvergesToTheTruePose) {
  EXPECT_GT(room().surface.planar_fraction(), 0.8);
  const Eigen::Vector3d view(3.0, 2.5, 1.3);
  const auto pts = submap(view, 0.0, 1);
  FineOptions o;
  const FineResult r =
      refine_pose(room().surface, pts, 3.0 * kDegToRad, view + Eigen::Vector3d(0.1, -0.08, 0.05), o);
  EXPECT_LT((r.anchor - view).norm(), 0.003);
  EXPECT_LT(std::abs(r.yaw) * kRadToDeg, 0.05);
  EXPECT_GT(r.fitness, 0.95);
  EXPECT_LT(r.rmse_m, 0.01);
}

// After the correspondence distance has shrunk, the iterations go on until the steps stop, up to
// the shipped cap: from a start off in height by more than the end distance, with the height held
// only by a few floor points (in the edge's stereo submaps the walls dominate) and stray points,
// the fine stage reaches the height and stops by converging, not by the cap. (On the seed-1
// tuning set, a fixed 20 iterations left three answers 12-20 cm high: cloud_server/localise/README.md.)
TEST(PointToPlane, AWeaklyHeldHeightConvergesBeforeTheCap) {
  const Eigen::Vector3d view(3.0, 2.5, 1.3);
  std::vector<Eigen::Vector3d> pts;
  int n = 0;
  for (const Eigen::Vector3d& p : submap(view, 0.01, 7)) {
    if (p.z() + view.z() > 0.03 || ++n % 50 == 0) pts.push_back(p);
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 400; ++i) pts.emplace_back(u(rng), u(rng), 0.5 * u(rng));
  FineOptions o;
  o.iterations = LocaliserOptions().fine_iterations;
  o.ramp_iterations = LocaliserOptions().fine_ramp_iterations;
  const FineResult r = refine_pose(room().surface, pts, 0.0, view + Eigen::Vector3d(0.0, 0.0, 0.25), o);
  EXPECT_LT(std::abs(r.anchor.z() - view.z()), 0.005);
  EXPECT_LT((r.anchor - view).norm(), 0.01);
  EXPECT_GE(r.iterations, o.ramp_iterations);
  EXPECT_LT(r.iterations, o.iterations) << "stopped by the cap, not converged";
}

TEST(PointToPlane, InformationPredictsTheSpreadOverNoiseDraws) {
  const Eigen::Vector3d view(5.0, 3.0, 1.2);
  const double sigma = 0.01;
  FineOptions o;
  std::vector<Eigen::Vector4d> errors;
  Eigen::Matrix4d predicted = Eigen::Matrix4d::Zero();
  const int trials = 40;
  for (int t = 0; t < trials; ++t) {
    const auto pts = submap(view, sigma, 100 + t);
    const FineResult r = refine_pose(room().surface, pts, 0.01, view + Eigen::Vector3d(0.03, 0.02, -0.02), o);
    errors.push_back((Eigen::Vector4d() << r.anchor - view, r.yaw).finished());
    predicted += r.rmse_m * r.rmse_m * r.information.inverse() / trials;
  }
  Eigen::Matrix4d sample = Eigen::Matrix4d::Zero();
  for (const auto& e : errors) sample += e * e.transpose() / trials;
  for (int i = 0; i < 4; ++i) {
    // 40 draws: the sample variance is within about a factor 1.6 of the truth (chi-square 95 %);
    // the map's own voxelisation (3 cm) adds a bias the prediction does not know about.
    EXPECT_LT(sample(i, i), 4.0 * predicted(i, i)) << i;
    EXPECT_GT(sample(i, i), 0.25 * predicted(i, i)) << i;
  }
}

}  // namespace
}  // namespace mrvs::localise
