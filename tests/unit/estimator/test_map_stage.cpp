// The map side of the estimator: the registered-point grid against brute force, the ray of a
// feature and the edge's multi-view check, the stage-1 map measurement (whitening by the map
// noise, absolute correction that the null-space mode cannot give), the stage's handling of
// the cloud's answers, silence and deadline, and the whole two-stage update in process on a
// generated sequence (map over an in-process QueryEngine, no DDS).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "mrvs/edge/feature_measurement.h"
#include "mrvs/edge/map_stage.h"
#include "mrvs/edge/msckf_updater.h"
#include "mrvs/test/numeric_jacobian.h"
#include "mrvs/voxel/resolution.h"
#include "msckf_scene.h"
#include "vio_test_world.h"

namespace mrvs::edge {
namespace {

using Clock = std::chrono::steady_clock;

std::array<long, 3> cell(const Vec3d& p, double v) {
  return {static_cast<long>(std::floor(p.x() / v)), static_cast<long>(std::floor(p.y() / v)),
          static_cast<long>(std::floor(p.z() / v))};
}

std::set<FeatureId> brute_neighbourhood(const std::map<FeatureId, Vec3d>& in, const Vec3d& p, double v,
                                        int radius) {
  std::set<FeatureId> out;
  const auto c = cell(p, v);
  for (const auto& [id, q] : in) {
    const auto d = cell(q, v);
    bool near = true;
    for (int i = 0; i < 3; ++i) near = near && std::abs(d[i] - c[i]) <= radius;
    if (near) out.insert(id);
  }
  return out;
}

TEST(RegisteredMap, MatchesBruteForce) {
  const double v = 0.3;
  RegisteredMap grid(v, 5);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::map<FeatureId, Vec3d> kept;
  std::map<std::array<long, 3>, int> count;
  for (FeatureId id = 0; id < 2000; ++id) {
    const Vec3d p(u(rng), u(rng), 0.3 * u(rng));
    const bool room = count[cell(p, v)] < 5;
    EXPECT_EQ(grid.has_room(p), room);
    ASSERT_EQ(grid.add(id, p), room) << id;
    if (room) ++count[cell(p, v)], kept[id] = p;
  }
  EXPECT_FALSE(grid.add(5000, Vec3d(NAN, 0.0, 0.0)));
  EXPECT_EQ(grid.size(), kept.size());
  // Remove a third, move a third (where there is room).
  for (auto it = kept.begin(); it != kept.end();) {
    const FeatureId id = it->first;
    if (id % 3 == 0) {
      grid.remove(id);
      --count[cell(it->second, v)];
      it = kept.erase(it);
      continue;
    }
    if (id % 3 == 1) {
      const Vec3d to = it->second + Vec3d(0.31, -0.2, 0.0);
      if (count[cell(to, v)] < 5 && cell(to, v) != cell(it->second, v)) {
        --count[cell(it->second, v)];
        ++count[cell(to, v)];
        it->second = to;
      }
      grid.move(id, to);
    }
    ++it;
  }
  EXPECT_EQ(grid.size(), kept.size());
  for (int k = 0; k < 50; ++k) {
    const Vec3d p(u(rng), u(rng), 0.3 * u(rng));
    for (int radius : {0, 1, 2}) {
      const auto got = grid.neighbourhood(p, radius);
      EXPECT_EQ(std::set<FeatureId>(got.begin(), got.end()), brute_neighbourhood(kept, p, v, radius));
    }
  }
}

MapDescription indoor_map() {
  MapDescription m;
  m.origin = Vec3d(10.0, -5.0, 2.0);
  m.resolutions = {0.01, 0.02, 0.03};
  return m;
}

/// Ground truth of the scene's clones (for query_pose_source gt).
io::Trajectory clone_truth(const State& state) {
  io::Trajectory gt;
  for (const auto& [t, c] : state.clones) gt.push_back({t, c.T_w_b});
  return gt;
}

TEST(MapAssociation, TheRayGoesThroughTheNewestLeftObservation) {
  const test::Scene s = test::make_scene();
  const MapDescription map = indoor_map();
  MapOptions o;
  const auto ray = make_feature_ray(s.state, {}, s.track, s.p_w, map, o);
  ASSERT_TRUE(ray.has_value());
  const SE3d T_w_c = s.state.clones.at(6000).T_w_b * s.state.cams[0].T_b_c;
  EXPECT_EQ(ray->t_ns, 6000);
  EXPECT_EQ(ray->cam, 0);
  EXPECT_LT((ray->ray.origin.cast<double>() + map.origin - T_w_c.translation()).norm(), 1e-5);
  const Vec3d to_point = s.p_w - T_w_c.translation();
  EXPECT_LT(ray->ray.direction.cast<double>().normalized().cross(to_point.normalized()).norm(), 1e-6);
  EXPECT_NEAR(ray->ray.initial_distance, to_point.norm(), 1e-5);
  EXPECT_NEAR(ray->depth_m, (T_w_c.inverse() * s.p_w).z(), 1e-9);
  const auto level = voxel::select_level(map.resolutions, ray->depth_m, ray->focal_px);
  ASSERT_TRUE(level.has_value());
  EXPECT_FLOAT_EQ(ray->ray.resolution, static_cast<float>(map.resolutions[*level]));
  // A larger footprint scale asks a coarser level: at this depth (about 4 m, f 458 px) the
  // paper's rule picks 0.01 m, three times the footprint 0.03 m.
  EXPECT_FLOAT_EQ(ray->ray.resolution, 0.01f);
  o.footprint_scale = 3.0;
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.03f);
  o.fixed_resolution_m = 0.02;
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.02f);
  // Behind the camera: no ray.
  EXPECT_FALSE(make_feature_ray(s.state, {}, s.track, T_w_c * Vec3d(0.0, 0.0, -2.0), map, o).has_value());
}

TEST(MapAssociation, AnUncertainPoseAsksALevelThatCoversWhereTheRayMeetsTheMap) {
  test::Scene s = test::make_scene();
  const MapDescription map = indoor_map();
  MapOptions o;
  o.uncertainty_scale = 2.0;
  const TimestampNs t = 6000;
  const Slot clone = s.state.clones.at(t).slot;
  const auto set_sigma = [&](double sigma_p) {
    s.state.P = Eigen::MatrixXd::Identity(s.state.dim(), s.state.dim()) * 1e-12;
    s.state.P.block<3, 3>(clone.offset + 3, clone.offset + 3) = Mat3d::Identity() * sigma_p * sigma_p;
  };
  // Position only, isotropic: sigma across the ray is that of the position.
  const RayAnchor anchor{t, 0, s.state.T_w_c(t, 0).inverse() * s.p_w};
  set_sigma(0.004);
  EXPECT_NEAR(hit_sigma_across(s.state, anchor), 0.004, 1e-6);
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.01f);  // footprint
  set_sigma(0.008);  // 2 sigma = 1.6 cm
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.02f);
  set_sigma(0.05);  // beyond the coarsest level: the coarsest
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.03f);
  // Rotation: 0.5 deg at about 4 m is 3.5 cm across the ray.
  s.state.P = Eigen::MatrixXd::Identity(s.state.dim(), s.state.dim()) * 1e-12;
  const double sr = 0.5 * M_PI / 180.0;
  s.state.P.block<3, 3>(clone.offset, clone.offset) = Mat3d::Identity() * sr * sr;
  const double d = (s.p_w - s.state.T_w_c(t, 0).translation()).norm();
  EXPECT_NEAR(hit_sigma_across(s.state, anchor), d * sr, 0.03 * d * sr);  // camera 5.5 cm off the body
  // The uncertainty is that of the estimated pose: with ground-truth query poses it is not used.
  set_sigma(0.05);
  o.query_pose_source = "gt";
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, clone_truth(s.state), s.track, s.p_w, map, o)->ray.resolution,
                  0.01f);
}

TEST(MapAssociation, AMinimumResolutionSkipsTheFinerLevelsOnly) {
  test::Scene s = test::make_scene();
  const MapDescription map = indoor_map();
  MapOptions o;
  ASSERT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.01f);  // footprint
  o.min_resolution_m = 0.02;
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.02f);
  o.min_resolution_m = 0.025;  // between levels: the next coarser one
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.03f);
  o.min_resolution_m = 1.0;  // beyond the coarsest: the coarsest
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, {}, s.track, s.p_w, map, o)->ray.resolution, 0.03f);
  // A map property: with ground-truth query poses too; a fixed level is what it says.
  o.min_resolution_m = 0.02;
  o.query_pose_source = "gt";
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, clone_truth(s.state), s.track, s.p_w, map, o)->ray.resolution,
                  0.02f);
  o.fixed_resolution_m = 0.01;
  EXPECT_FLOAT_EQ(make_feature_ray(s.state, clone_truth(s.state), s.track, s.p_w, map, o)->ray.resolution,
                  0.01f);
}

TEST(MapAssociation, TheMultiViewCheckAcceptsTheTruePointOnly) {
  test::Scene s = test::make_scene();
  const MapDescription map = indoor_map();
  MapOptions o;
  const auto ray = make_feature_ray(s.state, {}, s.track, s.p_w, map, o);
  ASSERT_TRUE(ray.has_value());
  double error = -1.0;
  EXPECT_TRUE(accept_hit(s.state, {}, s.track, *ray, s.p_w, o, &error));
  EXPECT_LT(error, 1e-3);
  // 5 cm across the ray: several pixels in the other views.
  const Vec3d v = ray->ray.direction.cast<double>().normalized();
  const Vec3d across = v.cross(Vec3d::UnitZ()).normalized();
  EXPECT_FALSE(accept_hit(s.state, {}, s.track, *ray, s.p_w + 0.05 * across, o, &error));
  EXPECT_GT(error, o.threshold_upper_px);
  // 20 cm along it: consistent views, but too far from the triangulated point.
  EXPECT_FALSE(accept_hit(s.state, {}, s.track, *ray, s.p_w + 0.2 * v, o));
  o.max_hit_distance_m = 1.0;
  EXPECT_TRUE(accept_hit(s.state, {}, s.track, *ray, s.p_w + 0.05 * v, o));
  // With the state's clones 4 cm off, the check on the estimated poses refuses the true
  // point; on ground-truth poses (query_pose_source gt) it takes it.
  const io::Trajectory gt = clone_truth(s.state);
  for (auto& [t, c] : s.state.clones) {
    if (t != 6000)
      c.T_w_b = SE3d(c.T_w_b.quaternion(), c.T_w_b.translation() + Vec3d(0.0, 0.01 * (t / 1000), 0.0));
  }
  o.max_hit_distance_m = 0.15;
  EXPECT_FALSE(accept_hit(s.state, gt, s.track, *ray, s.p_w, o));
  o.query_pose_source = "gt";
  EXPECT_TRUE(accept_hit(s.state, gt, s.track, *ray, s.p_w, o, &error));
  EXPECT_LT(error, 1e-3);
}

TEST(MapMeasurement, KnownLandmarkRowsAreWhitenedByTheMapNoise) {
  const test::Scene s = test::make_scene(0.5);
  MsckfOptions mo;
  const MsckfUpdater updater(mo, TriangulationOptions{});
  const MapPoint point{s.p_w + Vec3d(0.004, -0.003, 0.002), 0.01 * 0.01, std::nullopt, Mat3d::Zero(),
                       std::nullopt};
  MsckfStats stats;
  const auto m = updater.map_measurement(s.state, s.track, point, Stage1Mode::kKnownLandmark, &stats);
  ASSERT_TRUE(m.has_value());
  auto rows = feature_rows(s.state, s.track, point.p_w, point.p_w, mo.sigma_px);
  ASSERT_TRUE(rows.ok());
  ASSERT_EQ(m->rows(), rows->m.rows());  // no null-space projection: every row stays
  // Brute force: information and weighted residual with the full noise covariance
  // S = sigma^2 I + var H_f H_f^T, in units of sigma^2.
  const double s2 = mo.sigma_px * mo.sigma_px;
  Eigen::MatrixXd S = point.variance * rows->H_f * rows->H_f.transpose();
  S.diagonal().array() += s2;
  const Eigen::MatrixXd Si = S.inverse();
  const Eigen::MatrixXd info = s2 * rows->m.H.transpose() * Si * rows->m.H;
  EXPECT_LT((m->H.transpose() * m->H - info).norm(), 1e-6 * info.norm());
  const Eigen::VectorXd g = s2 * rows->m.H.transpose() * Si * rows->m.r;
  EXPECT_LT((m->H.transpose() * m->r - g).norm(), 1e-6 * g.norm() + 1e-12);
  // The reference code's mode projects the point out: 2N - 3 rows.
  const auto ns = updater.map_measurement(s.state, s.track, point, Stage1Mode::kMsckfNullspace, &stats);
  ASSERT_TRUE(ns.has_value());
  EXPECT_EQ(ns->rows(), rows->m.rows() - 3);
}

/// Clones shifted together by `shift` (the unobservable direction of plain VIO), updated with
/// 20 features whose map points are known; the clones' mean position error after the update.
double mean_error_after_map_update(bool nullspace, const Vec3d& shift) {
  test::Scene s = test::make_scene();
  FeatureDatabase db;
  const std::vector<Vec3d> truth = test::add_points(s.state, 20, 0.3, 5, &db);
  std::map<TimestampNs, Vec3d> true_positions;
  for (auto& [t, c] : s.state.clones) {
    true_positions[t] = c.T_w_b.translation();
    c.T_w_b = c.fej = SE3d(c.T_w_b.quaternion(), c.T_w_b.translation() + shift);
    // Loose, independent priors: the shift is within them.
    s.state.P.block<3, 3>(c.slot.offset + 3, c.slot.offset + 3) = Mat3d::Identity() * 0.1 * 0.1;
  }
  std::vector<FeatureId> ids;
  std::map<FeatureId, MapPoint> map_points;
  for (FeatureId id = 1; id <= 20; ++id) {
    ids.push_back(id);
    map_points[id] = MapPoint{truth[id - 1], 0.005 * 0.005, std::nullopt, Mat3d::Zero(), std::nullopt};
  }
  const MsckfUpdater updater(MsckfOptions{}, TriangulationOptions{});
  const MsckfStats stats = updater.update(
      s.state, db, ids, map_points, nullspace ? Stage1Mode::kMsckfNullspace : Stage1Mode::kKnownLandmark);
  EXPECT_TRUE(stats.status.ok()) << stats.status;
  EXPECT_EQ(stats.with_map, 20);
  double sum = 0.0;
  for (const auto& [t, c] : s.state.clones) sum += (c.T_w_b.translation() - true_positions[t]).norm();
  return sum / static_cast<double>(s.state.clones.size());
}

TEST(MapMeasurement, KnownLandmarksCorrectAShiftThatTheNullSpaceModeCannot) {
  const Vec3d shift(0.02, 0.05, -0.03);
  const double known = mean_error_after_map_update(false, shift);
  const double nullspace = mean_error_after_map_update(true, shift);
  EXPECT_LT(known, 0.1 * shift.norm()) << "known_landmark";
  EXPECT_GT(nullspace, 0.7 * shift.norm()) << "msckf_nullspace";
}

/// The anchor of the scene's point on its newest left-camera observation, at `depth_error`
/// beyond the point.
RayAnchor scene_anchor(const State& state, const Vec3d& p_w, double depth_error) {
  const TimestampNs t = state.newest_clone_ns();
  const Vec3d p_c = state.T_w_c(t, 0).inverse() * p_w;
  return RayAnchor{t, 0, p_c * (1.0 + depth_error / p_c.norm())};
}

TEST(MapMeasurement, AnchoredRowsMatchTheirModelNumerically) {
  test::Scene s = test::make_scene(0.3);
  s.state.cams[0].extrinsic_slot = s.state.append(6);  // the anchor camera's extrinsics too
  s.state.P = Eigen::MatrixXd::Identity(s.state.dim(), s.state.dim()) * 1e-4;
  const RayAnchor anchor = scene_anchor(s.state, s.p_w, 0.02);
  auto rows = anchored_feature_rows(s.state, s.track, anchor, 1.0);
  ASSERT_TRUE(rows.ok()) << rows.status();
  EXPECT_EQ(rows->m.rows(), 2 * 12 - 2);  // every observation but the anchor's own
  EXPECT_EQ(rows->used.size(), 11u);
  // The model: across the ray the point moves with the anchor camera, along it it stays.
  const Vec3d X0 = *anchored_point(s.state, anchor);
  const Vec3d v = (X0 - s.state.T_w_c(anchor.t_ns, 0).translation()).normalized();
  FeatureTrack others = s.track;
  others.obs.erase(
      std::remove_if(others.obs.begin(), others.obs.end(),
                     [&](const CameraObservation& o) { return o.t_ns == anchor.t_ns && o.cam == 0; }),
      others.obs.end());
  const auto residuals = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
    const State moved = test::moved_state(s.state, rows->m.vars, d);
    const Vec3d moved_by = *anchored_point(moved, anchor) - X0;
    const Vec3d X = X0 + moved_by - v * v.dot(moved_by);
    return feature_rows(moved, others, X, X, 1.0)->m.r;
  };
  EXPECT_TRUE(rows->m.r.isApprox(residuals(Eigen::VectorXd::Zero(rows->m.H.cols()))));
  const Eigen::MatrixXd num =
      -mrvs::test::numeric_jacobian<double>(residuals, static_cast<int>(rows->m.H.cols()), 1e-6);
  EXPECT_TRUE(mrvs::test::matrices_near(rows->m.H, num, 1e-3));
  // The anchor clone's columns carry the point (they are not those of plain rows).
  auto plain = feature_rows(s.state, others, X0, X0, 1.0);
  ASSERT_TRUE(plain.ok());
  EXPECT_GT((rows->m.H.leftCols(plain->m.H.cols()) - plain->m.H).norm(), 0.1 * plain->m.H.norm());
  // An anchor whose clone or observation is gone is refused.
  RayAnchor gone = anchor;
  gone.t_ns = 999;
  EXPECT_FALSE(anchored_feature_rows(s.state, s.track, gone, 1.0).ok());
  EXPECT_FALSE(anchored_feature_rows(s.state, others, anchor, 1.0).ok());
}

/// Clones shifted together by `shift` (prior 10 cm a side), updated once with 20 map points
/// found along the estimated rays (each on a surface facing the ray through the true point:
/// across the ray the hit moves with the camera); the NEES of the newest clone's position
/// after the update and its error along the mean ray.
struct ShiftResult {
  double nees = 0.0;
  double error_along = 0.0, error_across = 0.0;
};
ShiftResult update_with_hits_along_estimated_rays(Stage1Mode mode, const Vec3d& shift,
                                                  bool association_noise = false) {
  test::Scene s = test::make_scene();
  FeatureDatabase db;
  const std::vector<Vec3d> truth = test::add_points(s.state, 20, 0.3, 5, &db);
  const TimestampNs newest = s.state.newest_clone_ns();
  const Vec3d true_p = s.state.clones.at(newest).T_w_b.translation();
  for (auto& [t, c] : s.state.clones) {
    c.T_w_b = c.fej = SE3d(c.T_w_b.quaternion(), c.T_w_b.translation() + shift);
    s.state.P.block<3, 3>(c.slot.offset + 3, c.slot.offset + 3) = Mat3d::Identity() * 0.1 * 0.1;
  }
  // Fully correlated position priors: the clones move together (plain VIO's drift).
  for (auto& [t, a] : s.state.clones)
    for (auto& [u, b] : s.state.clones)
      s.state.P.block<3, 3>(a.slot.offset + 3, b.slot.offset + 3) = Mat3d::Identity() * 0.1 * 0.1;
  std::vector<FeatureId> ids;
  std::map<FeatureId, MapPoint> map_points;
  Vec3d mean_ray = Vec3d::Zero();
  for (FeatureId id = 1; id <= 20; ++id) {
    const SE3d T_w_c = s.state.T_w_c(newest, 0);
    const Vec3d v = (truth[id - 1] + shift - T_w_c.translation()).normalized();  // estimated ray
    const Vec3d hit = T_w_c.translation() + v * v.dot(truth[id - 1] - T_w_c.translation());
    mean_ray += v;
    FeatureRay ray;
    ray.t_ns = newest;
    ids.push_back(id);
    map_points[id] = MapPoint{hit, 0.005 * 0.005, ray_anchor(s.state, *db.find(id), ray, hit), Mat3d::Zero(),
                              std::nullopt};
    if (association_noise)
      map_points[id].association = hit_covariance_across(s.state, *map_points[id].anchor);
  }
  mean_ray.normalize();
  const MsckfUpdater updater(MsckfOptions{}, TriangulationOptions{});
  const MsckfStats stats = updater.update(s.state, db, ids, map_points, mode);
  EXPECT_TRUE(stats.status.ok()) << stats.status;
  EXPECT_EQ(stats.with_map, 20);
  const CloneState& c = s.state.clones.at(newest);
  const Vec3d e = c.T_w_b.translation() - true_p;
  const Mat3d P = s.state.P.block<3, 3>(c.slot.offset + 3, c.slot.offset + 3);
  ShiftResult out;
  out.nees = e.dot(P.ldlt().solve(e));
  out.error_along = std::abs(e.dot(mean_ray));
  out.error_across = (e - mean_ray * e.dot(mean_ray)).norm();
  return out;
}

TEST(MapMeasurement, HitsAlongTheEstimatedRaysCorrectDepthWithoutFalseConfidenceInRayDepthMode) {
  const Vec3d shift(0.06, 0.04, -0.03);  // mostly along the rays (body x)
  const ShiftResult known = update_with_hits_along_estimated_rays(Stage1Mode::kKnownLandmark, shift);
  const ShiftResult depth = update_with_hits_along_estimated_rays(Stage1Mode::kRayDepth, shift);
  RecordProperty("known_nees", std::to_string(known.nees));
  RecordProperty("ray_depth_nees", std::to_string(depth.nees));
  RecordProperty("known_error_along_m", std::to_string(known.error_along));
  RecordProperty("ray_depth_error_along_m", std::to_string(depth.error_along));
  // ray_depth takes the depth the map gives, and knows that across the rays the hits say
  // nothing; the known landmarks pin the pose where the estimated rays met the map (here
  // they even keep most of the error along the rays) and claim millimetres.
  EXPECT_LT(depth.error_along, 0.3 * shift.x());
  EXPECT_GT(known.error_along, depth.error_along);
  EXPECT_GT(known.error_across, 0.5 * Vec2d(shift.y(), shift.z()).norm());
  EXPECT_GT(known.nees, 100.0);
  EXPECT_LT(depth.nees, 11.3);  // chi-square 3 dof, 99 %
  // Known landmarks with the association's uncertainty added: no longer pinned by their
  // claimed millimetres (the hits are still taken as independent of the pose).
  const ShiftResult assoc = update_with_hits_along_estimated_rays(Stage1Mode::kKnownLandmark, shift, true);
  RecordProperty("known_association_nees", std::to_string(assoc.nees));
  EXPECT_LT(assoc.nees, 11.3);
  EXPECT_LT(assoc.error_along, known.error_along);
}

/// A cloud that answers each ray with its point at the initial distance (the triangulated
/// point) moved by `offset`, or not at all.
class FakeCloud : public MapService {
 public:
  std::optional<MapDescription> description() override { return map; }
  MapReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs, DurationNs timeout,
                 bool want_normals) override {
    ++calls;
    last_timeout = timeout;
    asked_normals = want_normals;
    MapReply reply;
    reply.answered = answer;
    if (!answer) return reply;
    for (const voxel::RayQuery& r : rays) {
      const Eigen::Vector3f p = r.origin + r.direction.normalized() * r.initial_distance;
      reply.hits.push_back(
          {true, p + offset_every_other(reply.hits.size()), want_normals ? normal : Eigen::Vector3f::Zero()});
    }
    return reply;
  }
  Eigen::Vector3f offset_every_other(std::size_t i) const {
    return i % 2 == 1 || all_off ? offset : Eigen::Vector3f::Zero();
  }
  std::optional<MapDescription> map = indoor_map();
  bool answer = true;
  bool all_off = false;
  Eigen::Vector3f offset = Eigen::Vector3f::Zero();
  Eigen::Vector3f normal = Eigen::Vector3f::Zero();  ///< answered with every hit when asked
  int calls = 0;
  DurationNs last_timeout = 0;
  bool asked_normals = false;
};

struct StageScene {
  test::Scene s = test::make_scene();
  FeatureDatabase db;
  std::vector<FeatureId> ids;
  StageScene() {
    test::add_points(s.state, 20, 0.0, 6, &db);
    for (FeatureId id = 1; id <= 20; ++id) ids.push_back(id);
  }
};

TEST(MapStage, AcceptsConsistentAnswersAndRefusesInconsistentOnes) {
  StageScene sc;
  const io::Trajectory none;
  MapOptions o;
  const MapStage stage(o, TriangulationOptions{});
  FakeCloud cloud;
  MapFrameStats st;
  const auto points =
      stage.associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1), &st);
  EXPECT_EQ(points.size(), 20u);
  EXPECT_EQ(st.requests, 1);
  EXPECT_EQ(st.answered, 1);
  EXPECT_EQ(st.stage1_rays, 20);
  EXPECT_EQ(st.stage1_hits, 20);
  EXPECT_EQ(st.stage1_accepted, 20);
  EXPECT_EQ(st.bytes_up, 20u * 32u);
  EXPECT_EQ(st.bytes_down, 20u * 12u + 3u);  // points plus one hit bit per ray
  EXPECT_LE(cloud.last_timeout, from_seconds(o.query_timeout_ms * 1e-3));
  // Every other answer 5 cm across its ray: those are refused; at hit rate 0.5 the rule
  // (0.7) keeps the unmatched features, at 0.4 it drops them.
  cloud.offset = Eigen::Vector3f(0.0f, 0.0f, 0.05f);
  MapFrameStats half;
  EXPECT_EQ(
      stage.associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1), &half)
          .size(),
      10u);
  EXPECT_EQ(sc.ids.size(), 20u);
  o.drop_unmatched_hit_rate = 0.4;
  const MapStage dropping(o, TriangulationOptions{});
  MapFrameStats dropped;
  EXPECT_EQ(dropping
                .associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1),
                           &dropped)
                .size(),
            10u);
  EXPECT_EQ(dropped.stage1_dropped, 10);
  EXPECT_EQ(sc.ids.size(), 10u);
  // At most max_stage1_features rays.
  o.max_stage1_features = 4;
  MapFrameStats capped;
  MapStage(o, TriangulationOptions{})
      .associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1), &capped);
  EXPECT_EQ(capped.stage1_rays, 4);
}

TEST(MapStage, InPlaneModeCloudNormalsGiveEveryAcceptedHitItsPlane) {
  StageScene sc;
  const io::Trajectory none;
  MapOptions o;
  o.cloud_normals = true;  // asked only in plane mode
  FakeCloud cloud;
  cloud.normal = Eigen::Vector3f(0.0f, 0.6f, 0.8f);
  MapFrameStats st;
  SurfaceMap surfaces(0.5, 16);
  MapStage(o, TriangulationOptions{})
      .associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1), &st);
  EXPECT_FALSE(cloud.asked_normals);
  EXPECT_EQ(st.bytes_down, 20u * 12u + 3u);
  o.stage1_mode = "plane";
  const MapStage stage(o, TriangulationOptions{});
  EXPECT_EQ(stage.max_rays(), 176) << "200 x 44 B per frame with 6 B more per hit";
  MapFrameStats planes;
  const auto points = stage.associate(sc.s.state, sc.db, none, &sc.ids, cloud,
                                      Clock::now() + std::chrono::seconds(1), &planes, &surfaces);
  EXPECT_TRUE(cloud.asked_normals);
  EXPECT_EQ(planes.bytes_down, 20u * (12u + 6u) + 3u);
  ASSERT_EQ(points.size(), 20u);
  EXPECT_EQ(planes.stage1_planes, 20);
  for (const auto& [id, point] : points) {
    ASSERT_TRUE(point.plane.has_value()) << id;
    EXPECT_LT((point.plane->normal - Vec3d(0.0, 0.6, 0.8)).norm(), 1e-6);
    EXPECT_EQ(point.plane->centroid, point.p_w);
    EXPECT_EQ(point.plane->rms_m, o.plane_max_rms_m);
  }
  // Without a normal (not planar there) the edge's own fit decides: 20 scattered points
  // in an empty surface map give none.
  cloud.normal = Eigen::Vector3f::Zero();
  MapFrameStats none_planar;
  SurfaceMap empty(0.5, 16);
  stage.associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1),
                  &none_planar, &empty);
  EXPECT_EQ(none_planar.stage1_planes, 0);
}

TEST(MapStage, WithoutAnAnswerTheFrameGoesOnWithoutMapPoints) {
  StageScene sc;
  const io::Trajectory none;
  const MapStage stage(MapOptions{}, TriangulationOptions{});
  FakeCloud cloud;
  cloud.answer = false;
  MapFrameStats st;
  EXPECT_TRUE(
      stage.associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1), &st)
          .empty());
  EXPECT_EQ(st.timeouts, 1);
  EXPECT_EQ(st.answered, 0);
  EXPECT_EQ(sc.ids.size(), 20u);
  // Past the frame's deadline nothing is sent at all.
  cloud.answer = true;
  const int calls = cloud.calls;
  MapFrameStats late;
  EXPECT_TRUE(stage
                  .associate(sc.s.state, sc.db, none, &sc.ids, cloud,
                             Clock::now() - std::chrono::milliseconds(1), &late)
                  .empty());
  EXPECT_EQ(cloud.calls, calls);
  EXPECT_EQ(late.timeouts, 1);
  // No map description yet (cloud not heard from): nothing either.
  cloud.map.reset();
  MapFrameStats unknown;
  EXPECT_TRUE(stage
                  .associate(sc.s.state, sc.db, none, &sc.ids, cloud, Clock::now() + std::chrono::seconds(1),
                             &unknown)
                  .empty());
  EXPECT_FALSE(unknown.available);
}

TEST(MapStage, RegistersAcceptedHitsAsStatePointsWithTheMapVariance) {
  StageScene sc;
  const io::Trajectory none;
  MapOptions o;
  const MapStage stage(o, TriangulationOptions{});
  FakeCloud cloud;
  cloud.offset = Eigen::Vector3f(0.0f, 0.0f, 0.05f);  // every other one inconsistent
  RegisteredMap grid(o.registered_voxel_m, o.registered_per_voxel);
  const int dim = sc.s.state.dim();
  MapFrameStats st;
  const auto added = stage.register_new(sc.s.state, sc.db, none, 1000, &grid, cloud,
                                        Clock::now() + std::chrono::seconds(1), &st);
  ASSERT_FALSE(added.empty());
  EXPECT_LE(added.size(), 10u);
  EXPECT_EQ(st.registration_rays, 20);
  EXPECT_EQ(grid.size(), added.size());
  EXPECT_EQ(sc.s.state.dim(), dim + 3 * static_cast<int>(added.size()));
  for (FeatureId id : added) {
    EXPECT_EQ(id % 2, 1u) << "a consistent ray (even index, odd id)";
    const PointState& p = sc.s.state.points.at(id);
    EXPECT_TRUE(p.from_map);
    const double var = map_point_variance(
        o, make_feature_ray(sc.s.state, {}, *sc.db.find(id), p.p_w, indoor_map(), o)->ray.resolution);
    EXPECT_NEAR(sc.s.state.P(p.slot.offset, p.slot.offset), var, 1e-12);
    EXPECT_EQ(sc.s.state.P.block(p.slot.offset, 0, 3, p.slot.offset).norm(),
              0.0);  // independent of the state
  }
  // All are seen at the newest clone: all suitable for stage 2.
  EXPECT_EQ(stage.suitable(sc.s.state, sc.db, grid, 6000).size(), added.size());
  EXPECT_TRUE(stage.suitable(sc.s.state, sc.db, grid, 99999).empty());
}

TEST(MapStage, RegistrationAsksOnlyForTheRoomTheStateHasLeft) {
  StageScene sc;
  const io::Trajectory none;
  MapOptions o;
  const MapStage stage(o, TriangulationOptions{});
  FakeCloud cloud;
  RegisteredMap grid(o.registered_voxel_m, o.registered_per_voxel);
  const int max_slam = sc.s.state.options().max_slam;
  for (FeatureId id = 1000; static_cast<int>(sc.s.state.points.size()) < max_slam - 3; ++id) {
    PointState p;
    p.slot = sc.s.state.append(3);
    sc.s.state.points.emplace(id, p);
  }
  MapFrameStats st;
  const auto added = stage.register_new(sc.s.state, sc.db, none, 1000, &grid, cloud,
                                        Clock::now() + std::chrono::seconds(1), &st);
  EXPECT_EQ(st.registration_rays, 6);  // twice the room of 3, of the 20 candidates
  EXPECT_EQ(st.registration_hits, 6);  // every hit counted, also those without room
  EXPECT_EQ(added.size(), 3u);
  EXPECT_EQ(static_cast<int>(sc.s.state.points.size()), max_slam);
  // Full: no request at all.
  const int calls = cloud.calls;
  MapFrameStats full;
  EXPECT_TRUE(stage
                  .register_new(sc.s.state, sc.db, none, 1000, &grid, cloud,
                                Clock::now() + std::chrono::seconds(1), &full)
                  .empty());
  EXPECT_EQ(cloud.calls, calls);
  EXPECT_EQ(full.registration_rays, 0);
  EXPECT_EQ(full.requests, 0);
}

// ---- The two-stage update in process on a generated sequence ----

test::SyntheticOptions mapped(double duration_s) {
  test::SyntheticOptions so;
  so.duration_s = duration_s;
  so.map_spacing_m = 0.015;
  so.preset = "realistic";
  so.drift_px = 0.05;  // KLT-like drift: plain VIO drifts, the map holds it
  return so;
}

/// config/euroc.yaml with deadlines no loaded test machine reaches (results must not depend
/// on timing).
EstimatorOptions untimed_options() {
  EstimatorOptions o = test::euroc_estimator_options();
  o.map.frame_budget_ms = o.map.query_timeout_ms = 10000.0;
  return o;
}

TEST(TwoStageUpdate, TheMapCorrectsTheAlignmentErrorThatPlainVioKeeps) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(mapped(20.0));
  ASSERT_NE(seq, nullptr);
  auto map = test::LocalMapService::create(*seq);
  ASSERT_NE(map, nullptr);
  EstimatorOptions o = untimed_options();
  o.alignment.translation_noise_mean_m = 0.08;  // a poor global pose at the start
  o.alignment.translation_noise_sd_m = 0.0;
  const auto plain = test::run_estimator(*seq, o);
  std::vector<FrameOutput> outs;
  const auto with_map = test::run_estimator(*seq, o, nullptr, map.get(), &outs);
  ASSERT_EQ(with_map.size(), plain.size());
  const double e_plain = test::ate_rmse(*seq, plain, false), e_map = test::ate_rmse(*seq, with_map, false);
  RecordProperty("ate_plain_m", std::to_string(e_plain));
  RecordProperty("ate_map_m", std::to_string(e_map));
  EXPECT_GT(e_plain, 0.05);
  EXPECT_LT(e_map, 0.5 * e_plain) << "plain " << e_plain << " map " << e_map;
  int accepted = 0, registered = 0, rays_max = 0;
  for (const FrameOutput& f : outs) {
    accepted += f.map.stage1_accepted;
    registered += f.map.registered;
    rays_max = std::max(rays_max, f.map.stage1_rays + f.map.registration_rays);
    EXPECT_EQ(f.map.timeouts, 0);
  }
  EXPECT_GT(accepted, 0);
  EXPECT_GT(registered, 0);
  EXPECT_LE(rays_max, o.map.max_rays_per_frame);
  // Rays from the ground-truth poses (the paper's "w/ GT" rows) do at least as well.
  o.map.query_pose_source = "gt";
  const auto with_gt = test::run_estimator(*seq, o, nullptr, map.get());
  ASSERT_EQ(with_gt.size(), plain.size());
  const double e_gt = test::ate_rmse(*seq, with_gt, false);
  RecordProperty("ate_gt_queries_m", std::to_string(e_gt));
  EXPECT_LT(e_gt, 0.5 * e_plain) << "plain " << e_plain << " w/ GT " << e_gt;
  // Stage 1 on the map surfaces' normals (stage1_mode plane) corrects it too.
  o.map.query_pose_source = "estimated";
  o.map.stage1_mode = "plane";
  outs.clear();
  const auto with_planes = test::run_estimator(*seq, o, nullptr, map.get(), &outs);
  ASSERT_EQ(with_planes.size(), plain.size());
  const double e_plane = test::ate_rmse(*seq, with_planes, false);
  RecordProperty("ate_plane_m", std::to_string(e_plane));
  int planes = 0;
  accepted = 0;
  for (const FrameOutput& f : outs) accepted += f.map.stage1_accepted, planes += f.map.stage1_planes;
  RecordProperty("plane_points", std::to_string(planes) + " of " + std::to_string(accepted));
  EXPECT_GT(planes, 0);
  EXPECT_LE(planes, accepted);
  EXPECT_LT(e_plane, 0.5 * e_plain) << "plain " << e_plain << " plane " << e_plane;
  // With the cloud's surface normals every accepted hit on a plane has one.
  o.map.cloud_normals = true;
  outs.clear();
  const auto with_normals = test::run_estimator(*seq, o, nullptr, map.get(), &outs);
  ASSERT_EQ(with_normals.size(), plain.size());
  const double e_normals = test::ate_rmse(*seq, with_normals, false);
  RecordProperty("ate_cloud_normals_m", std::to_string(e_normals));
  int cloud_planes = 0;
  for (const FrameOutput& f : outs) cloud_planes += f.map.stage1_planes;
  RecordProperty("cloud_normal_planes", std::to_string(cloud_planes));
  EXPECT_GT(cloud_planes, planes);
  // Indoors the normal's neighbourhood is 6 voxels of the 0.03 m level (0.18 m), noisier
  // than the 1 m it has outdoors: the indoor bar of the issue, 0.6x (measured 0.53x).
  EXPECT_LT(e_normals, 0.6 * e_plain) << "plain " << e_plain << " cloud normals " << e_normals;
}

TEST(TwoStageUpdate, ASilentCloudGivesPlainVio) {
  const test::SyntheticSequence* seq = test::synthetic_sequence(mapped(20.0));
  ASSERT_NE(seq, nullptr);
  auto map = test::LocalMapService::create(*seq);
  ASSERT_NE(map, nullptr);
  const EstimatorOptions o = untimed_options();
  const auto plain = test::run_estimator(*seq, o);
  const auto same_as_plain = [&](const io::Trajectory& t) {
    ASSERT_EQ(t.size(), plain.size());
    for (std::size_t i = 0; i < plain.size(); ++i) {
      ASSERT_EQ(t[i].t_ns, plain[i].t_ns);
      ASSERT_LT((t[i].T_w_b.translation() - plain[i].T_w_b.translation()).norm(), 1e-9) << i;
    }
  };
  // Known map, no answers: every request times out and the frame goes on as plain VIO.
  map->answer = false;
  std::vector<FrameOutput> outs;
  same_as_plain(test::run_estimator(*seq, o, nullptr, map.get(), &outs));
  int timeouts = 0, requests = 0, asking = 0, accepted = 0;
  for (const FrameOutput& f : outs) {
    timeouts += f.map.timeouts, requests += f.map.requests, accepted += f.map.stage1_accepted;
    asking += f.map.requests > 0;
  }
  EXPECT_EQ(timeouts, requests);
  EXPECT_GT(asking, static_cast<int>(outs.size()) / 4);  // most frames have rays to ask (measured 49 %)
  EXPECT_EQ(accepted, 0);
  EXPECT_GT(map->queries, 0);
  // A cloud never heard from: nothing is sent.
  map->announced = false;
  map->queries = 0;
  same_as_plain(test::run_estimator(*seq, o, nullptr, map.get()));
  EXPECT_EQ(map->queries, 0);
}

}  // namespace
}  // namespace mrvs::edge
