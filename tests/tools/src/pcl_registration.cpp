#include "mrvs/tools/pcl_registration.h"

#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <pcl/features/fpfh.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/filter.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/ndt.h>
#include <pcl/registration/sample_consensus_prerejective.h>
#include <pcl/search/kdtree.h>
#include <Eigen/Geometry>

namespace mrvs::tools {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;
using NormalCloud = pcl::PointCloud<pcl::PointNormal>;
using Features = pcl::PointCloud<pcl::FPFHSignature33>;

struct PclMap::Impl {
  PclOptions o;
  Cloud::Ptr target{new Cloud};
  NormalCloud::Ptr target_normals{new NormalCloud};
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
  pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
  pcl::IterativeClosestPointWithNormals<pcl::PointNormal, pcl::PointNormal> icp_n;
  Cloud::Ptr feature_points{new Cloud};
  Features::Ptr features{new Features};
  pcl::SampleConsensusPrerejective<pcl::PointXYZ, pcl::PointXYZ, pcl::FPFHSignature33> sac;
  bool with_features = false;
  double setup_s = 0.0;
};

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Cloud::Ptr to_cloud(const std::vector<Eigen::Vector3d>& points) {
  Cloud::Ptr c(new Cloud);
  c->reserve(points.size());
  for (const auto& p : points) c->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  return c;
}

Cloud::Ptr voxel_thin(const Cloud::ConstPtr& in, double cell) {
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(in);
  grid.setLeafSize(cell, cell, cell);
  Cloud::Ptr out(new Cloud);
  grid.filter(*out);
  return out;
}

/// Normals within radius (oriented towards viewpoint); points without a valid normal dropped.
NormalCloud::Ptr with_normals(const Cloud::ConstPtr& in, double radius, const Eigen::Vector3d& viewpoint) {
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> ne;
  pcl::search::KdTree<pcl::PointXYZ>::Ptr tree(new pcl::search::KdTree<pcl::PointXYZ>);
  ne.setInputCloud(in);
  ne.setSearchMethod(tree);
  ne.setRadiusSearch(radius);
  ne.setViewPoint(viewpoint.x(), viewpoint.y(), viewpoint.z());
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);
  NormalCloud::Ptr out(new NormalCloud);
  for (std::size_t i = 0; i < in->size(); ++i) {
    const pcl::Normal& n = normals[i];
    if (!std::isfinite(n.normal_x) || !std::isfinite(n.normal_y) || !std::isfinite(n.normal_z)) continue;
    pcl::PointNormal p;
    p.x = (*in)[i].x;
    p.y = (*in)[i].y;
    p.z = (*in)[i].z;
    p.normal_x = n.normal_x;
    p.normal_y = n.normal_y;
    p.normal_z = n.normal_z;
    p.curvature = n.curvature;
    out->push_back(p);
  }
  return out;
}

Cloud::Ptr xyz_of(const NormalCloud& in) {
  Cloud::Ptr c(new Cloud);
  for (const auto& p : in) c->push_back(pcl::PointXYZ(p.x, p.y, p.z));
  return c;
}

Features::Ptr fpfh(const NormalCloud::ConstPtr& points, double radius) {
  pcl::FPFHEstimation<pcl::PointNormal, pcl::PointNormal, pcl::FPFHSignature33> est;
  pcl::search::KdTree<pcl::PointNormal>::Ptr tree(new pcl::search::KdTree<pcl::PointNormal>);
  est.setInputCloud(points);
  est.setInputNormals(points);
  est.setSearchMethod(tree);
  est.setRadiusSearch(radius);
  Features::Ptr f(new Features);
  est.compute(*f);
  return f;
}

double fitness(const PclMap::Impl& m, const Cloud& source, const Eigen::Matrix4d& M) {
  if (source.empty()) return 0.0;
  const Eigen::Matrix4f Mf = M.cast<float>();
  std::vector<int> idx(1);
  std::vector<float> d2(1);
  int in = 0;
  const float r2 = static_cast<float>(m.o.inlier_m * m.o.inlier_m);
  for (const auto& p : source) {
    const Eigen::Vector4f q = Mf * Eigen::Vector4f(p.x, p.y, p.z, 1.0f);
    if (m.tree.nearestKSearch(pcl::PointXYZ(q.x(), q.y(), q.z()), 1, idx, d2) == 1 && d2[0] <= r2) ++in;
  }
  return static_cast<double>(in) / static_cast<double>(source.size());
}

Status build_features(PclMap::Impl& m, const Eigen::Vector3d& centre) {
  const NormalCloud::Ptr thinned =
      with_normals(voxel_thin(m.target, m.o.voxel_m), m.o.normal_radius_m, centre);
  m.feature_points = xyz_of(*thinned);
  m.features = fpfh(thinned, m.o.fpfh_radius_m);
  if (m.features->empty()) return absl::FailedPreconditionError("pcl: the map has no FPFH features");
  m.sac.setInputTarget(m.feature_points);
  m.sac.setTargetFeatures(m.features);
  m.sac.setMaximumIterations(m.o.sac_iterations);
  m.sac.setNumberOfSamples(3);
  m.sac.setCorrespondenceRandomness(m.o.sac_randomness);
  m.sac.setSimilarityThreshold(static_cast<float>(m.o.sac_similarity));
  m.sac.setMaxCorrespondenceDistance(2.0 * m.o.voxel_m);
  m.sac.setInlierFraction(static_cast<float>(m.o.sac_inlier_fraction));
  return Status();
}

}  // namespace

const char* pcl_method_name(PclMethod m) {
  switch (m) {
    case PclMethod::kGicp:
      return "gicp";
    case PclMethod::kNdt:
      return "ndt";
    case PclMethod::kPointToPlane:
      return "point_to_plane";
    case PclMethod::kFpfhSac:
      return "fpfh_sac";
  }
  return "?";
}

std::optional<PclMethod> pcl_method_from_name(const std::string& name) {
  for (PclMethod m : {PclMethod::kGicp, PclMethod::kNdt, PclMethod::kPointToPlane, PclMethod::kFpfhSac}) {
    if (name == pcl_method_name(m)) return m;
  }
  return std::nullopt;
}

AlignedSubmap align_submap(const localisation::Request& q, const PclOptions& o) {
  AlignedSubmap s;
  s.R_g = Eigen::Quaterniond::FromTwoVectors(q.gravity_o.normalized(), -Eigen::Vector3d::UnitZ())
              .toRotationMatrix();
  std::vector<Eigen::Vector3d> aligned;
  for (const auto& p : q.points) aligned.push_back(s.R_g * p.cast<double>());
  const Cloud::Ptr thinned = voxel_thin(to_cloud(aligned), o.voxel_m);
  const std::size_t n = thinned->size(), k = std::min<std::size_t>(n, static_cast<std::size_t>(o.max_points));
  for (std::size_t i = 0; i < k; ++i) {
    const auto& p = (*thinned)[i * n / k];
    s.points.emplace_back(p.x, p.y, p.z);
  }
  double views = 0.0;
  for (const auto& v : q.viewpoints) {
    s.viewpoint += v.count * (s.R_g * v.position.cast<double>());
    views += v.count;
  }
  if (views > 0) s.viewpoint /= views;
  return s;
}

SE3d T_m_o_from(const Eigen::Matrix4d& M, const AlignedSubmap& s, const localisation::Request& q,
                const Vec3d& map_origin) {
  const Eigen::Matrix3d R = M.topLeftCorner<3, 3>() * s.R_g;
  const Eigen::Quaterniond qr = Eigen::Quaterniond(R).normalized();
  return SE3d(qr, M.topRightCorner<3, 1>() + map_origin - qr.toRotationMatrix() * q.anchor_o);
}

Eigen::Matrix4d M_from(const SE3d& T_m_o, const AlignedSubmap& s, const localisation::Request& q,
                       const Vec3d& map_origin) {
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  M.topLeftCorner<3, 3>() = T_m_o.rotation_matrix() * s.R_g.transpose();
  M.topRightCorner<3, 1>() = T_m_o * q.anchor_o - map_origin;
  return M;
}

StatusOr<PclMap> PclMap::build(const map::VoxelMap& map, const PclOptions& o, bool with_features) {
  const int level = map.level_of(o.map_level_m);
  if (level < 0) {
    return absl::InvalidArgumentError(fmt::format("pcl: {} m is not a level of the map (levels: {} m)",
                                                  o.map_level_m, fmt::join(map.resolutions(), ", ")));
  }
  const auto t0 = Clock::now();
  auto m = std::make_shared<Impl>();
  m->o = o;
  Eigen::AlignedBox3d box;
  for (const auto& p : map.levels[static_cast<std::size_t>(level)].points) {
    m->target->push_back(pcl::PointXYZ(p.position.x(), p.position.y(), p.position.z()));
    box.extend(p.position.cast<double>());
  }
  if (m->target->size() < 10)
    return absl::FailedPreconditionError("pcl: the map level has fewer than 10 points");
  m->tree.setInputCloud(m->target);
  m->gicp.setInputTarget(m->target);
  m->gicp.setMaxCorrespondenceDistance(o.max_correspondence_m);
  m->gicp.setMaximumIterations(o.iterations);
  m->ndt.setInputTarget(m->target);
  m->ndt.setResolution(static_cast<float>(o.ndt_resolution_m));
  m->ndt.setStepSize(o.ndt_step_m);
  m->ndt.setTransformationEpsilon(1e-3);
  m->ndt.setMaximumIterations(o.iterations);
  m->target_normals = with_normals(m->target, o.normal_radius_m, box.center());
  m->icp_n.setInputTarget(m->target_normals);
  m->icp_n.setMaxCorrespondenceDistance(o.max_correspondence_m);
  m->icp_n.setMaximumIterations(o.iterations);
  m->icp_n.setTransformationEpsilon(1e-8);
  // GICP's target covariances are computed on its first alignment and kept: do it here.
  Cloud::Ptr probe(new Cloud);
  for (std::size_t i = 0; i < m->target->size() && probe->size() < 50; i += m->target->size() / 50 + 1)
    probe->push_back((*m->target)[i]);
  m->gicp.setInputSource(probe);
  Cloud warm;
  m->gicp.align(warm);
  if (with_features) MRVS_RETURN_IF_ERROR(build_features(*m, box.center()));
  m->with_features = with_features;
  m->setup_s = ms_since(t0) * 1e-3;
  PclMap out;
  out.impl_ = std::move(m);
  return out;
}

PclResult PclMap::register_fine(PclMethod method, const AlignedSubmap& s, const Eigen::Matrix4d& start) {
  Impl& m = *impl_;
  const auto t0 = Clock::now();
  const Cloud::Ptr source = to_cloud(s.points);
  const Eigen::Matrix4f guess = start.cast<float>();
  PclResult r;
  if (method == PclMethod::kGicp) {
    Cloud out;
    m.gicp.setInputSource(source);
    m.gicp.align(out, guess);
    r.converged = m.gicp.hasConverged();
    r.M = m.gicp.getFinalTransformation().cast<double>();
  } else if (method == PclMethod::kNdt) {
    Cloud out;
    m.ndt.setInputSource(source);
    m.ndt.align(out, guess);
    r.converged = m.ndt.hasConverged();
    r.M = m.ndt.getFinalTransformation().cast<double>();
  } else if (method == PclMethod::kPointToPlane) {
    NormalCloud out;
    m.icp_n.setInputSource(with_normals(source, m.o.normal_radius_m, s.viewpoint));
    m.icp_n.align(out, guess);
    r.converged = m.icp_n.hasConverged();
    r.M = m.icp_n.getFinalTransformation().cast<double>();
  } else {
    return register_global(s);
  }
  r.ms = ms_since(t0);
  r.fitness = fitness(m, *source, r.M);
  return r;
}

PclResult PclMap::register_global(const AlignedSubmap& s) {
  Impl& m = *impl_;
  PclResult r;
  if (!m.with_features) return r;
  const auto t0 = Clock::now();
  const NormalCloud::Ptr src = with_normals(to_cloud(s.points), m.o.normal_radius_m, s.viewpoint);
  const Cloud::Ptr src_xyz = xyz_of(*src);
  m.sac.setInputSource(src_xyz);
  m.sac.setSourceFeatures(fpfh(src, m.o.fpfh_radius_m));
  Cloud out;
  m.sac.align(out);
  const double sac_ms = ms_since(t0);
  if (!m.sac.hasConverged()) {
    r.ms = sac_ms;
    return r;
  }
  r = register_fine(PclMethod::kGicp, s, m.sac.getFinalTransformation().cast<double>());
  r.ms += sac_ms;
  return r;
}

double PclMap::setup_s() const { return impl_->setup_s; }

}  // namespace mrvs::tools
