#include "localise_scene.h"

#include <cmath>
#include <random>
#include <unordered_set>

#include "mrvs/core/hash.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::localise::test {
namespace {

/// Samples of the rectangle c + u a + v b, |u| <= 1, |v| <= 1.
void sample_face(const Eigen::Vector3d& c, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double spacing,
                 std::vector<Eigen::Vector3d>* out) {
  const int nu = std::max(1, static_cast<int>(std::ceil(2 * a.norm() / spacing)));
  const int nv = std::max(1, static_cast<int>(std::ceil(2 * b.norm() / spacing)));
  for (int i = 0; i <= nu; ++i) {
    for (int j = 0; j <= nv; ++j) out->push_back(c + (2.0 * i / nu - 1.0) * a + (2.0 * j / nv - 1.0) * b);
  }
}

void sample_box(const Box& box, double spacing, bool inside, std::vector<Eigen::Vector3d>* out) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      if (!inside && axis == 2 && side < 0) continue;  // a box's bottom is on the floor
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = side * box.half[axis];
      Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
      a[(axis + 1) % 3] = box.half[(axis + 1) % 3];
      b[(axis + 2) % 3] = box.half[(axis + 2) % 3];
      sample_face(box.centre + R * n, R * a, R * b, spacing, out);
    }
  }
}

}  // namespace

std::vector<Eigen::Vector3d> Scene::sample(double spacing) const {
  std::vector<Eigen::Vector3d> out;
  sample_box({0.5 * (room_min + room_max), 0.5 * (room_max - room_min), 0.0}, spacing, true, &out);
  for (const Box& b : boxes) sample_box(b, spacing, false, &out);
  return out;
}

Scene cluttered_room(int boxes, std::uint64_t seed) {
  Scene s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < boxes; ++i) {
    Box b;
    b.half = Eigen::Vector3d(0.2 + 0.4 * u(rng), 0.2 + 0.4 * u(rng), 0.2 + 0.6 * u(rng));
    b.centre = Eigen::Vector3d(1.0 + 6.0 * u(rng), 1.0 + 4.0 * u(rng), b.half.z());
    b.yaw = u(rng) < 0.3 ? (u(rng) - 0.5) : 0.0;
    s.boxes.push_back(b);
  }
  return s;
}

std::shared_ptr<map::VoxelMap> voxelise(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<double>& resolutions,
                                        const Eigen::Vector3d& origin) {
  auto m = std::make_shared<map::VoxelMap>();
  m->origin = origin;
  for (double r : resolutions) {
    map::MapLevel level;
    level.resolution = r;
    std::unordered_set<std::uint64_t> seen;
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3f local = (p - origin).cast<float>();
      const auto v = map::voxel_of(local, r);
      if (!v) continue;
      if (!seen.insert(voxel::pack(*v)).second) continue;
      level.points.push_back({local, 0.5f, 0.0f});
    }
    m->levels.push_back(std::move(level));
  }
  m->raw_point_count = points.size();
  return m;
}

localisation::Request submap_request(const std::vector<Eigen::Vector3d>& samples,
                                     const Eigen::Vector3d& viewpoint, double range, int max_points,
                                     double sigma, const SE3d& T_o_m, std::uint64_t seed) {
  std::vector<Eigen::Vector3d> near;
  for (const Eigen::Vector3d& p : samples) {
    if ((p - viewpoint).norm() <= range) near.push_back(p);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, sigma);
  localisation::Request q;
  q.seq = 1;
  q.anchor_o = T_o_m * viewpoint;
  const std::size_t step =
      std::max<std::size_t>(1, near.size() / static_cast<std::size_t>(std::max(max_points, 1)));
  for (std::size_t i = 0; i < near.size(); i += step) {
    const Eigen::Vector3d noisy = near[i] + Eigen::Vector3d(n(rng), n(rng), n(rng));
    q.points.push_back((T_o_m * noisy - q.anchor_o).cast<float>());
  }
  return q;
}

SE3d yaw_pose(double yaw, const Eigen::Vector3d& t) {
  return SE3d(Quatd(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())), t);
}

}  // namespace mrvs::localise::test
