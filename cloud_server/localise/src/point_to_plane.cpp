#include "point_to_plane.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace mrvs::localise {
namespace {

using Row4 = Eigen::Matrix<double, 1, 4>;

/// Directions with less than this share of the strongest one's information are not moved along.
constexpr double kDegenerate = 1e-4;

struct Linearised {
  Eigen::Matrix4d H = Eigen::Matrix4d::Zero();  ///< weighted
  Eigen::Vector4d b = Eigen::Vector4d::Zero();
  Eigen::Matrix4d information = Eigen::Matrix4d::Zero();  ///< unweighted, inliers only
  double sum_r2 = 0.0;
  double structure = 0.0;  ///< sum of |n_xy| over the inliers with a normal
  int used = 0;            ///< residuals in H
  int with_normal = 0;     ///< inliers with a normal
  int inliers = 0;
};

/// Where each point's nearest map point can be, from one iteration to the next: at the last
/// placement it was `distance` away (infinite: none within the search radius); after a move of
/// the pose by d_anchor and d_yaw, that map point lies at most distance + |d_anchor| +
/// |d_yaw| |p_xy| from the point, so the nearest one does too, and the search stops there.
/// Exact: the same neighbour is found as by an unbounded search.
struct NeighbourBounds {
  std::vector<float> distance;
  double moved_m = INFINITY;     ///< |d_anchor| since the last placement
  double turned_rad = INFINITY;  ///< |d_yaw| since then
  float radius(std::size_t i, const Eigen::Vector3d& p, float max_radius) const {
    if (i >= distance.size() || !std::isfinite(distance[i])) return max_radius;
    const double r = distance[i] + moved_m + turned_rad * p.head<2>().norm() + 1e-4;
    return std::min(max_radius, static_cast<float>(r));
  }
};

/// evidence, matched: when given, filled with each point's structure weight and inlier match
/// (FineResult::evidence, FineResult::matched).
Linearised linearise(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points, double yaw,
                     const Eigen::Vector3d& anchor, double max_distance, const FineOptions& o,
                     NeighbourBounds* bounds, std::vector<float>* evidence = nullptr,
                     std::vector<std::int32_t>* matched = nullptr) {
  Linearised L;
  const double reach = o.inlier_m + o.voxel_m;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  if (evidence) evidence->assign(points.size(), 0.0f);
  if (matched) matched->assign(points.size(), -1);
  const float max_radius = static_cast<float>(std::max(max_distance, reach));
  std::vector<float> found(points.size(), INFINITY);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    const Eigen::Vector3d x = R * p + anchor;
    const auto nb = surface.nearest(x.cast<float>(), bounds->radius(i, p, max_radius));
    if (nb) found[i] = nb->distance_m;
    if (!nb) continue;
    const Eigen::Vector3d n = surface.normal(nb->index).cast<double>();
    const bool planar = n.squaredNorm() > 0.5;
    const double r = planar ? n.dot(x - surface.point(nb->index).cast<double>()) : 0.0;
    const bool inlier =
        planar ? nb->distance_m <= reach && std::abs(r) <= o.inlier_m : nb->distance_m <= o.inlier_m;
    L.inliers += inlier;
    if (matched && inlier) (*matched)[i] = static_cast<std::int32_t>(nb->index);
    if (!planar || nb->distance_m > max_distance) continue;
    Row4 J;
    J.head<3>() = n.transpose();
    J(3) = n.dot(Eigen::Vector3d::UnitZ().cross(x - anchor));
    const double w = std::abs(r) <= o.huber_m ? 1.0 : o.huber_m / std::abs(r);
    L.H.noalias() += w * J.transpose() * J;
    L.b.noalias() += w * J.transpose() * r;
    ++L.used;
    if (!inlier) continue;
    L.information.noalias() += J.transpose() * J;
    L.sum_r2 += r * r;
    L.structure += n.head<2>().norm();
    if (evidence) (*evidence)[i] = static_cast<float>(n.head<2>().norm());
    ++L.with_normal;
  }
  bounds->distance = std::move(found);
  bounds->moved_m = bounds->turned_rad = 0.0;
  return L;
}

}  // namespace

FineResult refine_pose(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points, double yaw,
                       const Eigen::Vector3d& anchor, const FineOptions& o) {
  FineResult out;
  out.yaw = yaw;
  out.anchor = anchor;
  const int n = std::max(0, o.iterations);  // 0: only evaluate the start
  NeighbourBounds bounds;
  for (int it = 0; it < n; ++it) {
    // A start off by more than the end distance along a weakly held direction (the height, held
    // by the few points on floors and tables) walks there in steps of a few cm: the iterations
    // at the end distance go on until the steps stop, not for a fixed count.
    const double s = o.ramp_iterations > 0 ? std::min(1.0, static_cast<double>(it) / o.ramp_iterations) : 1.0;
    const double dist = o.start_distance_m + s * (o.end_distance_m - o.start_distance_m);
    const Linearised L = linearise(surface, points, out.yaw, out.anchor, dist, o, &bounds);
    if (L.used < 4) break;
    // No step along directions the submap does not constrain (a wall leaves two free): they
    // keep the start's value (solution remapping, Zhang et al., ICRA 2016).
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(L.H);
    const Eigen::Vector4d lambda = eig.eigenvalues();
    Eigen::Vector4d dx = Eigen::Vector4d::Zero();
    for (int k = 0; k < 4; ++k) {
      if (lambda(k) <= kDegenerate * lambda(3)) continue;
      const Eigen::Vector4d v = eig.eigenvectors().col(k);
      dx -= v * (v.dot(L.b) / lambda(k));
    }
    if (!dx.allFinite()) break;
    out.anchor += dx.head<3>();
    out.yaw += dx(3);
    bounds.moved_m = dx.head<3>().norm();
    bounds.turned_rad = std::abs(dx(3));
    out.iterations = it + 1;
    if (s >= 1.0 && dx.head<3>().norm() < o.converged_m && std::abs(dx(3)) < o.converged_rad) break;
  }
  const Linearised L = linearise(surface, points, out.yaw, out.anchor, o.end_distance_m, o, &bounds,
                                 &out.evidence, &out.matched);
  out.information = L.information;
  out.inliers = L.inliers;
  out.fitness = points.empty() ? 0.0 : static_cast<double>(L.inliers) / static_cast<double>(points.size());
  out.structure = points.empty() ? 0.0 : L.structure / static_cast<double>(points.size());
  out.rmse_m = L.with_normal > 0 ? std::sqrt(L.sum_r2 / L.with_normal) : 0.0;
  return out;
}

}  // namespace mrvs::localise
