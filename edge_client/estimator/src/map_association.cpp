#include "mrvs/edge/map_association.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "mrvs/edge/camera_measurement.h"
#include "mrvs/edge/global_alignment.h"
#include "mrvs/edge/state_helper.h"
#include "mrvs/voxel/resolution.h"

namespace mrvs::edge {

std::optional<SE3d> query_camera_pose(const State& state, const io::Trajectory& groundtruth,
                                      const MapOptions& o, TimestampNs t_ns, int cam) {
  const SE3d& T_b_c = state.cams[static_cast<std::size_t>(cam)].T_b_c;
  if (o.query_pose_source == "gt") {
    const auto T = interpolate_trajectory(groundtruth, t_ns + from_seconds(state.time_offset_s));
    if (!T.ok()) return std::nullopt;
    return *T * T_b_c;
  }
  const auto it = state.clones.find(t_ns);
  if (it == state.clones.end()) return std::nullopt;
  return it->second.T_w_b * T_b_c;
}

Mat3d hit_covariance_across(const State& state, const RayAnchor& anchor) {
  const std::optional<AnchorJacobian> aj = anchor_jacobian(state, anchor);
  if (!aj) return Mat3d::Zero();
  return aj->J * marginal_covariance(state, aj->vars) * aj->J.transpose();
}

double hit_sigma_across(const State& state, const RayAnchor& anchor) {
  const Eigen::SelfAdjointEigenSolver<Mat3d> eig(hit_covariance_across(state, anchor),
                                                 Eigen::EigenvaluesOnly);
  return std::sqrt(std::max(eig.eigenvalues()(2), 0.0));
}

std::optional<FeatureRay> make_feature_ray(const State& state, const io::Trajectory& gt,
                                           const FeatureTrack& track, const Vec3d& p_tri,
                                           const MapDescription& map, const MapOptions& o) {
  const auto obs = std::find_if(track.obs.rbegin(), track.obs.rend(), [&](const CameraObservation& c) {
    return c.cam == 0 && state.clones.count(c.t_ns) != 0;
  });
  if (obs == track.obs.rend()) return std::nullopt;
  const auto T_w_c = query_camera_pose(state, gt, o, obs->t_ns, 0);
  if (!T_w_c) return std::nullopt;
  const Vec3d p_c = T_w_c->inverse() * p_tri;
  if (!(p_c.z() > 0.05)) return std::nullopt;
  FeatureRay out;
  out.id = track.id;
  out.p_tri = p_tri;
  out.t_ns = obs->t_ns;
  out.cam = 0;
  out.depth_m = p_c.z();
  const auto& model = *state.cams[0].model;
  out.focal_px = 0.5 * (model.fx() + model.fy());
  double r = o.fixed_resolution_m;
  if (r <= 0.0) {
    auto level = voxel::select_level(map.resolutions, o.footprint_scale * out.depth_m, out.focal_px);
    if (!level) return std::nullopt;
    double need = o.min_resolution_m;
    if (o.uncertainty_scale > 0.0 && o.query_pose_source != "gt")
      need = std::max(need, o.uncertainty_scale * hit_sigma_across(state, RayAnchor{obs->t_ns, 0, p_c}));
    while (*level + 1 < map.resolutions.size() && map.resolutions[*level] < need - 1e-9) ++*level;
    r = map.resolutions[*level];
  }
  const Vec3d c = T_w_c->translation();
  const Vec3d v = (T_w_c->rotation_matrix() * Vec3d(obs->xn.x(), obs->xn.y(), 1.0)).normalized();
  out.ray.origin = (c - map.origin).cast<float>();
  out.ray.direction = v.cast<float>();
  out.ray.initial_distance = static_cast<float>((p_tri - c).norm());
  out.ray.resolution = static_cast<float>(r);
  return out;
}

bool accept_hit(const State& state, const io::Trajectory& gt, const FeatureTrack& track,
                const FeatureRay& ray, const Vec3d& X, const MapOptions& o, double* mean_error_px) {
  if ((X - ray.p_tri).norm() > o.max_hit_distance_m) return false;
  double sum = 0.0;
  int n = 0;
  for (const CameraObservation& obs : track.obs) {
    if (obs.t_ns == ray.t_ns && obs.cam == ray.cam) continue;
    const auto T_w_c = query_camera_pose(state, gt, o, obs.t_ns, obs.cam);
    if (!T_w_c) continue;
    const auto& model = *state.cams[static_cast<std::size_t>(obs.cam)].model;
    const auto uv = model.project(T_w_c->inverse() * X, nullptr, 0.05);
    if (!uv) continue;
    sum += (*uv - obs.uv).norm();
    ++n;
  }
  if (n == 0) return false;
  const double mean = sum / n;
  if (mean_error_px != nullptr) *mean_error_px = mean;
  const auto T_w_c = query_camera_pose(state, gt, o, ray.t_ns, ray.cam);
  const double z = T_w_c ? (T_w_c->inverse() * X).z() : ray.depth_m;
  const double thr =
      std::clamp(ray.ray.resolution * ray.focal_px / std::max(z, 0.05) + o.threshold_offset_px - 0.5,
                 o.threshold_lower_px, o.threshold_upper_px);
  return mean < thr;
}

std::optional<RayAnchor> ray_anchor(const State& state, const FeatureTrack& track, const FeatureRay& ray,
                                    const Vec3d& X) {
  if (state.clones.count(ray.t_ns) == 0) return std::nullopt;
  const auto obs = std::find_if(track.obs.begin(), track.obs.end(), [&](const CameraObservation& c) {
    return c.t_ns == ray.t_ns && c.cam == ray.cam;
  });
  if (obs == track.obs.end()) return std::nullopt;
  const double z = (state.T_w_c(ray.t_ns, ray.cam).inverse() * X).z();
  if (!(z > 0.05)) return std::nullopt;
  return RayAnchor{ray.t_ns, ray.cam, z * Vec3d(obs->xn.x(), obs->xn.y(), 1.0)};
}

}  // namespace mrvs::edge
