#include "plane_fit.h"

#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace mrvs::map::detail {

void gather_neighbourhood(const LevelIndex& index, const Eigen::Vector3i& voxel, Neighbourhood* out) {
  out->count = 0;
  // The 27 voxels fall in at most 8 bricks: remember the last brick looked up.
  Eigen::Vector3i cached_brick(0, 0, 0);
  std::uint32_t cached = kNoBrick;
  bool have_cache = false;
  for (int dz = -1; dz <= 1; ++dz) {
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Eigen::Vector3i q = voxel + Eigen::Vector3i(dx, dy, dz);
        const Eigen::Vector3i b(brick_of(q.x()), brick_of(q.y()), brick_of(q.z()));
        if (!have_cache || b != cached_brick) {
          cached = index.find_brick(b.x(), b.y(), b.z());
          cached_brick = b;
          have_cache = true;
        }
        if (cached == kNoBrick) continue;
        const int bit = bit_of(q.x(), q.y(), q.z());
        const BrickMask& mask = index.mask(cached);
        if (!mask.test(bit)) continue;
        out->points[out->count++] = index.position(index.base(cached) + mask.rank(bit)).cast<double>();
      }
    }
  }
}

void gather_ball(const LevelIndex& index, const Eigen::Vector3d& centre, double radius_m,
                 std::vector<Eigen::Vector3d>* out) {
  const double r = index.resolution();
  const Eigen::Vector3i lo = ((centre.array() - radius_m) / r).floor().cast<int>();
  const Eigen::Vector3i hi = ((centre.array() + radius_m) / r).floor().cast<int>();
  const double r2 = radius_m * radius_m;
  for (int z = lo.z(); z <= hi.z(); ++z) {
    for (int y = lo.y(); y <= hi.y(); ++y) {
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const std::uint32_t sorted = index.find_voxel(x, y, z);
        if (sorted == kNoBrick) continue;
        const Eigen::Vector3d p = index.position(sorted).cast<double>();
        if ((p - centre).squaredNorm() <= r2) out->push_back(p);
      }
    }
  }
}

namespace {

/// Kasa fit of x^2 + y^2 + D x + E y + F = 0 to the points projected on (u, w) around c.
/// Returns (centre_u, centre_w, radius) or nullopt.
std::optional<Eigen::Vector3d> kasa_circle(const Neighbourhood& n, const Eigen::Vector3d& c,
                                           const Eigen::Vector3d& u, const Eigen::Vector3d& w) {
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (int i = 0; i < n.count; ++i) {
    const Eigen::Vector3d d = n.points[i] - c;
    const Eigen::Vector3d row(u.dot(d), w.dot(d), 1.0);
    normal.noalias() += row * row.transpose();
    rhs += row * -(row.x() * row.x() + row.y() * row.y());
  }
  const Eigen::Vector3d def = normal.ldlt().solve(rhs);
  if (!def.allFinite()) return std::nullopt;
  const double cu = -0.5 * def.x();
  const double cw = -0.5 * def.y();
  const double radius_sq = cu * cu + cw * cw - def.z();
  if (!(radius_sq > 0.0)) return std::nullopt;
  const double radius = std::sqrt(radius_sq);
  if (!(radius <= 10.0)) return std::nullopt;
  return Eigen::Vector3d(cu, cw, radius);
}

}  // namespace

std::optional<Eigen::Vector3d> plane_circle_intersection(const Neighbourhood& n, const Eigen::Vector3d& o,
                                                         const Eigen::Vector3d& v, double min_planarity) {
  if (n.count < 4) return std::nullopt;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (int i = 0; i < n.count; ++i) centroid += n.points[i];
  centroid /= n.count;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n.count; ++i) {
    const Eigen::Vector3d d = n.points[i] - centroid;
    cov.noalias() += d * d.transpose();
  }
  cov /= n.count;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  if (eig.info() != Eigen::Success) return std::nullopt;
  // Eigen sorts eigenvalues ascending: lambda3 = [0] (normal), lambda1 = [2].
  const double s1 = std::sqrt(std::abs(eig.eigenvalues()[2]));
  const double s2 = std::sqrt(std::abs(eig.eigenvalues()[1]));
  const double s3 = std::sqrt(std::abs(eig.eigenvalues()[0]));
  if (!std::isfinite(s1) || s1 < 1e-8) return std::nullopt;
  const double planarity = (s2 - s3) / s1;
  if (!(planarity >= min_planarity)) return std::nullopt;
  Eigen::Vector3d normal = eig.eigenvectors().col(0).normalized();

  // In-plane basis: u = n x e_x (n x e_y when n is close to e_x), w = n x u.
  const Eigen::Vector3d u = (std::abs(normal.x()) < 0.9 ? normal.cross(Eigen::Vector3d::UnitX())
                                                        : normal.cross(Eigen::Vector3d::UnitY()))
                                .normalized();
  const Eigen::Vector3d w = normal.cross(u).normalized();
  const std::optional<Eigen::Vector3d> circle = kasa_circle(n, centroid, u, w);
  if (!circle) return std::nullopt;

  if (normal.dot(v) < 0.0) normal = -normal;
  const double nv = normal.dot(v);
  if (!(std::abs(nv) >= 1e-6)) return std::nullopt;
  const double t = normal.dot(centroid - o) / nv;
  if (!(t >= 0.0)) return std::nullopt;
  const Eigen::Vector3d x = o + t * v;
  const Eigen::Vector3d centre = centroid + circle->x() * u + circle->y() * w;
  if (!((x - centre).norm() <= circle->z())) return std::nullopt;
  return x;
}

}  // namespace mrvs::map::detail
